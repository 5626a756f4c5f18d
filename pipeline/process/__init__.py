"""The recording-to-results pipeline (stages 1-4 on one recording): :func:`process_recording`
takes a recording, the subject's measures and :class:`IKOptions`, and returns an :class:`IKRun`
(joint angles, landmarks, residuals, the calibration applied). The API, ``pipeline ik``, the demo
and the Wang reproduction all call it; it writes nothing. :mod:`pipeline.process.options` defines
every option of ``pipeline ik`` once.

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "calibrate_knees": "functional",
    "CORRECTIONS": "knee_correction",
    "IKOptions": "options",
    "IKRun": "run",
    "IKSettings": "options",
    "InputOptions": "options",
    "KneeCalibration": "functional",
    "mot_columns": "run",
    "MOT_NAMES": "run",
    "orientations_from_signals": "signals",
    "OutputOptions": "options",
    "process_recording": "run",
    "resolve_settings": "options",
    "sensor_set": "sensors",
    "SensorSet": "sensors",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
