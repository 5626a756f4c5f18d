"""The rerun viewer (outputs): trials and model motions written to ``.rrd`` recordings (columns
over a timeline, a default layout) by rerun's native writer (:mod:`pipeline.viz.rrd`), read
back, and opened in the native or web viewer.

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "default_blueprint": "layout",
    "default_layout": "layout",
    "RrdWriter": "rrd",
    "SceneOptions": "model",
    "entity_row_counts": "recording",
    "log_motion": "model",
    "log_trial": "recording",
    "read_entities": "recording",
    "segment_meshes": "model",
    "view": "viewer",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
