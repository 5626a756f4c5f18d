"""Reports a gait lab reads (after the outputs): ``<name>_report.html`` of a run, with the joint
angles over the gait cycle, the spatiotemporal table with its symmetry, the sensor checks in
words and a still of the skeleton, and ``batch_report.html`` of a batch; figures by matplotlib
(the ``report`` extra), the page self-contained.

The public names below load their module on first use (:mod:`pipeline._lazy`).
"""

from pipeline._lazy import lazy_exports

_EXPORTS = {
    "GroupTrial": "page",
    "cycle_figure": "plots",
    "group_figure": "plots",
    "group_report_html": "page",
    "report_html": "page",
    "skeleton_figure": "plots",
    "symmetry_index": "page",
}
__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
