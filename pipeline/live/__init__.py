"""Live capture (the recording-to-results pipeline frame by frame): streams in (Lab Streaming
Layer, or a recording replayed as if live), put on one time base, each sensor's orientation
updated sample by sample, calibrated by the offline pipeline on what has been captured, each
frame's IK warm-started from the last, shown in rerun as it comes; ``pipeline live``
(:mod:`pipeline.commands.live`) writes the capture and its offline outputs at the end.

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "Aligner": "aligner",
    "CalibrationUsed": "capture",
    "CaptureResult": "capture",
    "Chunk": "sources",
    "LiveCalibration": "calibration",
    "LiveCapture": "capture",
    "LiveOptions": "options",
    "LiveOrientations": "orientation",
    "LiveViewer": "viewer",
    "LslSource": "sources",
    "ReplaySource": "sources",
    "Tracker": "tracker",
    "calibrate_capture": "calibration",
    "layout_of": "channels",
    "serve_outlets": "sources",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
