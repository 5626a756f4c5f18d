"""What ``pipeline batch`` writes beside the trials: ``batch_summary.csv`` (every row, its status
and figures) and ``batch_report.html`` (the group report: :func:`pipeline.report.page.
group_report_html`, one row of curves per trial, the parameters side by side), both read from each
trial's ``<name>_figures.json``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

__all__ = ["STRIDE_COLUMNS", "SUMMARY_COLUMNS", "trial_figures", "write_summary"]

#: The strides' means per trial (both sides, over the straight, steady strides; empty without).
STRIDE_COLUMNS = ("strides", "stride_time_s", "stride_length_m", "speed_m_s", "cadence_steps_min",
                  "stance_share")
SUMMARY_COLUMNS = ("row", "subject", "orientations", "status", "message", "frames",
                   "residual_median_deg", "flags", *STRIDE_COLUMNS, "seconds",
                   "out_dir")


def _read_figures(path: Path) -> dict | None:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None


def trial_figures(path: Path) -> dict[str, str]:
    """Frames, median residual, the number of flags and the strides' means, from a run's
    ``_figures.json`` (empty cells where it has none)."""
    fig = _read_figures(path)
    try:
        out = {"frames": str(fig["frames"]),
               "residual_median_deg": f"{fig['residual_median_deg']:.2f}",
               "flags": str(len(fig["flags"])), "strides": str(fig.get("strides", ""))}
        for c in STRIDE_COLUMNS[1:]:
            out[c] = "" if fig.get(c) is None else f"{fig[c]:.4g}"
        return out
    except (KeyError, TypeError):
        return dict.fromkeys(("frames", "residual_median_deg", "flags", *STRIDE_COLUMNS), "")


def write_summary(out: Path, ordered: list[dict], report: bool) -> None:
    """``batch_summary.csv`` (``ordered``: one result per row, :data:`SUMMARY_COLUMNS`) and, with
    ``report``, ``batch_report.html``, all or nothing; without matplotlib the report is left out
    with a warning naming the extra."""
    from pipeline.io.atomic import output_set
    from pipeline.io.formats import recording_name
    from pipeline.io.tables import csv_text

    report = report and _can_report()
    with output_set() as outs:
        with outs.open(out / "batch_summary.csv") as fh:
            fh.write(csv_text(ordered, SUMMARY_COLUMNS))
        if report:
            from pipeline.report.page import GroupTrial, group_report_html

            trials = []
            for r in ordered:
                found = sorted(Path(str(r["out_dir"])).glob("*_figures.json"))
                name = found[0].name.removesuffix("_figures.json") if found else \
                    recording_name(str(r["orientations"]))
                ok = r["status"] in ("ok", "skipped") and len(found) == 1
                trials.append(GroupTrial(str(r["subject"]), name,
                                         _read_figures(found[0]) if ok else None))
            with outs.open(out / "batch_report.html") as fh:
                fh.write(group_report_html(trials, title=out.name))


def _can_report() -> bool:
    import importlib.util

    if importlib.util.find_spec("matplotlib") is not None:
        return True
    print("warning: no batch_report.html: the report needs matplotlib, which the 'report' extra "
          "installs: pip install 'imu-skeleton-pipeline[report]'", file=sys.stderr)
    return False
