"""The one-page reports: ``<name>_report.html`` of a run and ``batch_report.html`` of a batch.

Self-contained HTML (the figures inline as PNG, the style inline, nothing fetched): what a gait
lab reads first. A run's page holds the joint angles over the gait cycle (:mod:`.plots`, from
:mod:`pipeline.analysis.cycles`), the spatiotemporal table with each parameter's left/right
symmetry index ``SI = 100 (R - L) / (0.5 (R + L))`` % (Robinson et al. 1987, J Manipulative
Physiol Ther 10(4):172-176; 0 is symmetric), the warnings and sensor checks in words, a still of
the skeleton at mid-stance and the run's notes. A batch's page holds one row of curves per trial
and the trials' parameters side by side, read from each trial's ``_figures.json``.
"""

from __future__ import annotations

import base64
import html
from dataclasses import dataclass

import numpy as np

from pipeline.analysis.cycles import STRAIGHT_ONLY, cycle_angles, cycles_figures
from pipeline.analysis.strides import left_out, stride_summary
from pipeline.calibration.heading import heading_rotation
from pipeline.process.run import IKRun
from pipeline.report import plots

__all__ = ["GroupTrial", "PARAMETERS", "ReportParts", "group_report_html", "render_report",
           "report_html", "report_parts", "symmetry_index", "write_report"]

#: The spatiotemporal table's rows: ``_strides.csv`` column -> (label, scale, digits).
PARAMETERS = {"stride_time_s": ("stride time (s)", 1.0, 2),
              "stance_share": ("stance share (of the stride)", 1.0, 3),
              "stride_length_m": ("stride length (m)", 1.0, 2),
              "speed_m_s": ("speed (m/s)", 1.0, 2),
              "cadence_steps_min": ("cadence (steps/min)", 1.0, 1),
              "clearance_m": ("foot clearance (cm)", 100.0, 1)}

_STYLE = """body{font-family:system-ui,sans-serif;max-width:1100px;margin:1.5em auto;color:#222}
h1{font-size:1.5em;margin-bottom:.2em}h2{font-size:1.15em;border-bottom:1px solid #ccc;
margin-top:1.4em}table{border-collapse:collapse;font-size:.9em}td,th{border:1px solid #ccc;
padding:.25em .6em;text-align:left}th{background:#f3f3f3}.warn{background:#fff4e5;
border-left:4px solid #e08000;padding:.5em 1em}.muted{color:#666;font-size:.9em}
img{max-width:100%}"""


def symmetry_index(right: float, left: float) -> float:
    """``100 (R - L) / (0.5 (R + L))`` % (module docstring); NaN without both sides."""
    if not (np.isfinite(right) and np.isfinite(left)) or right + left == 0:
        return np.nan
    return float(100.0 * (right - left) / (0.5 * (right + left)))


def _img(png: bytes, alt: str) -> str:
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,' \
           f'{base64.b64encode(png).decode("ascii")}">'


def _table(header: list[str], rows: list[list[object]]) -> str:
    head = "".join(f"<th>{html.escape(str(h))}</th>" for h in header)
    body = "".join("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in r) + "</tr>"
                   for r in rows)
    return f"<table><tr>{head}</tr>{body}</table>"


def _page(title: str, sections: list[str]) -> str:
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>'
            f"{html.escape(title)}</title><style>{_STYLE}</style></head><body>\n"
            + "\n".join(sections) + "\n</body></html>\n")


def _cell(mean: float, sd: float, n: int, scale: float, digits: int) -> str:
    if n == 0 or not np.isfinite(mean):
        return ""
    if n == 1 or not np.isfinite(sd):
        return f"{scale * mean:.{digits}f}"
    return f"{scale * mean:.{digits}f} ± {scale * sd:.{digits}f}"


def _stride_rows(run: IKRun) -> list[list[object]]:
    summary = stride_summary(run.gait.strides)
    rows = []
    for col, (label, scale, digits) in PARAMETERS.items():
        r, left = summary["right"][col], summary["left"][col]
        si = symmetry_index(r[0], left[0])
        rows.append([label, _cell(*r, scale, digits), _cell(*left, scale, digits),
                     "" if not np.isfinite(si) else f"{si:+.1f}",
                     _cell(*summary["both"][col], scale, digits)])
    counts = {side: summary[side]["stride_time_s"][2] for side in ("right", "left")}
    rows.append(["strides in the means", counts["right"], counts["left"], "", sum(counts.values())])
    return rows


def _fallback_words(means: dict) -> str:
    """Which side's curves are over its straight strides, for want of a steady one."""
    sides = [side for side, curves in means.items()
             if any(c.get("over") == STRAIGHT_ONLY for c in curves.values())]
    return "".join(f"; the {side} side has no steady stride: its curves are over its straight "
                   "strides, start, stop and those beside a turn included" for side in sides)


def _left_out_words(run: IKRun) -> str:
    out = left_out(run.gait.strides)
    total = len(run.gait.strides)
    return (f"{total} strides found; the means are over the straight, steady ones: left out "
            f"{out['turning']} turning, {out['starting or stopping']} starting or stopping a "
            f"straight walk, {out['merged']} longer than 1.5 times their side's median (a missed "
            "contact).")


def _still_points(run: IKRun) -> tuple[dict[str, np.ndarray], str]:
    """The landmarks at mid-stance (30 % of the first right stride in the means; the first
    sample without one), in the subject's heading at that instant (x anterior, y up, z to the
    right from the left hip centre to the right; the calibration pose's without both hips)."""
    from pipeline.analysis.strides import in_the_means

    chosen = [s for s in run.gait.strides if in_the_means(s)] or list(run.gait.strides)
    k, when = 0, "the first sample"
    if chosen:
        s = next((s for s in chosen if s.side == "right"), chosen[0])
        t = s.start_s + 0.3 * s.stride_time_s
        k = int(np.clip(np.searchsorted(run.time, t), 0, len(run.time) - 1))
        when = f"mid-stance of the {s.side} leg, t = {run.time[k]:.2f} s"
    right = run.heading_right
    hips = [run.landmarks.get(f"{side}_HJC") for side in ("right", "left")]
    if all(h is not None and np.all(np.isfinite(h[k])) for h in hips):
        across = hips[0][k] - hips[1][k]
        across[1] = 0.0
        right = across / max(np.linalg.norm(across), 1e-9)
    H = heading_rotation(right)
    points = {n: xyz[k] @ H for n, xyz in run.landmarks.items() if np.all(np.isfinite(xyz[k]))}
    return points, when


def _sensor_rows(run: IKRun) -> list[list[object]]:
    found: dict[str, list] = {}
    for f in run.sensor_findings:
        found.setdefault(f.sensor, []).append(f)
    rows = []
    for sensor, fs in sorted(found.items()):
        used = "no: excluded" if any(f.action == "excluded" for f in fs) else "yes"
        rows.append([sensor, "; ".join(f"{f.check}: {f.evidence} ({f.action})" for f in fs),
                     used])
    return rows


@dataclass(frozen=True)
class ReportParts:
    """What a run's page shows, computed from the run (no plotting: picklable, so that the
    figures can be drawn in another process, :func:`render_report`): the page's ``title``, its
    HTML before the curves (``head``), the cycles' ``means`` and each side's ``foot_off``
    (``None``: no strides), the HTML after the curves (``middle``), the skeleton's ``points`` at
    ``when``, and the HTML after it (``tail``)."""

    title: str
    head: list[str]
    means: dict | None
    foot_off: dict[str, float]
    middle: list[str]
    points: dict[str, np.ndarray]
    when: str
    tail: list[str]


def report_parts(run: IKRun, name: str) -> ReportParts:
    """The page of ``run`` (module docstring) but its figures."""
    m = run.measures
    summary = stride_summary(run.gait.strides)
    head = [f"<h1>Gait report: {html.escape(name)}</h1>",
            f'<p class="muted">subject: sex {m.sex}, height {m.height_m:.2f} m; '
            f"{run.time[-1] - run.time[0]:.1f} s, {len(run.time)} frames; joints: "
            f"{html.escape(', '.join(run.sensors.joints))}; calibration: "
            f"{html.escape(str(run.calibration))}</p>"]
    if run.flags:
        items = "".join(f"<li>{html.escape(f)}</li>" for f in run.flags)
        head.append(f'<div class="warn"><b>Warnings</b><ul>{items}</ul></div>')
    head.append("<h2>Joint angles over the gait cycle</h2>")
    means, middle = None, []
    if run.gait.strides:
        means = cycles_figures(cycle_angles(run.time, run.joint_angles, run.gait.strides))
        middle = ['<p class="muted">Mean ± SD over each side\'s straight, steady strides (right '
                  "green, left red; dashed: the mean foot-off" + _fallback_words(means) + "). "
                  + _left_out_words(run) + "</p>",
                  "<h2>Spatiotemporal parameters</h2>",
                  _table(["parameter", "right", "left", "symmetry index (%)", "both"],
                         _stride_rows(run)),
                  '<p class="muted">Symmetry index 100 (R - L) / (0.5 (R + L)): 0 is symmetric '
                  "(Robinson et al. 1987).</p>"]
    else:
        middle.append("<p>No strides: " + html.escape("; ".join(
            n for n in run.notes if n.startswith("no strides")) or "none found") + "</p>")
    points, when = _still_points(run)
    rows = _sensor_rows(run)
    tail = ["<h2>Sensor checks</h2>", _table(["sensor", "what the checks found", "used"], rows)
            if rows else "<p>Every sensor passed every check.</p>"]
    if run.notes:
        tail += ["<h2>Notes</h2><ul>" + "".join(f"<li>{html.escape(n)}</li>" for n in run.notes)
                 + "</ul>"]
    return ReportParts(f"Gait report: {name}", head, means,
                       {side: summary[side]["stance_share"][0] for side in ("right", "left")},
                       middle, points, when, tail)


def render_report(parts: ReportParts) -> str:
    """The page's HTML, its figures drawn (:mod:`pipeline.report.plots`)."""
    body = list(parts.head)
    if parts.means is not None:
        body.append(_img(plots.cycle_figure(parts.means, parts.foot_off),
                         "joint angles over the gait cycle"))
    body += parts.middle
    if parts.points:
        body += ["<h2>The skeleton</h2>",
                 _img(plots.skeleton_figure(parts.points, parts.when), parts.when)]
    return _page(parts.title, body + parts.tail)


def report_html(run: IKRun, name: str) -> str:
    """``<name>_report.html`` of a run (module docstring)."""
    return render_report(report_parts(run, name))


def write_report(path: str, parts: ReportParts) -> None:
    """The rendered page (:func:`render_report`) into the file ``path``."""
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(render_report(parts))


@dataclass(frozen=True)
class GroupTrial:
    """One trial of a batch: its subject, recording name and ``_figures.json`` (None when it
    has none: failed or not run)."""

    subject: str
    name: str
    figures: dict | None


#: The group table's columns from ``_figures.json``: key -> (label, digits).
GROUP_PARAMETERS = {"strides": ("strides", 0), "stride_time_s": ("stride time (s)", 2),
                    "stride_length_m": ("stride length (m)", 2), "speed_m_s": ("speed (m/s)", 2),
                    "cadence_steps_min": ("cadence (steps/min)", 1),
                    "stance_share": ("stance share", 3)}


def group_report_html(trials: list[GroupTrial], title: str = "batch") -> str:
    """``batch_report.html``: one row of curves per trial with figures, the parameters (both
    sides' means over the straight, steady strides) side by side."""
    rows = []
    for t in trials:
        fig = t.figures or {}
        cells = [t.subject, t.name]
        for key, (_, digits) in GROUP_PARAMETERS.items():
            v = fig.get(key)
            cells.append("" if v is None else f"{v:.{digits}f}")
        cells.append("no figures (failed or not run)" if t.figures is None
                     else str(len(fig.get("flags", []))))
        rows.append(cells)
    header = ["subject", "recording", *(lbl for lbl, _ in GROUP_PARAMETERS.values()), "flags"]
    with_curves = [(f"{t.subject} / {t.name}", t.figures["cycles"]) for t in trials
                   if t.figures and any(t.figures.get("cycles", {}).values())]
    sections = [f"<h1>Group report: {html.escape(title)}</h1>",
                f'<p class="muted">{len(trials)} trials; means over each trial\'s straight, '
                "steady strides (both sides).</p>", "<h2>Parameters</h2>",
                _table(header, rows)]
    if with_curves:
        sections += ["<h2>Sagittal joint angles over the gait cycle, one row per trial</h2>",
                     _img(plots.group_figure(with_curves), "curves per trial"),
                     '<p class="muted">Right green, left red: mean ± SD.</p>']
    return _page(f"Group report: {title}", sections)
