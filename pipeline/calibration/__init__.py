"""Calibration (stage 3): recordings and a model in, sensor-to-segment relations out. Takes:
segment or IMU orientations, gyroscope and accelerometer signals. Gives: the knee AoR (Wang eq
1-8) and its orientation correction (eq 9-13; IPOPT whole-trial version), joint-constraint
calibration of hinge and spherical joints (Hu eq 1-29: :func:`calibrate` with GN, DWPSO, GWO or
IPOPT), segment frames from it (eq 30-38), the subject's heading, IMU placements from a
calibration pose, and the PI attitude filter (eq 43-50).

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "anatomical_right": "heading",
    "angular_acceleration": "joint_constraints",
    "aor_correction_ipopt": "aor_ipopt",
    "AorCorrection": "aor_ipopt",
    "apply_correction": "aor",
    "AttitudeEstimate": "attitude",
    "axis_from_spherical": "joint_constraints",
    "calibrate": "calibrate",
    "calibrate_classic": "solvers",
    "calibrate_ipopt": "ipopt",
    "CalibrationResult": "solvers",
    "check_loss": "losses",
    "consistent_axis_signs": "joint_constraints",
    "correction_rotations": "aor",
    "DEFAULT_METHOD": "calibrate",
    "diagnose": "solvers",
    "dominant_axis": "heading",
    "dwpso": "solvers",
    "elevation_coordinate": "aor",
    "flexion_coordinate": "aor",
    "frame_pairs": "aor",
    "gamma": "joint_constraints",
    "gauss_newton": "solvers",
    "gwo": "solvers",
    "heading_rotation": "heading",
    "HEADINGS": "heading",
    "hinge_fit": "hinge_fit",
    "hinge_jacobian": "joint_constraints",
    "hinge_jacobian_spherical": "joint_constraints",
    "hinge_residual": "joint_constraints",
    "HingeFit": "hinge_fit",
    "imu_placements_from_calibration": "placement",
    "joint_data": "joint_constraints",
    "joint_rotation": "segment_frames",
    "JointData": "joint_constraints",
    "JOINTS": "calibrate",
    "knee_aor": "aor",
    "KneeAoR": "aor",
    "LOSSES": "losses",
    "mahony_filter": "attitude",
    "METHODS": "calibrate",
    "motion_weights": "hinge_fit",
    "observability": "joint_constraints",
    "parallel_frame": "segment_frames",
    "pelvis_axis_right": "heading",
    "PlacementEstimate": "placement",
    "placements_from_pose": "placement",
    "population_aor": "aor",
    "PopulationAoR": "aor",
    "project_hinge_positions": "joint_constraints",
    "projection_angles": "aor",
    "reexpress_tibia": "aor",
    "relative_rotations": "hinge_fit",
    "robust_loss": "losses",
    "sample_weights": "hinge_fit",
    "segment_orientation": "segment_frames",
    "select_windows": "aor",
    "shank_frame": "segment_frames",
    "solve_subproblem": "solvers",
    "spherical_from_axis": "joint_constraints",
    "spherical_jacobian": "joint_constraints",
    "spherical_residual": "joint_constraints",
    "subject_right": "heading",
    "Subproblem": "solvers",
    "subproblem": "solvers",
    "thigh_frame": "segment_frames",
    "tilt_error": "attitude",
    "UP": "heading",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
