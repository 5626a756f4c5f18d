"""The recording-to-results pipeline (stages 1-4 on one recording): :func:`process_recording`
takes a recording, the subject's measures and :class:`IKOptions`, and returns an :class:`IKRun`
(joint angles, landmarks, residuals, the calibration applied). The API, ``pipeline ik``, the demo
and the Wang reproduction all call it; it writes nothing.

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "apply_sensor_map": "sensors",
    "calibrate_knees": "functional",
    "check_sensor_to_model": "options",
    "IKOptions": "options",
    "IKRun": "run",
    "JOINT_SEGMENTS": "sensors",
    "KneeCalibration": "functional",
    "known_segments": "sensors",
    "MAX_SAMPLES": "functional",
    "mot_columns": "run",
    "MOT_NAMES": "run",
    "orientations_from_signals": "signals",
    "process_recording": "run",
    "RESIDUAL_BOUND_RAD_S": "functional",
    "SENSOR_ALIASES": "sensors",
    "sensor_set": "sensors",
    "SensorSet": "sensors",
    "SPLIT_HALF_DEG": "functional",
    "Z_UP_TO_Y_UP": "signals",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
