"""A sensor that slips on its segment during a walk: its own view of the segment turns.

A segment's flexion axis is fixed in the segment, and so, nearly, is gravity's direction in it at
mid-stance, when the foot rests flat and the leg passes over it in the same posture stride after
stride. A sensor sees both in its own frame without any orientation estimate: the flexion axis
as the principal axis of the horizontal angular velocity (:mod:`pipeline.calibration.flexion_axis`,
eq 1 there, the vertical ``u`` from the low-passed accelerometer), gravity as the mean
accelerometer over the foot's rest. A sensor fixed to its segment keeps both from stride to
stride; one that slipped by ``theta`` turns them in its frame by up to ``theta`` (the axis unless
it slipped about the axis itself, gravity unless about the vertical: every slip turns one).

Per stride ``k`` of the sensor's leg (initial contact to the next, from the foot's events, else
the shank's: :mod:`pipeline.analysis.gait_events`), the scatter of the horizontal angular velocity
``C_k = sum w_h w_h^T`` and the mid-stance gravity ``g_k`` (strides with a foot rest). At each
split ``m`` of the strides, with at least :data:`MIN_SIDE` strides on either side,

    d_axis(m) = angle(e1(sum_{k<m} C_k), e1(sum_{k>=m} C_k))                       (1)
    d_g(m)    = angle(mean_{k<m} g_k, mean_{k>=m} g_k)                             (2)

(``e1``: the principal eigenvector, its sign free). The step is the largest ``max(d_axis, d_g)``
over the splits; beyond :data:`SLIP_DEG` the sensor slipped at that stride. Measured without a
slip: up to 7 deg on the real walk gaittoolbox_s02 (5-6 strides a side, a turn), 9.8 on the
simulated walk with soft tissue (its first strides from standing differ; seeds 0-3, 5); a 30 deg
slip about any of the sensor's axes, of a thigh, shank or foot sensor halfway through the walk:
23-34 deg on S02, 25-35 on the simulated walk
(``tests/test_process_slip.py``, ``scripts/bench_faults.py``). A leg with fewer than
``2 MIN_SIDE`` strides is not checked (no walk to compare).

The pelvis has no flexion axis, but it rocks once a stride about a forward axis (its obliquity,
the hip of the swinging leg dropping) while it tilts twice a stride about its lateral axis and
turns about the vertical. So its axis is taken from the stride rate alone: per stride ``k`` of
``n_k`` samples, the first Fourier coefficient of the horizontal angular velocity and its scatter

    c_k = 1/n_k sum_j w_h(j) exp(-2 pi i j / n_k),   C_k = Re c_k Re c_k^T + Im c_k Im c_k^T   (3)

(no low-pass: the coefficient is one), whose principal axis goes into eq (1), with gravity at
mid-stance (eq 2), on the right foot's strides, else the left's. Only strides of a walk count
(:func:`walking_strides`: joined to a neighbour, within :data:`STRIDE_TOL` of the median
duration): a lone step, or two strides joined by a missed contact, rock at another rate (on the
qmt recording such strides put the axis 74-84 deg away). Measured without a slip (the largest step
of eq 1 for the pelvis): S02 8.0 deg on the right leg's strides (4.7 on the left's), the
simulated walk 0.7-1.7 (seeds 0-3, 5), qmt 8.9; a 30 deg turn about the sensor's vertical (a
belt turning around the waist) 22 deg on S02 and 26-29 on the simulated walk, found; a turn
about a horizontal axis turns gravity (27-31 deg). The principal axis of the low-passed (3 Hz)
horizontal angular velocity, tried first, mixes the rocking with the tilt (principal ratio
1.2-3.3 against the harmonic's 6-8 on S02 and hundreds on the simulated walk) and stepped 11-15
deg without a slip on S02 and on seed 3; that of the horizontal acceleration 24-29 deg.

A slip moves one sensor; a change of the walk itself (stairs, a slope, gait initiation's first
strides) turns every sensor of the leg, and both legs. So a step is a slip only while the leg's
other sensors step less than :data:`ALONE_DEG` at the same split, or, where they step too, while
the other leg's sensor on the same segment does (at its split nearest in time): with a 30 deg
slip the leg's other sensors step 2-7 deg (S02, the simulated walk); without one, the early
splits where a sensor steps most are common to the leg (others at 6-8 deg: the first strides from
standing), and on the qmt full-body recording, whose movement changes at 67-70 s, the thighs'
mid-stance gravity steps 21-29 deg with the shanks' 10-15 and the other thigh's 18-22: a change of
the movement, which the rule keeps from being taken for slips. Two sensors of a leg slipping
together (one strap over both) step 23-30 deg (S02) and 29-32 (the simulated walk) while the other
leg's step 2-4: both are named. Without a slip the other leg's same sensor steps 1.9-6.4 deg at
the split (a right thigh, shank or foot sensor slipped on S02, on the simulated walk's seeds 0-3,
5). A step beyond the limit that the leg's
others and the other leg's share (:attr:`Slip.inconclusive`) cannot be told from such a change:
the sensor is listed as not checked (the x-IMU3 walk, two short walks with turns on the spot and
shuffles: every leg sensor steps 20-86 deg with the others, the pelvis 19; qmt's thighs).

**Certain or a flag.** A step beyond :data:`SLIP_DEG` is a flag (the sensor kept, the run says
where); only a leg sensor's flexion axis turned beyond :data:`CERTAIN_SLIP_DEG`, alone on its
leg, excludes it (:attr:`Slip.certain`). The pelvis's is never certain: its rocking changes
where a walk starts, speeds up, slows, stops or turns, and no other sensor turns with it to tell
(S02 cut to its strides, with the turn and the stop: 8.0-10.9 deg; other labs' walkways: 20-21
deg, as much as the 22 deg of a belt turned by 30 deg on S02).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pipeline.filtering import lowpass
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR, SENSOR_TO_SEGMENT
from pipeline.model.conventions import other_side
from pipeline.process.slip_step import (
    ALONE_DEG,
    CERTAIN_SLIP_DEG,
    MAX_STRIDE_S,
    ROCKING_AXIS,
    SLIP_DEG,
    Slip,
    larger,
)

__all__ = ["ALONE_DEG", "CERTAIN_SLIP_DEG", "MAX_STRIDE_S", "MIN_SIDE", "ROCKING_AXIS", "SLIP_DEG",
           "STRIDE_TOL", "Slip", "leg_slips", "legs_slips", "slip_step", "unchecked",
           "walking_strides"]

#: Strides needed on each side of a split.
MIN_SIDE = 2
#: The flexion axis's low-pass cut-off (Hz) and the vertical's, and the horizontal angular speed
#: (rad/s) from which a sample counts (as :mod:`pipeline.calibration.flexion_axis`).
AXIS_CUTOFF_HZ = 3.0
VERTICAL_CUTOFF_HZ = 0.5
MIN_SPEED = 0.5
#: A stride lasting longer or shorter than the leg's median by more than this share is not used
#: for the pelvis's axis (eq 3).
STRIDE_TOL = 0.25
def _angle(a: np.ndarray, b: np.ndarray, signed: bool = True) -> float:
    """The angle (deg) between ``a`` and ``b`` (of their lines when not ``signed``); NaN when
    either is zero (a sensor's samples missing there)."""
    norms = float(np.linalg.norm(a) * np.linalg.norm(b))
    if not norms > 0.0:
        return float("nan")
    c = float(a @ b / norms)
    return float(np.degrees(np.arccos(np.clip(c if signed else abs(c), -1.0, 1.0))))


def _principal(C: np.ndarray) -> np.ndarray:
    return np.linalg.eigh(C)[1][:, -1]


def _strides(ctx, side: str) -> tuple[list[tuple[int, int]], np.ndarray]:
    """The leg's strides as sample ranges and its foot's rests (none from a shank), from the
    recording's gait events (the context's ``gait``: the foot's, else the shank's); a stride
    over a gap of the leg's or the pelvis's sensors left out (bridged there, not measured)."""
    ev = ctx.gait.events.get(side)
    if ev is None:
        return [], np.zeros((0, 2), int)
    ics = np.round(ev.ic).astype(int)
    longest = MAX_STRIDE_S * ctx.rec.rate_hz
    own = ctx.rec.present(*(n for n in ctx.rec.sensors if _on_leg(n, side)))
    strides = [(a, b) for a, b in zip(ics[:-1], ics[1:], strict=True)
               if b - a <= longest and own[a:b].all()]
    foot = ctx.gait.sources[side].startswith("foot")
    return strides, (ev.rests if foot else np.zeros((0, 2), int))


def _on_leg(name: str, side: str) -> bool:
    """Whether sensor ``name`` is on the ``side`` leg or the pelvis."""
    segment = SENSOR_TO_SEGMENT.get(name, "")
    return segment == "pelvis" or segment.startswith(f"{side}_")


def _horizontal(w: np.ndarray, acc: np.ndarray, rate_hz: float) -> np.ndarray:
    """``w`` less its part along the vertical ``u`` (the low-passed accelerometer's direction)."""
    u = lowpass(acc, rate_hz, VERTICAL_CUTOFF_HZ)
    norm = np.linalg.norm(u, axis=1, keepdims=True)
    u = np.divide(u, norm, out=np.zeros_like(u), where=norm > 0)
    return w - np.sum(w * u, axis=1, keepdims=True) * u


def _flexing(gyr, acc, rate_hz, strides) -> np.ndarray:
    """A leg sensor's ``C_k`` (k, 3, 3), eq (1): the scatter of its horizontal angular velocity."""
    w_h = _horizontal(lowpass(gyr, rate_hz, AXIS_CUTOFF_HZ), acc, rate_hz)
    w_h[np.linalg.norm(w_h, axis=1) < MIN_SPEED] = 0.0
    return np.array([w_h[a:b].T @ w_h[a:b] for a, b in strides])


def _mid_stance_gravity(acc, strides, rests) -> np.ndarray:
    """``g_k`` (k, 3), eq (2): the mean accelerometer over the stride's longest foot rest, NaN
    for a stride without one."""
    g = np.full((len(strides), 3), np.nan)
    for k, (a, b) in enumerate(strides):
        inside = [(r0, r1) for r0, r1 in rests if a <= r0 and r1 <= b]
        if inside:
            r0, r1 = max(inside, key=lambda r: r[1] - r[0])
            g[k] = np.mean(acc[r0:r1], axis=0)
    return g


def _rocking(gyr, acc, rate_hz, strides) -> np.ndarray:
    """The pelvis's ``C_k`` (k, 3, 3), eq (3): the scatter of the stride-rate Fourier coefficient
    of its horizontal angular velocity, whose principal axis is the one it rocks about once a
    stride (its obliquity's, forward)."""
    w_h = _horizontal(gyr, acc, rate_hz)
    C = np.zeros((len(strides), 3, 3))
    for k in walking_strides(strides):
        a, b = strides[k]
        c = np.exp(-2j * np.pi * np.arange(b - a) / (b - a)) @ w_h[a:b] / (b - a)
        C[k] = np.outer(c.real, c.real) + np.outer(c.imag, c.imag)
    return C


def walking_strides(strides: list[tuple[int, int]]) -> list[int]:
    """The strides that are one stride of a walk: joined to the one before or after and within
    :data:`STRIDE_TOL` of the leg's median duration (not a lone step, nor two strides joined by
    a missed contact, whose stride rate is not the walk's)."""
    n = np.array([b - a for a, b in strides], float)
    typical = np.median(n) if len(n) else 0.0
    joined = [(k > 0 and strides[k - 1][1] == a) or (k + 1 < len(strides)
              and strides[k + 1][0] == b) for k, (a, b) in enumerate(strides)]
    return [k for k in range(len(strides))
            if joined[k] and abs(n[k] - typical) <= STRIDE_TOL * typical]


def _step_at(C: np.ndarray, g: np.ndarray, m: int) -> tuple[float, float]:
    """Eq (1) and (2) at split ``m``; ``d_axis`` NaN without an axis on both sides (``C``
    zero), ``d_g`` NaN without rests on both sides."""
    C_0, C_1 = C[:m].sum(0), C[m:].sum(0)
    d_axis = _angle(_principal(C_0), _principal(C_1), signed=False) if C_0.any() and C_1.any() \
        else np.nan
    before, after = g[:m][np.isfinite(g[:m, 0])], g[m:][np.isfinite(g[m:, 0])]
    d_g = _angle(before.mean(0), after.mean(0)) if len(before) and len(after) else np.nan
    return d_axis, d_g


def _largest_step(C: np.ndarray, g: np.ndarray, strides, time: np.ndarray) -> Slip:
    """The split with the largest ``max(d_axis, d_g)`` (eq 1, 2)."""
    best = None
    for m in range(MIN_SIDE, len(strides) - MIN_SIDE + 1):
        pause = float(time[strides[m][0]] - time[strides[m - 1][1]])
        step = Slip(*_step_at(C, g, m), float(time[strides[m][0]]), m, len(strides) - m,
                    pause_s=pause)
        if best is None or step.deg > best.deg:
            best = step
    return best


def _leg_views(ctx, side: str, pelvis: bool):
    """The leg's strides, its sensors with raw signals (the pelvis's too when asked, its ``C_k``
    by eq 3) and each one's ``(C_k, g_k)``; no sensors for a leg with too few strides."""
    rec = ctx.rec
    strides, rests = _strides(ctx, side)
    if len(strides) < 2 * MIN_SIDE:
        return strides, {}, {}
    names = [SEGMENT_SENSOR[f"{side}_{seg}"] for seg in ("femur", "tibia", "foot")]
    pelvis_name = SEGMENT_SENSOR["pelvis"]
    names += [pelvis_name] if pelvis else []
    leg = {n: rec.sensors[n] for n in names if n in rec.sensors
           and rec.sensors[n].gyr is not None and rec.sensors[n].acc is not None}
    views = {}
    for n, s in leg.items():
        gyr, acc = np.nan_to_num(s.gyr), np.nan_to_num(s.acc)
        axis = _rocking if n == pelvis_name else _flexing  # the pelvis has no flexion axis
        views[n] = (axis(gyr, acc, rec.rate_hz, strides), _mid_stance_gravity(acc, strides, rests))
    return strides, leg, views


def _mirror_step(other, name: str, time_s: float, time: np.ndarray) -> float:
    """The step of the other leg's sensor on ``name``'s segment (``other``: that leg's
    :func:`_leg_views`) at its split nearest ``time_s`` (NaN without that sensor or enough
    strides)."""
    side, _, segment = SENSOR_TO_SEGMENT.get(name, "").partition("_")
    if side not in ("right", "left"):
        return float("nan")
    strides, leg, views = other
    mirror = SEGMENT_SENSOR[f"{other_side(side)}_{segment}"]
    if mirror not in views or not leg[mirror].complete:
        return float("nan")
    starts = time[[a for a, _ in strides]]
    m = int(np.clip(np.argmin(np.abs(starts - time_s)), MIN_SIDE, len(strides) - MIN_SIDE))
    return larger(*_step_at(*views[mirror], m))


def leg_slips(ctx, side: str, pelvis: bool = False) -> dict[str, Slip]:
    """Sensor -> its largest step (module docstring) for each sensor of the ``side`` leg with raw
    signals, with the leg's other sensors' steps at the same split (those with every sample
    finite: a sensor with a dropout is excluded by its own check) and the other leg's same
    sensor's; empty for a leg with too few strides. ``ctx``: the recording's
    :class:`~pipeline.process.check_context.CheckContext`; ``pelvis``: the pelvis's sensor too,
    on this leg's strides (eq 2, 3), the leg's sensors its others."""
    return _slips(ctx.rec, _leg_views(ctx, side, pelvis), _leg_views(ctx, other_side(side), False))


def _slips(rec: Recording, this, other) -> dict[str, Slip]:
    """:func:`leg_slips` from the two legs' :func:`_leg_views`."""
    strides, leg, views = this
    pelvis_name = SEGMENT_SENSOR["pelvis"]
    out = {}
    for name, (C, g) in views.items():
        best = _largest_step(C, g, strides, rec.time)
        others = [larger(*_step_at(*views[n], best.before)) for n in views
                  if n not in (name, pelvis_name) and leg[n].complete]
        seen = [d for d in others if np.isfinite(d)]
        out[name] = dataclasses.replace(
            best, others_deg=float(max(seen, default=0.0)),
            others_min_deg=float(min(seen, default=0.0)),
            mirror_deg=_mirror_step(other, name, best.time_s, rec.time),
            axis_name=ROCKING_AXIS if name == pelvis_name else best.axis_name)
    return out


def legs_slips(ctx) -> dict[str, tuple[dict[str, Slip], int]]:
    """Side -> (:func:`leg_slips` with the pelvis, the leg's stride count), each leg's views
    computed once for its own check and the other leg's (the context keeps the result)."""
    views = {side: _leg_views(ctx, side, pelvis=True) for side in ("right", "left")}
    return {side: (_slips(ctx.rec, views[side], views[other_side(side)]), len(views[side][0]))
            for side in views}


def slip_step(name: str, ctx) -> Slip | None:
    """Sensor ``name``'s entry of :func:`leg_slips` (the pelvis's: on the right leg's strides,
    else the left's); None for a torso sensor, one without raw signals, or too few strides.
    ``ctx``: the recording's :class:`~pipeline.process.check_context.CheckContext`."""
    s, segment = ctx.rec.sensors[name], SENSOR_TO_SEGMENT.get(name, "")
    if s.gyr is None or s.acc is None:
        return None
    if segment == "pelvis":
        return next((found for side in ("right", "left")
                     if (found := ctx.slips[side][0].get(name)) is not None), None)
    if not segment.startswith(("right_", "left_")):
        return None
    return ctx.slips[segment.split("_", 1)[0]][0].get(name)


def unchecked(name: str, ctx) -> str | None:
    """Why sensor ``name`` was not checked although the recording walks: its leg has fewer than
    ``2 MIN_SIDE`` strides (one stride a side is too few: without a slip S02's left shank
    steps 15.3 deg between single strides, beyond the limit, with the leg's others at 11.7 and the
    other leg's at 1.2: it would be named); None when it was checked or neither leg walked."""
    segment, s = SENSOR_TO_SEGMENT.get(name, ""), ctx.rec.sensors[name]
    sides = ("right", "left") if segment == "pelvis" else (segment.split("_", 1)[0],)
    if s.gyr is None or s.acc is None or sides[0] not in ("right", "left") \
            or slip_step(name, ctx) is not None:
        return None
    strides = {side: ctx.slips[side][1] for side in ("right", "left")}
    found = max(strides[side] for side in sides)
    if max(strides.values()) == 0 or found >= 2 * MIN_SIDE:
        return None
    where = ("on either leg" if len(sides) == 2 else
             f"on its leg (the other leg: {strides[other_side(sides[0])]})")
    return (f"not checked for a slip: {found} stride(s) found {where}, {2 * MIN_SIDE} are needed "
            "to compare before and after")
