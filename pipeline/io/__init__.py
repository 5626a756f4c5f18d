"""Formats (stage 1 of the data flow): users' files in, typed arrays in SI units out, and the
writers of every output. :func:`read_recording` recognises every recording format once (OpenSim
``.sto``, Xsens MT ``.txt``, Movella DOT ``.csv``, x-IMU3 device folders, our IMU CSV, a folder of
them) and gives one :class:`Recording` type (named sensors' orientations and raw signals on one
time base, our sensor names) whose readers checked time stamps, rates, units and quaternions and
filled short gaps (noted). Also: ``.mot`` tables, C3D markers, the configuration file, the one CSV
writer (:mod:`pipeline.io.tables`) and all-or-nothing output sets (:mod:`pipeline.io.atomic`).

The public names below load their module on first use (:mod:`pipeline._lazy`); the modules hold
the rest.
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "align_clocks": "clocks",
    "apply_sensor_map": "formats",
    "atomic_write": "atomic",
    "C3dMarkers": "c3d",
    "config_text": "config",
    "csv_text": "tables",
    "Format": "formats",
    "FORMATS": "formats",
    "markdown_table": "tables",
    "MotTable": "mot",
    "our_name": "sensor_names",
    "output_dir": "atomic",
    "output_set": "atomic",
    "read_c3d": "c3d",
    "read_config": "config",
    "read_imu_csv": "imu_csv",
    "read_mot": "mot",
    "read_movella_dot_csv": "vendor_imu",
    "read_orientations_sto": "opensim",
    "read_recording": "formats",
    "read_ximu3_folder": "vendor_imu",
    "read_xsens_txt": "xsens",
    "recognise": "formats",
    "Recording": "recording",
    "rotate_world": "opensim",
    "SENSOR_TO_SEGMENT": "sensor_names",
    "sensor_to_opensim_matrix": "opensim",
    "SensorSignals": "recording",
    "write_array_csv": "tables",
    "write_imu_csv": "imu_csv",
    "write_mot": "mot",
    "write_orientations_sto": "opensim",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
