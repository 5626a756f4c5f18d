"""Calibration (stage 3): recordings and a model in, sensor-to-segment relations out.

* Wang 2023: the knee AoR (eq 1-8, :func:`knee_aor`), its correction (eq 9-13,
  :func:`correction_rotations`; one leg as ``pipeline ik`` applies it, :func:`correct_knee`; the
  whole-trial IPOPT version, :func:`aor_correction_ipopt`).
* Hu 2021: joint-constraint calibration of hinge and spherical joints (eq 1-29,
  :func:`calibrate` with GN, DWPSO, GWO or IPOPT), segment frames from it (eq 30-38,
  :func:`thigh_frame`, :func:`shank_frame`), the PI attitude filter (eq 43-50) beside VQF
  (:func:`filter_orientations`).
* The subject's heading (:func:`subject_right`), IMU placements from a calibration pose
  (:func:`placements_from_pose`), the heading between two sensors from a joint
  (:func:`hinge_heading`, :func:`heading_between`).

The public names below load their module on first use (:mod:`pipeline._lazy`); the modules hold
the rest.
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "aor_correction_ipopt": "aor_ipopt",
    "AorCorrection": "aor_ipopt",
    "calibrate": "calibrate",
    "CALIBRATION_POSES": "conventions",
    "CALIBRATIONS": "conventions",
    "CalibrationResult": "solvers",
    "correct_knee": "correction",
    "correction_rotations": "aor",
    "CORRECTIONS": "conventions",
    "DEFAULT_CALIBRATION_POSE": "conventions",
    "DEFAULT_CORRECTION": "conventions",
    "DEFAULT_FILTER": "conventions",
    "DEFAULT_METHOD": "conventions",
    "DRIFT_CORRECTIONS": "conventions",
    "filter_orientations": "attitude",
    "FILTERS": "conventions",
    "heading_between": "heading_offset",
    "HeadingDrift": "heading_offset",
    "HEADINGS": "conventions",
    "hinge_heading": "heading_offset",
    "joint_data": "joint_constraints",
    "JointData": "joint_constraints",
    "JOINTS": "conventions",
    "knee_aor": "aor",
    "KneeAoR": "aor",
    "KneeCorrection": "correction",
    "METHODS": "conventions",
    "placements_from_pose": "placement",
    "population_aor": "aor",
    "pose_rotations": "placement",
    "shank_frame": "segment_frames",
    "subject_right": "heading",
    "thigh_frame": "segment_frames",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
