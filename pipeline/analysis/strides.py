"""Stride parameters of one foot from its events and its path.

A stride runs from an initial contact (IC) to the next IC of the same foot
(:mod:`pipeline.analysis.gait_events`). Its **time** is their interval; its **stance share** the
part before the foot's final contact (FC) within it; **cadence** ``120 / stride time`` steps per
minute (two steps per stride). From the foot's path (:mod:`pipeline.analysis.foot_trajectory`):
its **length** is the horizontal distance between the foot's rests that follow the two ICs (the
mid-stances: where the integration is exact), **speed** length over time, **clearance** the sensor's
highest lift above its first rest during the swing, **turn** the change of the foot's heading
between the two rests (deg, positive to the left: counter-clockwise seen from above); a stride is
``straight`` when ``|turn|`` is below :data:`STRAIGHT_TURN_DEG`. A pair of ICs more than
:data:`MAX_STRIDE_S` apart (the subject stopped) is no stride. Without a path (events from a
shank sensor) length, speed, clearance and turn are NaN.

A stride is ``steady`` when it is neither the first nor the last of its straight walk (a run of
strides, each starting where the one before ended, none of them turning: the first starts the
walk from standing or out of a turn, the last stops it or leads into a turn; S02's last step is
0.34 m where its walk's strides are 1.31-1.45 m, and the x-IMU3 walk's step before a turn on the
spot 0.11 m where its straight strides are 0.97-1.10 m) and lasts no longer than
:data:`MERGED_SHARE` times its side's median stride (longer, a contact was missed and two strides
merged): the steady state of clinical gait analysis, which leaves out each straight walk's first
and last strides (gait initiation and termination, and the slowing into a turn and the speeding
out of it: Ensink et al. 2023, Sensors 23:2002, found the two strides either side of a turn
different from steady walking in 191 patients, and one left out either side giving the same
means and SDs as two). The summary's means (:func:`stride_summary`) are over the straight,
steady strides, and it counts the others.
"""

from __future__ import annotations

from dataclasses import astuple, dataclass, fields, replace

import numpy as np

from pipeline.analysis.foot_trajectory import FootTrajectory
from pipeline.analysis.gait_events import GaitEvents

__all__ = ["MAX_STRIDE_S", "MERGED_SHARE", "STRAIGHT_TURN_DEG", "STRIDES_CSV_COLUMNS",
           "STRIDE_COLUMNS", "Stride",
           "foot_strides", "in_the_means", "left_out", "mark_steady", "stride_rows",
           "stride_summary", "stride_table", "strides_csv"]

#: A stride turning less than this (deg) is straight.
STRAIGHT_TURN_DEG = 20.0
#: Two initial contacts further apart than this (s) are no stride.
MAX_STRIDE_S = 2.5
#: A stride longer than this many times its side's median merges two: a contact was missed.
MERGED_SHARE = 1.5


@dataclass(frozen=True)
class Stride:
    """One stride (module docstring), SI units; the fields are ``<name>_strides.csv``'s columns."""

    side: str
    start_s: float
    end_s: float
    stride_time_s: float
    stance_share: float
    stride_length_m: float
    speed_m_s: float
    cadence_steps_min: float
    clearance_m: float
    turn_deg: float
    straight: bool
    steady: bool = True


STRIDE_COLUMNS = tuple(f.name for f in fields(Stride))


def _rest_after(rests: np.ndarray, k: float) -> tuple[int, int] | None:
    later = rests[rests[:, 0] >= k]
    return (int(later[0, 0]), int(later[0, 1])) if len(later) else None


def _heading(R: np.ndarray) -> float:
    """The heading (rad) of the sensor's most horizontal axis, measured about z."""
    axis = R[:, int(np.argmin(np.abs(R[2])))]
    return float(np.arctan2(axis[1], axis[0]))


def _path_measures(events: GaitEvents, path: FootTrajectory, k0: float, k1: float):
    """``(length, clearance, turn_deg)`` between the rests after ICs ``k0`` and ``k1``."""
    nan = (np.nan, np.nan, np.nan)
    r0, r1 = _rest_after(events.rests, k0), _rest_after(events.rests, k1)
    if r0 is None or r1 is None or r0 == r1:
        return nan
    m0, m1 = (r0[0] + r0[1]) // 2, (r1[0] + r1[1]) // 2
    p0, p1 = path.position[m0], path.position[m1]
    if not (np.all(np.isfinite(p0)) and np.all(np.isfinite(p1))):
        return nan
    length = float(np.linalg.norm(p1[:2] - p0[:2]))
    clearance = float(np.nanmax(path.position[r0[1]:r1[0] + 1, 2]) - p0[2])
    turn = np.degrees(np.angle(np.exp(1j * (_heading(path.rotation[m1]) -
                                            _heading(path.rotation[m0])))))
    return length, clearance, float(turn)


def foot_strides(side: str, time: np.ndarray, events: GaitEvents,
                 path: FootTrajectory | None) -> list[Stride]:
    """Every stride of one foot (module docstring)."""
    out = []

    def at(k: float) -> float:  # the time of a fractional sample index
        return float(np.interp(k, np.arange(len(time)), time))

    for k0, k1 in zip(events.ic[:-1], events.ic[1:], strict=True):
        t = at(k1) - at(k0)
        if not 0 < t <= MAX_STRIDE_S:
            continue
        off = events.fc[(events.fc > k0) & (events.fc < k1)]
        stance = (at(off[0]) - at(k0)) / t if len(off) else np.nan
        length, clearance, turn = (np.nan,) * 3
        if path is not None:
            length, clearance, turn = _path_measures(events, path, k0, k1)
        out.append(Stride(side, at(k0), at(k1), t, stance, length, length / t,
                          120.0 / t, clearance, turn, bool(abs(turn) < STRAIGHT_TURN_DEG)))
    return mark_steady(out)


def mark_steady(strides: list[Stride]) -> list[Stride]:
    """One side's strides (in order) with ``steady`` set (module docstring)."""
    if not strides:
        return strides
    typical = float(np.median([s.stride_time_s for s in strides]))
    out = []
    for k, s in enumerate(strides):
        before = strides[k - 1] if k > 0 else None
        after = strides[k + 1] if k + 1 < len(strides) else None
        walked_in = before is not None and before.end_s == s.start_s and _goes_on(before)
        walks_on = after is not None and after.start_s == s.end_s and _goes_on(after)
        merged = s.stride_time_s > MERGED_SHARE * typical
        out.append(replace(s, steady=walked_in and walks_on and _goes_on(s) and not merged))
    return out


def _goes_on(s: Stride) -> bool:
    """Whether a stride continues a straight walk: straight, or its turn unknown (a shank's)."""
    return s.straight or not np.isfinite(s.turn_deg)


def left_out(strides: list[Stride]) -> dict[str, int]:
    """Why strides are left out of the means: their counts (``turning``, ``starting or
    stopping`` a straight walk, from standing or a turn, ``merged``: longer than
    :data:`MERGED_SHARE` times the side's median)."""
    typical = {side: float(np.median([s.stride_time_s for s in strides if s.side == side]))
               for side in {s.side for s in strides}}
    merged = [s for s in strides if s.stride_time_s > MERGED_SHARE * typical[s.side]]
    turning = [s for s in strides if not _goes_on(s) and s not in merged]
    ends = [s for s in strides if not s.steady and s not in merged and s not in turning]
    return {"turning": len(turning), "starting or stopping": len(ends), "merged": len(merged)}


def in_the_means(s: Stride) -> bool:
    """Whether a stride counts in the summary's means: steady, and straight where its turn is
    known (a shank's strides have none)."""
    return s.steady and (s.straight or not np.isfinite(s.turn_deg))


def stride_rows(strides: list[Stride]) -> list[tuple]:
    """The strides as rows of :data:`STRIDE_COLUMNS`."""
    return [astuple(s) for s in strides]


def stride_summary(strides: list[Stride]) -> dict[str, dict[str, tuple[float, float, int]]]:
    """``{'right'|'left'|'both': {parameter: (mean, SD, n)}}`` over the straight, steady strides
    with a value (:func:`in_the_means`; NaN where none)."""
    out = {}
    for group in ("right", "left", "both"):
        chosen = [s for s in strides if group in ("both", s.side) and in_the_means(s)]
        out[group] = {}
        for name in STRIDE_COLUMNS[3:10]:
            v = np.array([getattr(s, name) for s in chosen], dtype=float)
            v = v[np.isfinite(v)]
            sd = float(np.std(v, ddof=1)) if len(v) > 1 else np.nan
            out[group][name] = (float(np.mean(v)) if len(v) else np.nan, sd, int(len(v)))
    return out


#: ``<name>_strides.csv``'s columns: the stride's number (from 1, as ``<name>_cycles.csv``
#: refers to it), :data:`STRIDE_COLUMNS`, and whether it counts in the means.
STRIDES_CSV_COLUMNS = ("stride", *STRIDE_COLUMNS, "in_means")


def strides_csv(strides: list[Stride]) -> str:
    """``<name>_strides.csv``: :data:`STRIDES_CSV_COLUMNS`, one row per stride (SI units, 6
    significant digits: ``stance_share`` a fraction of the stride; ``straight``, ``steady`` and
    ``in_means`` (:func:`in_the_means`) as ``true``/``false``; an empty cell where a value is not
    measured)."""
    from pipeline.io.tables import csv_text

    def cell(v):
        if isinstance(v, bool):
            return "true" if v else "false"
        return "" if isinstance(v, float) and not np.isfinite(v) else v

    rows = [{"stride": k + 1, **{c: cell(getattr(s, c)) for c in STRIDE_COLUMNS},
             "in_means": cell(in_the_means(s))} for k, s in enumerate(strides)]
    return csv_text(rows, STRIDES_CSV_COLUMNS)


#: The summary's parameters: column -> (label, scale, digits).
_SHOWN = {"stride_time_s": ("stride time (s)", 1.0, 2), "stance_share": ("stance share", 1.0, 3),
          "stride_length_m": ("stride length (m)", 1.0, 2), "speed_m_s": ("speed (m/s)", 1.0, 2),
          "cadence_steps_min": ("cadence (steps/min)", 1.0, 1),
          "clearance_m": ("clearance (cm)", 100.0, 1)}


def stride_table(strides: list[Stride]) -> list[str]:
    """The strides' mean ± SD per side and over both, as Markdown lines."""
    summary = stride_summary(strides)
    n = {g: sum(1 for s in strides if g in ("both", s.side) and in_the_means(s))
         for g in summary}
    lines = [f"| parameter | right (n={n['right']}) | left (n={n['left']}) | "
             f"both (n={n['both']}) |", "|---|---|---|---|"]
    for col, (label, scale, digits) in _SHOWN.items():
        cells = []
        for group in ("right", "left", "both"):
            mean, sd, k = summary[group][col]
            cells.append("" if k == 0 else f"{scale * mean:.{digits}f} ± {scale * sd:.{digits}f}"
                         if k > 1 else f"{scale * mean:.{digits}f}")
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    out = left_out(strides)
    lines.append(f"| strides turning {STRAIGHT_TURN_DEG:.0f} deg or more | | | {out['turning']} |")
    lines.append(f"| strides starting or stopping a straight walk (from standing or a turn) | | | "
                 f"{out['starting or stopping']} |")
    lines.append(f"| strides longer than {MERGED_SHARE:g} times the side's median (a missed "
                 f"contact?) | | | {out['merged']} |")
    return lines
