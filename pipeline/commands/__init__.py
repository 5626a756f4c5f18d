"""One module per CLI command, shared by the CLI (:mod:`pipeline.cli`) and the Python API: each
``run_<command>`` reads the inputs, calls the domain code and writes the outputs all or nothing.

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "CALIBRATION_KEYS": "calibrate",
    "demo": "demo",
    "DemoResult": "demo",
    "load_orientations": "ik",
    "MAX_DURATION_S": "simulate",
    "MIN_MOTION_RAD_S": "calibrate",
    "option_columns": "batch",
    "PAPERS": "reproduce",
    "read_manifest": "batch",
    "recording_name": "ik",
    "REQUIRED_COLUMNS": "batch",
    "run_settings": "ik",
    "figures_json": "ik",
    "run_batch": "batch",
    "run_calibration": "calibrate",
    "run_demo": "demo",
    "run_ik": "ik",
    "run_orientations": "orientations",
    "run_reproduce": "reproduce",
    "run_row": "batch",
    "run_scale": "scale",
    "run_simulation": "simulate",
    "run_view": "view",
    "SUBJECT": "demo",
    "SUMMARY_COLUMNS": "batch",
    "summary_text": "ik",
    "write_landmarks_csv": "ik",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
