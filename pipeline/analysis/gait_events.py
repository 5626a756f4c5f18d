"""Gait events from one foot's (or shank's) gyroscope and accelerometer.

**Rest** (mid-stance, the foot flat and still): samples whose angular speed stays below
:data:`REST_GYRO` and whose specific force stays within :data:`REST_ACC` of 1 g over a
:data:`REST_WINDOW_S` window, the stance-phase detector of zero-velocity-aided foot navigation
(Skog et al. 2010, IEEE TBME 57(11), the "angular rate energy" and "acceleration moving variance"
tests), kept when it lasts :data:`MIN_REST_S`.

**Contacts** from the sagittal angular velocity ``w`` (the gyroscope projected on the principal
axis of its horizontal part over the moving samples, the foot's flexion axis: turns about the
vertical left out, :func:`sagittal_rate`). Between two rests the foot turns one way
in push-off (the heel rising), the other way through the swing, and back at the heel strike
(foot flat): the swing is the lobe of ``w`` (a run of one sign) that turns the foot furthest, and
``w`` is signed so that it is positive. **Final contact** (FC, toe-off) is the fastest push-off
rotation, the minimum of ``w`` before the swing lobe (as Rampp et al. 2015, IEEE TBME 62(4)),
**initial contact** (IC) where the swing lobe ends (``w`` crosses zero downwards, interpolated
between samples: the foot stops turning up as the heel lands). Measured on S02 against the
Vicon heel and toe markers (Zeni et al. 2008's events): :file:`results/bench_gait.txt`. A
movement between two rests counts as a swing when its peak exceeds :data:`MIN_SWING_RATE`, or when
the foot moved :data:`MIN_STEP_M` or more between the two rests (its path by
:func:`pipeline.analysis.foot_trajectory.foot_trajectory`): a pivot step in a turn barely pitches
the foot (S02's right foot at its 180 deg turn: 30 cm with a peak of 1.3 rad/s, its IC 10 ms from
Vicon's); standing still or shuffling gives no event (the largest such movements: 5 cm on the
x-IMU3 walk, 1 cm on S02), nor does a movement whose largest lobe turns the foot backwards (the
x-IMU3 walk's turns have two, of 22 and 40 cm: steps sideways or back, not found). A shank
sensor never rests in stance: its swings are the peaks of ``w`` (Salarian et al. 2004, IEEE TBME
51(8)) beyond a share of the walk's own (:data:`SHANK_PEAK_SHARE`; a turn's pivot step swings
the shank slowly), its FC the minimum within :data:`CONTACT_SEARCH_S`
before each peak, its IC, as the foot's, where the swing's rotation ends (``w`` crosses zero
downwards after the peak, or its first trough, whichever comes first; else the minimum within
:data:`CONTACT_SEARCH_S` after it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.analysis.foot_trajectory import FootTrajectory, foot_trajectory
from pipeline.filtering import lowpass
from pipeline.io.gaps import true_runs

__all__ = ["MAX_STANCE_S", "MIN_SHANK_PEAK", "SEGMENTS", "SHANK_PEAK_SHARE", "STRIDE_SHARE",
           "STRIDE_RANGE_S", "GaitEvents",
           "MIN_STEP_M", "MIN_SWING_RATE", "REST_ACC", "REST_GYRO", "gait_events", "rest_periods",
           "rest_vertical", "sagittal_rate", "stance_rests", "stride_period",
           "swing_peaks"]

#: Rest: angular speed below this (rad/s; ~29 deg/s), specific force within REST_ACC (m/s^2) of
#: 1 g, over a REST_WINDOW_S window; kept when it lasts MIN_REST_S.
REST_GYRO = 0.5
REST_ACC = 1.5
REST_WINDOW_S = 0.05
MIN_REST_S = 0.05
#: A swing's mid-swing peak of the sagittal rate (rad/s; feet reach 5-12 in walking).
MIN_SWING_RATE = 2.0
#: Or a step: the foot's horizontal move between two rests (m), twice the largest shuffle seen.
MIN_STEP_M = 0.10
G = 9.81


@dataclass(frozen=True)
class GaitEvents:
    """One foot's events: ``rests`` (k, 2) ``[start, stop)`` sample ranges of each rest, the
    swing peaks' samples ``swing``, and per swing ``fc`` before and ``ic`` after it (fractional
    sample indices);
    ``axis``: the sagittal axis in the sensor frame (unit, mid-swing positive); ``trajectory``:
    the foot's path between its rests when a weak swing needed it (None otherwise), so that the
    gait analysis does not compute it again."""

    rests: np.ndarray
    swing: np.ndarray
    ic: np.ndarray
    fc: np.ndarray
    axis: np.ndarray
    trajectory: FootTrajectory | None = None


def _moving_max(x: np.ndarray, n: int) -> np.ndarray:
    """The largest value within ``n`` samples centred on each sample."""
    pad = np.pad(x, (n // 2, n - 1 - n // 2), mode="edge")
    windows = np.lib.stride_tricks.sliding_window_view(pad, n)
    return windows.max(axis=1)


def rest_periods(gyr: np.ndarray, acc: np.ndarray, rate_hz: float) -> np.ndarray:
    """``(k, 2)`` ``[start, stop)`` sample ranges of rest (module docstring)."""
    n = max(1, int(round(REST_WINDOW_S * rate_hz)))
    speed = _moving_max(np.linalg.norm(np.nan_to_num(gyr), axis=1), n)
    force = _moving_max(np.abs(np.linalg.norm(np.nan_to_num(acc), axis=1) - G), n)
    still = (speed < REST_GYRO) & (force < REST_ACC)
    least = max(2, int(round(MIN_REST_S * rate_hz)))
    rests = [(a, b) for a, b in true_runs(still) if b - a >= least]
    return np.array(rests, dtype=int).reshape(-1, 2)


def _runs(w: np.ndarray) -> list[tuple[int, int]]:
    """``[start, stop)`` of each run of one sign of ``w``."""
    cuts = np.flatnonzero(np.diff(np.sign(w)) != 0) + 1
    bounds = np.concatenate([[0], cuts, [len(w)]])
    return list(zip(bounds[:-1].tolist(), bounds[1:].tolist(), strict=True))


def _swing_lobe(w: np.ndarray, a: int, b: int) -> tuple[int, int, float]:
    """The run of one sign within ``[a, b)`` with the largest turn: ``(start, stop, turn)``;
    the largest forward (positive) run where it turns at least half as much as the largest
    backward one (a fast walk's first stride from standing turns the foot back through its
    whole stance as much as forward in its swing: no rest between them splits the stance)."""
    runs = [(a + i, a + j, float(np.sum(w[a + i:a + j]))) for i, j in _runs(w[a:b])]
    largest = max(runs, key=lambda r: abs(r[2]))
    forward = max(runs, key=lambda r: r[2])
    return forward if forward[2] >= 0.5 * abs(largest[2]) else largest


def _largest_turn(w: np.ndarray, a: int, b: int) -> float:
    """The largest turn (rad, signed) of a run of one sign within ``[a, b)``."""
    return max((float(np.sum(w[a + i:a + j])) for i, j in _runs(w[a:b])), key=abs)


def rest_vertical(acc: np.ndarray, rests: np.ndarray) -> np.ndarray:
    """The world's vertical (unit, up) in the sensor frame: the specific force's mean direction
    over the rests (the foot flat, the leg upright), else over the whole recording."""
    still = np.zeros(len(acc), dtype=bool)
    for a, b in rests:
        still[a:b] = True
    f = np.nan_to_num(acc[still] if still.any() else acc)
    unit = f / np.maximum(np.linalg.norm(f, axis=1, keepdims=True), 1e-9)
    mean = unit.mean(axis=0)
    return mean / max(float(np.linalg.norm(mean)), 1e-9)


def sagittal_rate(gyr: np.ndarray, rests: np.ndarray,
                  up: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """``(w, axis)``: the gyroscope on the principal axis of its horizontal part over the samples
    out of rest, signed so that the swings (the largest turn between two rests; without rests,
    the largest peak) are positive.

    The horizontal part ``w_h = w - (w . u) u``, with ``u`` the vertical at rest (``up``, from
    :func:`rest_vertical` as :func:`gait_events` gives it; without it the plain principal axis),
    leaves out the turns about the vertical: where a walk turns on the spot or shuffles, those
    outweigh the flexion (the x-IMU3 walk's right foot: its plain principal axis is 5 deg from
    the vertical). Aligning a foot sensor by gravity, then by the principal axis of its horizontal
    angular velocity, is gaitmap's foot-frame alignment (Küderle et al. 2024)."""
    moving = np.ones(len(gyr), dtype=bool)
    for a, b in rests:
        moving[a:b] = False
    g = np.nan_to_num(gyr)
    sample = g[moving] if moving.sum() >= 10 else g
    if up is not None:
        sample = sample - np.outer(sample @ up, up)
    _, _, vt = np.linalg.svd(sample - sample.mean(axis=0), full_matrices=False)
    axis = vt[0]
    w = g @ axis
    turns = [_largest_turn(w, a, b) for (_, a), (b, _) in zip(rests[:-1], rests[1:], strict=True)
             if b - a >= 3]
    if turns:  # the walk's swings outweigh a standing start's or a shuffle's small turns
        flip = np.sum(turns) < 0
    else:
        flip = w[moving].max(initial=0.0) < -w[moving].min(initial=0.0)
    return (-w, -axis) if flip else (w, axis)


def _crossing(w: np.ndarray, k: int) -> float:
    """The zero crossing of ``w`` between samples ``k - 1`` and ``k`` (interpolated)."""
    if k <= 0 or k >= len(w) or w[k - 1] == w[k]:
        return float(k)
    return k - 1 + float(w[k - 1] / (w[k - 1] - w[k]))


#: Without rests (a shank sensor: the shank turns through stance), each swing peak's contacts
#: are searched within this many seconds of it (a swing lasts ~0.4 s).
CONTACT_SEARCH_S = 0.35


#: A shank's swing peak counts from this share of the walk's typical peak (the median of those
#: beyond :data:`MIN_SWING_RATE`), down to :data:`MIN_SHANK_PEAK` rad/s: a pivot step in a turn
#: swings the shank at a third of a straight stride's rate (S02's right shank at its 180 deg turn:
#: 1.6 rad/s, its straight strides 4.5-5.4), standing and shuffling at a tenth.
SHANK_PEAK_SHARE = 0.25
MIN_SHANK_PEAK = 1.0
#: Swing peaks lie at least this share of the walk's stride apart (:func:`stride_period`): S02's
#: feet turn at 4-6.4 rad/s in a lobe 0.65 s after a swing (a stride of 1.4 s), nearly as fast as
#: the swing itself.
STRIDE_SHARE = 0.7


def _shank_events(w: np.ndarray, rate_hz: float):
    peaks = swing_peaks(w, rate_hz)
    reach = int(CONTACT_SEARCH_S * rate_hz)
    fc = [max(0, p - reach) + int(np.argmin(w[max(0, p - reach):p])) for p in peaks]
    ic = [_swing_end(w, p, 2 * reach) for p in peaks]
    return peaks, np.asarray(ic, float), np.asarray(fc, float)


def _swing_end(w: np.ndarray, peak: int, reach: int) -> float:
    """Where a shank's swing rotation ends after its ``peak`` (the heel lands): ``w`` crossing
    zero downwards, or sooner its first trough below a quarter of the peak (a stopping step:
    the shank keeps turning slowly forward after the heel lands, S02's last left stride crossed
    zero 270 ms after the foot's contact, its trough within 10 ms of it); without either, the
    minimum within ``reach`` samples."""
    after = w[peak:peak + reach]
    below = np.flatnonzero(after < 0)
    low = after < 0.25 * after[0]
    trough = np.flatnonzero(low[1:-1] & (after[1:-1] <= after[:-2]) & (after[1:-1] < after[2:]))
    ends = ([_crossing(w, peak + int(below[0]))] if len(below) else []) + \
        ([float(peak + 1 + trough[0])] if len(trough) else [])
    return min(ends) if ends else float(peak + np.argmin(after[:reach // 2 + 1]))


def _smooth(w: np.ndarray, rate_hz: float) -> np.ndarray:
    """The sagittal rate low-passed at 15 Hz (the events' timing, not the impacts')."""
    return lowpass(w, rate_hz, min(15.0, 0.4 * rate_hz))


#: The longest stance (s) between two swings that is given a rest of its own: longer, it is a
#: pause whose rests the fixed thresholds find, or no walk.
MAX_STANCE_S = 2.0


def swing_peaks(w: np.ndarray, rate_hz: float) -> np.ndarray:
    """The swings' peaks of a sagittal rate ``w`` (positive in the swing): its peaks beyond a
    share of the walk's typical one (:data:`SHANK_PEAK_SHARE` of the median of those beyond
    :data:`MIN_SWING_RATE`, at least :data:`MIN_SHANK_PEAK`), one a stride at most
    (:data:`STRIDE_SHARE`)."""
    from scipy.signal import find_peaks

    peaks, props = find_peaks(w, height=MIN_SHANK_PEAK, distance=max(1, int(0.4 * rate_hz)))
    strong = props["peak_heights"][props["peak_heights"] >= MIN_SWING_RATE]
    if not len(strong):
        return np.zeros(0, dtype=int)
    least = max(MIN_SHANK_PEAK, SHANK_PEAK_SHARE * float(np.median(strong)))
    stride = stride_period(w, rate_hz)
    if stride is not None:  # one peak a stride: a foot's other lobes are not swings
        peaks, _ = find_peaks(w, height=least, distance=max(1, int(STRIDE_SHARE * stride)))
    return peaks[(peaks > 0) & (w[peaks] >= least)]


#: Where a stride's period is looked for (s): a run's to a slow walk's.
STRIDE_RANGE_S = (0.5, 2.5)


def stride_period(w: np.ndarray, rate_hz: float) -> float | None:
    """The stride's period (samples): the lag within :data:`STRIDE_RANGE_S` at which the sagittal
    rate ``w`` correlates best with itself (the whole stride's pattern repeats, where a foot's
    lobes within a stride do not); None where no lag there correlates at all."""
    x = np.nan_to_num(w - np.nanmean(w))
    n = len(x)
    lo, hi = (int(round(v * rate_hz)) for v in STRIDE_RANGE_S)
    if n < 2 * lo or hi <= lo:
        return None
    spectrum = np.fft.rfft(x, 2 * n)
    r = np.fft.irfft(spectrum * np.conj(spectrum))[:n] / np.maximum(n - np.arange(n), 1)
    hi = min(hi, n // 2)
    if hi <= lo or r[0] <= 0:
        return None
    k = lo + int(np.argmax(r[lo:hi]))
    return float(k) if r[k] > 0.0 else None


def stance_rests(gyr: np.ndarray, acc: np.ndarray, rate_hz: float, rests: np.ndarray,
                 w: np.ndarray) -> np.ndarray:
    """``rests`` with, for each stance between two swings (:func:`swing_peaks` of ``w``, at most
    :data:`MAX_STANCE_S` apart) within a stretch of more than one and a half strides without
    a rest, its stillest :data:`REST_WINDOW_S` window in its middle three fifths: the
    smallest ``|w|^2 / REST_GYRO^2 + (|a| - g)^2 / REST_ACC^2`` over the window (the energy
    of Skog et al. 2010's SHOE detector, the thresholds its scales). A fast walk's foot
    never rests by the fixed thresholds (at 1.9 m/s its stillest 50 ms turn at 0.43-0.92
    rad/s), but each of its stances has a stillest moment, the zero-velocity update's place
    (Rampp et al. 2015's mid-stance: the minimum of the gyroscope's energy between two
    swings). The heel strike's impact keeps the window off the contact (the specific force's
    term), and so the search needs no sign of ``w``: on a run the fastest rotation is the
    push-off, not the swing (qmt's run: 11-12 against 8-9 rad/s), and the peaks then bound a
    swing and a stance, not a stance alone."""
    n = max(1, int(round(REST_WINDOW_S * rate_hz)))
    energy = (np.linalg.norm(np.nan_to_num(gyr), axis=1) / REST_GYRO) ** 2 + (
        (np.linalg.norm(np.nan_to_num(acc), axis=1) - G) / REST_ACC) ** 2
    window = np.convolve(energy, np.ones(n) / n, mode="valid")  # window k: samples k..k+n-1
    added = []
    stride = stride_period(w, rate_hz)
    for a, b in _stances(swing_peaks(w, rate_hz), rests, MAX_STANCE_S * rate_hz, stride):
        lo, hi = a + (b - a) // 5, b - (b - a) // 5 - n + 1  # the peaks' lobes left out
        if hi > lo:
            k = lo + int(np.argmin(window[lo:hi]))
            added.append((k, k + n))
    if not added:
        return rests
    return np.array(sorted([*map(tuple, rests), *added]), dtype=int).reshape(-1, 2)


def _stances(peaks: np.ndarray, rests: np.ndarray, longest: float,
             stride: float | None) -> list[tuple[int, int]]:
    """The sample ranges between consecutive swing ``peaks`` that hold no rest, at most
    ``longest`` samples long, within a stretch between two rests that lasts more than one and a
    half ``stride`` (a walk whose stances the fixed thresholds do not find; a stretch of one
    stride between two rests is a walk's, whatever its peaks)."""
    if stride is None:
        return []
    ends = [0, *(int(v) for r in rests for v in r), 1 << 62]
    gaps = [(a, b) for a, b in zip(ends[0::2], ends[1::2], strict=False) if b - a > 1.5 * stride]
    return [(int(a), int(b)) for a, b in zip(peaks[:-1], peaks[1:], strict=True)
            if b - a <= longest and any(g0 <= a and b <= g1 for g0, g1 in gaps)]


#: The segments whose sensor gives events: a foot's rests in stance, a shank's swing peaks.
SEGMENTS = ("foot", "shank")


def gait_events(gyr: np.ndarray, acc: np.ndarray, rate_hz: float,
                segment: str = "foot") -> GaitEvents:
    """Rests, swings and contacts of a ``segment`` (:data:`SEGMENTS`) sensor (module
    docstring), event times in fractional samples."""
    if segment not in SEGMENTS:
        raise ValueError(f"segment {segment!r}: expected one of {SEGMENTS}")
    rests = rest_periods(gyr, acc, rate_hz)
    if segment == "shank":
        w, axis = sagittal_rate(gyr, np.zeros((0, 2), int), rest_vertical(acc, rests))
        swing, ic, fc = _shank_events(_smooth(w, rate_hz), rate_hz)
        return GaitEvents(rests, np.asarray(swing, int), ic, fc, axis)
    up = rest_vertical(acc, rests)
    first, _ = sagittal_rate(gyr, np.zeros((0, 2), int), up)  # signed by the fastest rotation
    rests = stance_rests(gyr, acc, rate_hz, rests, _smooth(first, rate_hz))
    w, axis = sagittal_rate(gyr, rests, up)
    w = _smooth(w, rate_hz)
    swing, ic, fc = [], [], []
    path = None  # the foot's trajectory, once a weak swing asks for it
    for (_, a), (b, _) in zip(rests[:-1], rests[1:], strict=True):
        if b - a < 3:
            continue
        start, stop, turn = _swing_lobe(w, a, b)
        peak = start + int(np.argmax(w[start:stop]))
        if turn <= 0 or start == a or stop == b:
            continue
        if w[peak] < MIN_SWING_RATE:
            if path is None:
                path = foot_trajectory(gyr, acc, rate_hz, rests)
            step = path.position[b, :2] - path.position[a - 1, :2]
            if not np.linalg.norm(step) >= MIN_STEP_M:
                continue
        swing.append(peak)
        fc.append(float(a + np.argmin(w[a:start])))
        ic.append(_crossing(w, stop))
    return GaitEvents(rests, np.asarray(swing, int), np.asarray(ic, float), np.asarray(fc, float),
                      axis, path)
