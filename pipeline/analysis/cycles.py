"""Joint angles over the gait cycle: each stride's curves at 0-100 % of its time.

A stride (:mod:`pipeline.analysis.strides`) runs from an initial contact (0 %) to the next of the
same foot (100 %). Its angles are sampled at :data:`CYCLE_POINTS` equally spaced instants of that
span by linear interpolation of the run's samples (time normalisation, as every clinical gait
report plots kinematics; e.g. Winter 2009, *Biomechanics and Motor Control of Human Movement*,
ch. 1): ``a_k(p) = a(t_0 + p (t_1 - t_0) / 100)``, ``p = 0, 1, ..., 100``. A stride over which a
joint has a missing sample gets no curve for that joint (NaN), never a bridged one.

The curves of a right stride are the right leg's joints, of a left stride the left leg's; the
pelvis's angles (``pelvis_tilt``, ``_list``, ``_rotation``: the pelvis in the room, one sign for
both sides, as in the ``.mot``) are given for every stride, its rotation about its mean over
the stride (the direction of progression: the ``.mot``'s ``pelvis_rotation`` is the heading in
the room). The means (:func:`cycle_means`) are
per side over the strides that count in the stride parameters' means
(:func:`pipeline.analysis.strides.in_the_means`: straight and steady), with their SD across
strides at each point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.analysis.strides import MERGED_SHARE, Stride, in_the_means

__all__ = ["CYCLE_COLUMNS", "CYCLE_POINTS", "STEADY", "STRAIGHT_ONLY", "Cycles", "CycleMean",
           "averaged", "cycle_angles", "cycle_means", "cycle_table", "cycles_csv", "cycles_figures"]

#: Points per cycle: 0, 1, ..., 100 % of the stride.
CYCLE_POINTS = 101

#: Our joint-angle names (without the side) -> the ``.mot`` coordinate names (without ``_r``/``_l``)
#: the cycles are listed under, in the order of ``<name>_cycles.csv``.
CYCLE_COLUMNS = {"pelvis_tilt": "pelvis_tilt", "pelvis_list": "pelvis_list",
                 "pelvis_rotation": "pelvis_rotation", "hip_flexion": "hip_flexion",
                 "hip_adduction": "hip_adduction", "hip_rotation": "hip_rotation",
                 "knee_flexion": "knee_angle", "knee_adduction": "knee_adduction",
                 "knee_rotation": "knee_rotation", "ankle_flexion": "ankle_angle",
                 "ankle_inversion": "subtalar_angle"}


@dataclass(frozen=True)
class Cycles:
    """``strides`` in the order of ``<name>_strides.csv``; ``angles``: column (``.mot`` name
    without the side) -> (n_strides, :data:`CYCLE_POINTS`) rad, NaN where the stride's leg does
    not have that joint or a sample is missing."""

    strides: list[Stride]
    angles: dict[str, np.ndarray]


#: What a side's means are over: its straight, steady strides...
STEADY = "straight, steady"
#: ... or, where it has none (a short walk, turns on the spot), its straight strides, said so.
STRAIGHT_ONLY = "straight, none steady"


@dataclass(frozen=True)
class CycleMean:
    """One joint's mean curve of one side, its SD across strides (rad, :data:`CYCLE_POINTS`
    each), the strides it is over (``n``) and which (``over``: :data:`STEADY`, or
    :data:`STRAIGHT_ONLY` where the side has no steady stride)."""

    mean: np.ndarray
    sd: np.ndarray
    n: int
    over: str = STEADY


def averaged(strides: list[Stride], side: str) -> tuple[np.ndarray, str]:
    """Which of ``strides`` a side's means are over (a mask) and what they are: its straight,
    steady strides, else its straight ones (start, stop and beside a turn included: a walk too
    short for a steady state still shows its curves, named as such)."""
    mine = np.array([s.side == side for s in strides], bool)
    steady = mine & np.array([in_the_means(s) for s in strides], bool)
    if steady.any() or not mine.any():
        return steady, STEADY
    typical = float(np.median([s.stride_time_s for s, m in zip(strides, mine, strict=True) if m]))
    straight = mine & np.array([s.straight and s.stride_time_s <= MERGED_SHARE * typical
                                for s in strides], bool)
    return straight, STRAIGHT_ONLY


def _angle_key(ours: str, side: str) -> str:
    return ours if ours.startswith("pelvis_") else f"{side}_{ours}"


def _curve(time: np.ndarray, angle: np.ndarray, stride: Stride) -> np.ndarray:
    """The angle at :data:`CYCLE_POINTS` instants of the stride; NaN if a sample it spans is."""
    a, b = np.searchsorted(time, [stride.start_s, stride.end_s])
    span = angle[max(a - 1, 0):min(b + 1, len(angle))]
    if not np.all(np.isfinite(span)):
        return np.full(CYCLE_POINTS, np.nan)
    at = np.linspace(stride.start_s, stride.end_s, CYCLE_POINTS)
    return np.interp(at, time, angle)


def cycle_angles(time: np.ndarray, joint_angles: dict[str, np.ndarray],
                 strides: list[Stride]) -> Cycles:
    """Every stride's angles over its cycle (module docstring); columns a run has for neither
    leg are left out."""
    angles = {}
    for ours, column in CYCLE_COLUMNS.items():
        keys = [_angle_key(ours, s.side) for s in strides]
        if not any(k in joint_angles for k in keys):
            continue
        rows = [_curve(time, joint_angles[k], s) if k in joint_angles
                else np.full(CYCLE_POINTS, np.nan) for k, s in zip(keys, strides, strict=True)]
        curves = np.array(rows).reshape(len(strides), CYCLE_POINTS)
        if ours == "pelvis_rotation":  # about the direction of progression
            curves = curves - np.mean(curves, axis=1, keepdims=True)
        angles[column] = curves
    return Cycles(list(strides), angles)


def cycle_means(cycles: Cycles) -> dict[str, dict[str, CycleMean]]:
    """``{side: {column: CycleMean}}`` over the side's straight, steady strides with a curve,
    else its straight ones (:func:`averaged`; sample SD; NaN with fewer than two)."""
    out: dict[str, dict[str, CycleMean]] = {}
    for side in ("right", "left"):
        chosen, over = averaged(cycles.strides, side)
        out[side] = {}
        for column, curves in cycles.angles.items():
            c = curves[chosen] if len(chosen) else curves
            c = c[np.all(np.isfinite(c), axis=1)]
            if not len(c):
                continue
            sd = np.std(c, axis=0, ddof=1) if len(c) > 1 else np.full(CYCLE_POINTS, np.nan)
            out[side][column] = CycleMean(np.mean(c, axis=0), sd, len(c), over)
    return out


def cycles_csv(cycles: Cycles) -> str:
    """``<name>_cycles.csv``: one row per stride and cycle point: ``stride`` (its row in
    ``<name>_strides.csv``, from 1), ``side``, ``straight``, ``steady``, ``in_means``,
    ``cycle_percent`` (0-100), then the angles in degrees (the ``.mot``'s names without the side;
    an empty cell where the stride has no curve)."""
    import io

    columns = ["stride", "side", "straight", "steady", "in_means", "cycle_percent",
               *cycles.angles]
    buf = io.StringIO()
    buf.write(",".join(columns) + "\n")
    percent = np.arange(CYCLE_POINTS)
    for k, s in enumerate(cycles.strides):
        head = f"{k + 1},{s.side},{_bool(s.straight)},{_bool(s.steady)},{_bool(in_the_means(s))}"
        values = np.column_stack([np.degrees(a[k]) for a in cycles.angles.values()]) \
            if cycles.angles else np.zeros((CYCLE_POINTS, 0))
        for p, row in zip(percent, values, strict=True):
            cells = ",".join("" if not np.isfinite(v) else f"{v:.6g}" for v in row)
            buf.write(f"{head},{p},{cells}\n" if cells else f"{head},{p}\n")
    return buf.getvalue()


def _bool(v: bool) -> str:
    return "true" if v else "false"


def cycles_figures(cycles: Cycles) -> dict[str, dict[str, dict]]:
    """The means as ``_figures.json`` lists them: ``{side: {column: {'n', 'over', 'mean_deg',
    'sd_deg'}}}``, :data:`CYCLE_POINTS` values each (2 decimals; ``null`` for an SD of one)."""
    def listed(v: np.ndarray) -> list:
        return [None if not np.isfinite(x) else round(float(x), 2) for x in np.degrees(v)]

    return {side: {col: {"n": m.n, "over": m.over, "mean_deg": listed(m.mean),
                         "sd_deg": listed(m.sd)} for col, m in means.items()}
            for side, means in cycle_means(cycles).items()}


def cycle_table(cycles: Cycles) -> list[str]:
    """The summary's Markdown lines: each joint's maximum, minimum and range over the cycle, mean
    ± SD across the side's straight, steady strides (deg)."""
    means = cycle_means(cycles)
    counts = {side: max((m.n for m in means[side].values()), default=0) for side in means}
    chosen_by = {side: averaged(cycles.strides, side) for side in ("right", "left")}
    lines = ["| angle over the cycle (deg) | right max | right min | right range | left max | "
             "left min | left range |", "|---|---|---|---|---|---|---|"]
    for column, curves in cycles.angles.items():
        cells = []
        for side in ("right", "left"):
            mask = chosen_by[side][0]
            chosen = [k for k in np.flatnonzero(mask) if np.all(np.isfinite(curves[k]))]
            c = np.degrees(curves[chosen]) if chosen else np.zeros((0, CYCLE_POINTS))
            for v in (c.max(axis=1), c.min(axis=1), np.ptp(c, axis=1)) if len(c) else ((),) * 3:
                cells.append(_mean_sd(np.asarray(v)))
        lines.append(f"| {column} | " + " | ".join(cells) + " |")
    lines.append(f"| strides in the means | {counts['right']} | | | {counts['left']} | | |")
    for side in ("right", "left"):
        if chosen_by[side][1] == STRAIGHT_ONLY:
            lines.append(f"| the {side} side's means are over its straight strides: it has no "
                         "steady one | | | | | | |")
    return lines


def _mean_sd(v: np.ndarray) -> str:
    if not len(v):
        return ""
    return f"{v.mean():.1f}" if len(v) == 1 else f"{v.mean():.1f} ± {v.std(ddof=1):.1f}"
