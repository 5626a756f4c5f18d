"""Formats (stage 1 of the data flow): users' files in, typed arrays in SI units out, and the
writers of every output. Takes: OpenSim ``.sto``/``.mot``, IMU CSV, Xsens MT ``.txt``, C3D.
Gives: one :class:`Recording` type (named sensors' orientations and raw signals on one time
base) whose readers checked
time stamps, rates, units and quaternions and filled short gaps (noted); the one CSV writer
(:mod:`pipeline.io.tables`), atomic all-or-nothing output sets (:mod:`pipeline.io.atomic`).

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "ACC_COLUMNS": "imu_csv",
    "align_clocks": "imu_folder",
    "atomic_write": "atomic",
    "C3dMarkers": "c3d",
    "check_acc_units": "checks",
    "check_gyro_units": "checks",
    "check_position_units": "checks",
    "check_quaternions": "checks",
    "check_rate": "checks",
    "check_same_length": "checks",
    "check_same_rate": "checks",
    "check_time": "checks",
    "Config": "config",
    "config_text": "config",
    "csv_text": "tables",
    "declared_rate": "sto_header",
    "DEFAULT_MAX_GAP_S": "gaps",
    "DOT_COLUMNS": "vendor_imu",
    "estimate_rate": "checks",
    "FileLike": "text",
    "fill_gaps": "gaps",
    "G": "vendor_imu",
    "GYR_COLUMNS": "imu_csv",
    "IK_KEYS": "config",
    "jsonable": "jsonio",
    "labels_and_rows": "sto_header",
    "MAG_COLUMNS": "imu_csv",
    "make_quaternions_continuous": "checks",
    "map_sensors": "opensim",
    "markdown_table": "tables",
    "mean_sd": "tables",
    "MODEL_FRAME_NAMES": "imu_folder",
    "MotTable": "mot",
    "Notes": "notes",
    "output_dir": "atomic",
    "output_set": "atomic",
    "OutputSet": "atomic",
    "parse_table": "text",
    "PLAUSIBLE_RATE_HZ": "checks",
    "QUAT_COLUMNS": "imu_csv",
    "RateInfo": "checks",
    "read_c3d": "c3d",
    "read_config": "config",
    "read_imu_csv": "imu_csv",
    "read_imu_folder": "imu_folder",
    "read_mot": "mot",
    "read_movella_dot_csv": "vendor_imu",
    "read_orientations_sto": "opensim",
    "read_text_lines": "text",
    "read_ximu3_folder": "vendor_imu",
    "read_xsens_trial": "xsens",
    "read_xsens_txt": "xsens",
    "Recording": "recording",
    "rotate_world": "opensim",
    "sensor_to_opensim_matrix": "opensim",
    "SENSOR_TO_SEGMENT": "opensim",
    "SensorSignals": "recording",
    "split_header": "sto_header",
    "SUBJECT_KEYS": "config",
    "UNIT_TO_METRES": "c3d",
    "where": "text",
    "write_array_csv": "tables",
    "write_bytes_atomic": "atomic",
    "write_imu_csv": "imu_csv",
    "write_mot": "mot",
    "write_orientations_sto": "opensim",
    "write_text_atomic": "atomic",
    "XIMU3_LABELS": "imu_folder",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
