"""The report's figures, drawn with matplotlib (the ``report`` extra) into PNG bytes.

Every figure takes the cycles' means as ``_figures.json`` lists them
(:func:`pipeline.analysis.cycles.cycles_figures`: ``{side: {column: {'n', 'over', 'mean_deg',
'sd_deg'}}}``), so a trial's report and a group's are drawn from the same numbers. Colours follow
the gait labs' convention (Vicon's and most clinical reports): right green, left red; a side's
mean is a line, its SD across strides a band, its mean foot-off a dashed vertical line.
"""

from __future__ import annotations

import io

import numpy as np

from pipeline.analysis.cycles import STRAIGHT_ONLY
from pipeline.optional import need

__all__ = ["COLOURS", "PANELS", "cycle_figure", "group_figure", "png_bytes", "skeleton_figure",
           "warm_plots"]

#: Right green, left red (module docstring).
COLOURS = {"right": "#1a9641", "left": "#d7191c"}

#: The kinematics panels: rows of (column, title with the positive direction) in the sagittal,
#: frontal and transverse planes (None: not measured); signs as in the ``.mot``
#: (:mod:`pipeline.analysis.joint_angles`).
PANELS = {
    "pelvis": (("pelvis_tilt", "pelvis tilt (+ posterior)"),
               ("pelvis_list", "pelvis list (+ right side down)"),
               ("pelvis_rotation", "pelvis rotation (+ to the left)")),
    "hip": (("hip_flexion", "hip flexion (+) / extension"),
            ("hip_adduction", "hip adduction (+) / abduction"),
            ("hip_rotation", "hip internal (+) / external rotation")),
    "knee": (("knee_angle", "knee flexion (+) / extension"),
             ("knee_adduction", "knee adduction (+) / abduction"),
             ("knee_rotation", "knee internal (+) / external rotation")),
    "ankle": (("ankle_angle", "ankle dorsiflexion (+) / plantarflexion"),
              ("subtalar_angle", "ankle inversion (+) / eversion"),
              (None, "ankle rotation: not in the model")),
}


def _pyplot():
    need("matplotlib", "the report")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def warm_plots() -> None:
    """matplotlib's import and first figure, where it is installed (in the forked child that
    writes the outputs, :mod:`pipeline.viz.background`, while the parent works)."""
    import importlib.util

    if importlib.util.find_spec("matplotlib") is not None:
        png_bytes(_pyplot().figure(figsize=(1, 1)))


def png_bytes(fig) -> bytes:
    """The figure as PNG bytes (closed afterwards)."""
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    _pyplot().close(fig)
    return buf.getvalue()


def _band(ax, curve: dict, colour: str, label: str) -> None:
    x = np.arange(len(curve["mean_deg"]))
    mean = np.array([np.nan if v is None else v for v in curve["mean_deg"]], float)
    sd = np.array([np.nan if v is None else v for v in curve["sd_deg"]], float)
    ax.plot(x, mean, color=colour, lw=1.6, label=label)
    if np.any(np.isfinite(sd)):
        ax.fill_between(x, mean - sd, mean + sd, color=colour, alpha=0.2, lw=0)


def _panel(ax, means: dict, column: str | None, title: str, foot_off: dict) -> None:
    ax.set_title(title, fontsize=8)
    ax.tick_params(labelsize=7)
    ax.set_xlim(0, 100)
    ax.axhline(0.0, color="0.6", lw=0.5)
    drawn = False
    for side in ("right", "left"):
        curve = means.get(side, {}).get(column) if column else None
        if curve is None:
            continue
        over = f" {STRAIGHT_ONLY}" if curve.get("over") == STRAIGHT_ONLY else ""
        _band(ax, curve, COLOURS[side], f"{side} (n={curve['n']}{over})")
        if np.isfinite(foot_off.get(side, np.nan)):
            ax.axvline(100 * foot_off[side], color=COLOURS[side], lw=0.8, ls="--")
        drawn = True
    if not drawn:
        ax.text(50, 0.5, "not measured", ha="center", va="center", fontsize=8, color="0.5",
                transform=ax.get_xaxis_transform())
        ax.set_yticks([])


def cycle_figure(means: dict, foot_off: dict[str, float]) -> bytes:
    """Pelvis, hip, knee and ankle in three planes over the cycle (0-100 %, deg), left and right
    mean ± SD; ``foot_off``: side -> mean stance share (the dashed line)."""
    plt = _pyplot()
    fig, axes = plt.subplots(len(PANELS), 3, figsize=(10.5, 2.3 * len(PANELS)), sharex=True)
    for row, panels in zip(axes, PANELS.values(), strict=True):
        for ax, (column, title) in zip(row, panels, strict=True):
            _panel(ax, means, column, title, foot_off)
        row[0].set_ylabel("deg", fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("gait cycle (%)", fontsize=8)
    handles, labels = axes[2][0].get_legend_handles_labels()
    if handles:
        fig.legend(handles, labels, loc="upper right", fontsize=8, ncol=2)
    fig.subplots_adjust(left=0.06, right=0.99, bottom=0.05, top=0.95, wspace=0.22, hspace=0.3)
    return png_bytes(fig)


#: The lines of the skeleton's still: landmark pairs (without the side), and across the pelvis.
BONES = (("HJC", "KJC"), ("KJC", "AJC"), ("AJC", "HEE"), ("HEE", "MT5"), ("MT5", "TOE"),
         ("TOE", "MT1"), ("MT1", "HEE"), ("EFM", "EFL"), ("MM", "LM"))


def skeleton_figure(points: dict[str, np.ndarray], title: str) -> bytes:
    """The skeleton at one instant from the side (x anterior to the right) and from the front
    (the subject's right on the left of the picture, as facing them): ``points`` landmark name
    -> (3,) m in the heading frame of the calibration pose (x anterior, y up, z right)."""
    plt = _pyplot()
    fig, (side_ax, front_ax) = plt.subplots(1, 2, figsize=(7.0, 5.0))
    for ax, horizontal, name in ((side_ax, 0, "from the right"), (front_ax, 2, "from the front")):
        sign = -1.0 if horizontal == 2 else 1.0
        for leg in ("right", "left"):
            for a, b in BONES:
                pa, pb = points.get(f"{leg}_{a}"), points.get(f"{leg}_{b}")
                if pa is None or pb is None:
                    continue
                ax.plot([sign * pa[horizontal], sign * pb[horizontal]], [pa[1], pb[1]],
                        color=COLOURS[leg], lw=2)
        hips = [points.get(f"{leg}_HJC") for leg in ("right", "left")]
        if all(h is not None for h in hips):
            ax.plot([sign * h[horizontal] for h in hips], [h[1] for h in hips], color="0.3", lw=3)
        ax.set_aspect("equal")
        ax.set_title(name, fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_xlabel("m", fontsize=8)
    fig.suptitle(title, fontsize=9)
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.1, top=0.88, wspace=0.35)
    return png_bytes(fig)


#: The group report's curves: the sagittal plane of hip, knee and ankle.
GROUP_COLUMNS = (("hip_flexion", "hip flexion"), ("knee_angle", "knee flexion"),
                 ("ankle_angle", "ankle dorsiflexion"))


def group_figure(trials: list[tuple[str, dict]]) -> bytes:
    """One row of curves per trial (``(name, cycles means)``): hip, knee and ankle flexion over
    the cycle, left and right mean ± SD, on common axes."""
    plt = _pyplot()
    rows = max(len(trials), 1)
    fig, axes = plt.subplots(rows, 3, figsize=(9.0, 1.9 * rows + 0.4), sharex=True,
                             sharey="col", squeeze=False)
    for row, (name, means) in zip(axes, trials, strict=False):
        for ax, (column, title) in zip(row, GROUP_COLUMNS, strict=True):
            _panel(ax, means, column, title, {})
        row[0].set_ylabel(name, fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("gait cycle (%)", fontsize=8)
    fig.subplots_adjust(left=0.12, right=0.98, bottom=0.4 / (1.9 * rows + 0.4) + 0.05,
                        top=0.97, wspace=0.25, hspace=0.25)
    return png_bytes(fig)
