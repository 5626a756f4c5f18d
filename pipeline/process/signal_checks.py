"""A sensor's own signals checked (the ``sensor`` scope of
:data:`pipeline.process.sensor_checks.CHECKS`): dead channels, dropouts, saturation, and whether
it moves with its segment. Each check takes the sensor's name, its own signals (its missing
samples NaN) and the recording's :class:`~pipeline.process.check_context.CheckContext`, and
returns a :class:`~pipeline.process.findings.Finding` or None; :func:`saturation` and
:func:`speed_ratio` are the statistics two of them judge (shared with
``scripts/bench_false_alarms.py``, which measures them on faultless recordings).
"""

from __future__ import annotations

import numpy as np

from pipeline.io.gaps import true_runs
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.process.check_context import CheckContext
from pipeline.process.findings import Action, Finding

__all__ = ["FOOT_QUANTILE", "MAX_HUMAN_GYRO_DPS", "MAX_MISSING", "MAX_SATURATED",
           "MIN_SPEED_RATIO", "MOVING_SPEED", "PLATEAU_S", "PLATEAU_SAMPLES", "PLATEAU_TOL",
           "dead_channels", "dropout", "moves_with_segment", "saturated", "saturation",
           "speed_ratio"]

#: A plateau: at least this many consecutive samples, lasting at least PLATEAU_S, within
#: PLATEAU_TOL (relative) of a channel's largest magnitude. A smooth peak of human motion stays
#: within 0.1 % of its top for ~1.4 % of its period (14 ms of a 1 s wave); at 0.5 % (~3 %) the
#: rounded tops of real shank gyroscopes (S02: ~300 deg/s, 0.6 % over 40 ms) and of the simulated
#: walk's shank accelerometer (2.3 g, 0.2 % over 30 ms) passed for a range's limit.
PLATEAU_SAMPLES = 3
PLATEAU_S = 0.03
PLATEAU_TOL = 0.001
#: Angular speed (deg/s) beyond any human segment's in walking or running (feet peak at ~800-1000).
MAX_HUMAN_GYRO_DPS = 1500.0
#: Share of saturated samples beyond which a sensor is excluded.
MAX_SATURATED = 0.01
#: A sensor missing this share of the recording or more is excluded (too little of it to
#: calibrate or check); less, it is kept and blank where it is missing.
MAX_MISSING = 0.9
#: A sensor turning slower than this share of its neighbours' median speed does not follow a
#: segment.
MIN_SPEED_RATIO = 0.15
#: Neighbours' median angular speed (rad/s) from which they are moving.
MOVING_SPEED = 0.3
#: A foot's speed is taken at this quantile: it rests flat on the floor through mid-stance while
#: its shank turns over it (median foot / shank speed with a 2 s standing start: S02 0.20-0.21,
#: the simulated walk 0.10-0.18, the x-IMU3 walk 0.37-0.42; the foot's upper quartile instead:
#: 2.4-3.2 on all three), where a fallen sensor rests at every quantile.
FOOT_QUANTILE = 0.75


def _constant_axes(x: np.ndarray | None) -> list[str]:
    if x is None:
        return []
    finite = x[np.all(np.isfinite(x), axis=1)]
    if len(finite) < 2:
        return list("xyz")
    return [a for a, k in zip("xyz", range(3), strict=True) if np.ptp(finite[:, k]) == 0.0]


def dead_channels(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
    for field, what in (("gyr", "gyroscope"), ("acc", "accelerometer")):
        axes = _constant_axes(getattr(s, field))
        if axes:
            return Finding(name, "dead", Action.EXCLUDED,
                           f"{what} axes {''.join(axes)} never change")
    axes = _constant_axes(s.mag)
    if axes:
        return Finding(name, "dead", Action.MAGNETOMETER_NOT_USED,
                       f"magnetometer axes {''.join(axes)} never change")
    return None


def _plateau_share(x: np.ndarray, min_peak: float, rate_hz: float) -> tuple[float, float]:
    """Share of samples in plateaus at a channel's largest magnitude (:data:`PLATEAU_TOL`;
    channels peaking below ``min_peak`` are not at a range's limit), and the highest plateau's
    level (0 without one)."""
    least = max(PLATEAU_SAMPLES, int(np.ceil(PLATEAU_S * rate_hz)))
    held = np.zeros(len(x), dtype=bool)
    level = 0.0
    for k in range(x.shape[1]):
        v = np.abs(x[:, k])
        peak = np.nanmax(v)
        if not peak >= min_peak:
            continue
        near = np.nan_to_num(v) >= (1.0 - PLATEAU_TOL) * peak
        for a, b in true_runs(near):
            if b - a >= least:
                held[a:b] = True
                level = max(level, float(peak))
    return float(np.mean(held)), level


def saturation(s: SensorSignals, rate_hz: float) -> tuple[float, str] | None:
    """The largest share of ``s``'s samples beyond a human segment's speed or held at a
    range's limit, and what it is; None without raw signals or any such sample."""
    if s.gyr is None or s.acc is None:
        return None
    speed = np.linalg.norm(np.nan_to_num(s.gyr), axis=1)
    fast = float(np.mean(speed > np.radians(MAX_HUMAN_GYRO_DPS)))
    g_share, g_level = _plateau_share(s.gyr, np.radians(250.0), rate_hz)  # smallest range
    a_share, a_level = _plateau_share(s.acc, 2 * 9.81, rate_hz)  # 2 g: the smallest range
    found = []
    if fast > 0:
        found.append((fast, f"gyroscope beyond a human segment's speed ({MAX_HUMAN_GYRO_DPS:.0f} "
                            f"deg/s, peak {np.degrees(speed.max()):.0f})"))
    if g_share > 0:
        found.append((g_share, f"gyroscope held at {np.degrees(g_level):.0f} deg/s (its range's "
                               "limit?)"))
    if a_share > 0:
        found.append((a_share, f"accelerometer held at {a_level / 9.81:.1f} g (its range's "
                               "limit?)"))
    return max(found) if found else None


def saturated(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
    found = saturation(s, ctx.rec.rate_hz)
    if found is None:
        return None
    share, what = found
    action = Action.EXCLUDED if share > MAX_SATURATED else Action.NOTED
    return Finding(name, "saturation", action, f"{what} in {100 * share:.2f}% of the samples")


def _speed(s: SensorSignals, quantile: float = 0.5) -> float:
    """The angular speed (rad/s) at ``quantile``, the median by default: a burst of a faulty
    neighbour does not move it."""
    speed = np.linalg.norm(s.gyr, axis=1)
    ok = np.isfinite(speed)
    return float(np.quantile(speed[ok], quantile)) if ok.any() else 0.0


_CHAIN = ("pelvis", "femur", "tibia", "foot")


def _neighbours(name: str, rec: Recording) -> list[str]:
    """The sensors of the segments next to ``name``'s along its leg (the pelvis for both legs)."""
    seg = {n: SENSOR_TO_SEGMENT.get(n) for n in rec.sensors}
    mine = seg.get(name)
    if mine is None or mine == "torso":
        return []
    side, kind = (mine.split("_", 1) if "_" in mine else ("", mine))
    k = _CHAIN.index(kind)
    near = [c for c in (_CHAIN[k - 1] if k > 0 else None, _CHAIN[k + 1] if k < 3 else None) if c]
    want = {c if c == "pelvis" else f"{s}_{c}" for c in near
            for s in ((side,) if side else ("right", "left"))}
    return [n for n, g in seg.items() if g in want and rec.sensors[n].gyr is not None]


def speed_ratio(name: str, ctx: CheckContext) -> tuple[float, float, list[str]] | None:
    """Sensor ``name``'s angular speed (median; a foot's upper quartile) over its slowest
    neighbour's, that speed and the neighbours; None without a gyroscope or moving neighbours
    (a still neighbour: a still segment is normal)."""
    if ctx.rec.sensors[name].gyr is None:
        return None
    near = _neighbours(name, ctx.rec)
    speeds = [_speed(ctx.own(n)) for n in near]
    if not speeds or min(speeds) < MOVING_SPEED:
        return None
    foot = SENSOR_TO_SEGMENT.get(name, "").endswith("foot")
    mine = _speed(ctx.own(name), FOOT_QUANTILE if foot else 0.5)
    return mine / min(speeds), min(speeds), near


def moves_with_segment(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
    found = speed_ratio(name, ctx)
    if found is None or found[0] >= MIN_SPEED_RATIO:
        return None
    ratio, slowest, near = found
    foot = SENSOR_TO_SEGMENT.get(name, "").endswith("foot")
    return Finding(name, "moves with its segment", _action_on_stillness(near),
                   f"it turns at {np.degrees(ratio * slowest):.0f} deg/s "
                   f"({'upper quartile' if foot else 'median'}) while its neighbours "
                   f"({', '.join(near)}) turn at {np.degrees(slowest):.0f} or more: it does "
                   "not follow a segment (loose or fallen off?)")


def _action_on_stillness(neighbours: list[str]) -> Action:
    """Excluded when two or more neighbours move around it; with one neighbour (a foot) only
    noted: a foot rests on the floor while its shank turns (squats, sit-to-stand)."""
    return Action.EXCLUDED if len(neighbours) >= 2 else Action.NOTED


def dropout(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
    spans = ctx.missing.spans.get(name)
    if not spans:
        return None
    rec = ctx.rec
    share = sum(b - a for a, b in spans) / rec.n_samples
    if share >= MAX_MISSING:
        return Finding(name, "dropout", Action.EXCLUDED,
                       f"missing {100 * share:.0f}% of the recording")
    return Finding(name, "dropout", Action.NOTED,
                   f"missing at {ctx.missing.describe(name, rec.time)} ({100 * share:.1f}% of "
                   "the recording): not bridged, what needs it is blank there")
