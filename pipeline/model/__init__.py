"""The subject model (stage 2): anthropometry in, a Pinocchio model out. Takes: sex, height and
optional measures (:class:`Measures`). Gives: the Wang 2023 Table I landmark positions (eq 14),
a scaled ISB lower-limb URDF (text, built in memory; files only as outputs) with landmark,
joint-centre and IMU frames, its :class:`Skeleton` (``pin.Model`` + ``pin.Data`` + names) and the
CasADi expression graph of its kinematics for the NLPs.

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "AXES": "anthropometry",
    "axis_rotation_sym": "casadi_kinematics",
    "build_urdf": "builder",
    "CasadiKinematics": "casadi_kinematics",
    "check_length_m": "anthropometry",
    "CSV_COLUMNS": "anthropometry",
    "default_imu_placements": "builder",
    "DEFAULT_KNEE": "conventions",
    "EQUATION_INPUTS": "anthropometry",
    "EQUATION_TARGETS": "anthropometry",
    "example_robot_data_share": "resources",
    "exp3_sym": "casadi_kinematics",
    "FEMUR_LANDMARKS": "anthropometry",
    "frame_ids": "skeleton",
    "geometry_from_measures": "scaling",
    "GROUPS": "anthropometry",
    "human_urdf": "resources",
    "imu_frame_names": "builder",
    "joint_names": "builder",
    "knee_axis": "skeleton",
    "KNEE_MODES": "conventions",
    "landmark_frame_names": "builder",
    "LANDMARK_SEGMENT": "conventions",
    "LandmarkPositions": "anthropometry",
    "LANDMARKS": "conventions",
    "leg_visuals": "meshes",
    "load_table1": "anthropometry",
    "materials": "meshes",
    "matrix_from_quat_xyzw_sym": "casadi_kinematics",
    "Measures": "anthropometry",
    "mirror_axis": "geometry",
    "mirror_point": "geometry",
    "models_file": "resources",
    "normalize_sex": "anthropometry",
    "pelvis_visuals": "meshes",
    "PLAUSIBLE_M": "anthropometry",
    "population_knee_axis": "scaling",
    "PopulationKneeAxis": "scaling",
    "predict_landmarks": "anthropometry",
    "RegressionEquation": "anthropometry",
    "RegressionTable": "anthropometry",
    "resolve_package_uri": "meshes",
    "ROOTS": "skeleton",
    "scale_model": "scaling",
    "segment_frame_names": "builder",
    "SEGMENTS": "conventions",
    "select_equation": "anthropometry",
    "Skeleton": "skeleton",
    "skew_sym": "casadi_kinematics",
    "SubjectGeometry": "geometry",
    "TEMPLATE_HEIGHT_M": "geometry",
    "TEMPLATE_HIP_OFFSET": "geometry",
    "TIBIA_LANDMARKS": "anthropometry",
    "urdf_text": "builder",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
