"""The sensor check of :func:`pipeline.process.process_recording`: each sensor's raw signals
checked before anything is estimated, every fault named and handled.

The checks are a registry (:data:`CHECKS`: name -> a :class:`Check`, its scope and its function);
adding one is one function (in a module of its own where it is more than a few lines) and one
entry. A check's scope says what it sees: ``recording`` (the whole recording: it refuses it,
:mod:`pipeline.process.recording_checks`), ``sensor`` (one sensor's signals, in the recording's
:class:`~pipeline.process.check_context.CheckContext`; returns a
:class:`~pipeline.process.findings.Finding` or None; a sensor's checks stop at its first
exclusion) and ``legs`` (the leg sensors that passed their own checks, taken together: their
findings and the recording read back). Every finding's action is one of
:class:`~pipeline.process.findings.Action`, applied in one place
(:func:`~pipeline.process.findings.apply_findings`). What each finds and what is done about it:

* ``units``, ``quaternion order`` (:mod:`pipeline.process.recording_checks`): gyroscopes not in
  rad/s, quaternions scalar last: the recording is **refused**.

* ``dead``: a gyroscope or accelerometer axis that never changes (all zero, or frozen at one
  value) cannot give an orientation: the sensor is **excluded** (its joints are not written). A
  magnetometer that never changes is **not used** (the sensor is filtered 6-D, its heading from
  the joints).
* ``dropout``: a sensor missing samples for longer than
  :data:`~pipeline.io.gaps.DEFAULT_MAX_GAP_S` (a radio dropout, a late start or an early end;
  shorter gaps the readers fill): **noted** with its spans, the sensor kept and what needs it
  blank there (:mod:`pipeline.process.missing`: never bridged); missing :data:`MAX_MISSING` of
  the recording or more: **excluded**.
* ``saturation``: samples held at the range's limit (plateaus: runs of at least
  :data:`PLATEAU_SAMPLES` samples and :data:`PLATEAU_S` within :data:`PLATEAU_TOL` of the
  largest magnitude) or an angular speed no human segment reaches
  (:data:`MAX_HUMAN_GYRO_DPS`): the integrated orientation is wrong from the first such sample
  on. Gyroscope: **excluded** when more than :data:`MAX_SATURATED` of the samples are, else
  **noted**; accelerometer (heel strikes clip a +-8 g range for a sample or two): **noted**
  unless more than :data:`MAX_SATURATED`, then excluded.
* ``orientations`` (:func:`~pipeline.process.recording_checks.turn_agreement`): a sensor whose
  own orientations do not turn as its gyroscope does (a wrong component order, direction or
  handedness of that sensor alone; the whole recording's order is refused first): its
  orientation comes **from its raw signals** (its world then its own, aligned by the joints).
* ``moves with its segment``: a sensor whose median angular speed (a foot's: its upper quartile,
  :data:`FOOT_QUANTILE`, as a walking foot rests through mid-stance) stays below
  :data:`MIN_SPEED_RATIO` of the slowest of its neighbours' while all of them move (a sensor that
  fell off): **excluded** when two or more neighbours move around it, **noted** with one (a foot
  stays on the floor while its shank turns). A still neighbour means a still segment is
  plausible (a thigh on a chair while the shank swings; a pelvis while one hip flexes).
* ``crossed``, ``swapped`` (:mod:`pipeline.process.swap`, on sensors that passed the others): the
  shanks' or feet's sensors exchanged between the legs (a stride's rhythm), then a leg's thigh and
  shank (its ankle fits the shank's sensor): **read as swapped back** (a flag); an exchange whose
  thighs do not tell which: the four **excluded**.

* ``slipped`` (:mod:`pipeline.process.slip`): a leg or pelvis sensor whose own view of its
  segment (the flexion axis or the pelvis's once-a-stride rocking axis, gravity at mid-stance)
  turns between the strides before and after some stride by more than
  :data:`~pipeline.process.slip.SLIP_DEG`: it may have slipped on its segment, its placement
  wrong from then on: **noted** (a flag, the sensor kept); a leg sensor alone on its leg whose
  flexion axis turned beyond :data:`~pipeline.process.slip.CERTAIN_SLIP_DEG` is **excluded**. The
  pelvis is never excluded: nothing else turns with its rocking to tell a slip from a walk that
  starts, stops or turns (which step it by 8-11 deg on S02 and 20-21 deg on other labs' walkways).
  Checked in walking (four strides or more on its leg); a leg that walked fewer has its sensors
  **listed** as not checked (not a flag), and so has a sensor whose step beyond the limit the leg's
  other sensors and the other leg's share (the movement changed: turns on the spot, shuffles; the
  x-IMU3 walk's sensors step 20-86 deg so).

* ``read``: what the reader of a sensor's own file repaired or noticed (dropped samples or
  packets filled, an irregular clock kept; ``Recording.sensor_notes``): **listed** in the sensor
  table (the run's notes say it too: not a flag, ``--strict`` does not stop on it).

Magnetometer trust is :mod:`pipeline.calibration.magnetometer`'s; the sensor table shows both.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pipeline.io.gaps import true_runs
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.process.check_context import CheckContext
from pipeline.process.findings import Action, Finding, apply_findings
from pipeline.process.recording_checks import (
    MIN_TURN_COSINE,
    check_quaternion_order,
    check_units,
    turn_agreement,
)
from pipeline.process.slip import slip_step, unchecked
from pipeline.process.swap import crossing_evidence, swap_evidence

__all__ = ["CHECKS", "FOOT_QUANTILE", "MAX_HUMAN_GYRO_DPS", "MAX_MISSING", "MAX_SATURATED",
           "MIN_SPEED_RATIO", "PLATEAU_SAMPLES", "SCOPES", "SWAPPED_BACK", "Action", "Check",
           "Finding", "check_sensors", "run_checks"]

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


def _dead(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
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


def _saturation(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
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


def _moves_with_segment(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
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


def _dropout(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
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


def _repaired_on_reading(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
    rec = ctx.rec
    said = rec.sensor_notes.get(name, ())
    if not said:
        return None
    return Finding(name, "read", Action.LISTED, "its file's reader: " + "; ".join(
        n.split(": ", 1)[1] if rec.source and n.startswith(str(rec.source)) else n
        for n in said))


def _orientations(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
    agreement = turn_agreement(s, ctx.rec.rate_hz)
    if agreement is None or agreement >= MIN_TURN_COSINE:
        return None
    return Finding(name, "orientations", Action.ORIENTATION_FROM_SIGNALS,
                   f"its orientations do not turn as its gyroscope does (median cosine "
                   f"{agreement:.2f} between their rates; real sensors' 0.995-0.999): their "
                   "component order (w, x, y, z), direction (sensor -> world) or handedness is "
                   "wrong")


def _slipped(name: str, s: SensorSignals, ctx: CheckContext) -> Finding | None:
    step = slip_step(name, ctx)
    if step is None:
        why = unchecked(name, ctx)
        return None if why is None else Finding(name, "slipped", Action.LISTED, why)
    if step.inconclusive:
        return Finding(name, "slipped", Action.LISTED, step.evidence())
    if step.slipped:
        return Finding(name, "slipped", Action.EXCLUDED if step.certain else Action.NOTED,
                       step.evidence())
    return None


def _crossed(ctx: CheckContext, faulty: set[str]) -> tuple[list[Finding], Recording]:
    """The shanks' or the feet's sensors exchanged between the legs
    (:func:`~pipeline.process.swap.crossing_evidence`): read back, or the four excluded where
    the thighs do not tell which."""
    crossing = crossing_evidence(ctx, faulty)
    if crossing is None or not crossing.crossed:
        return [], ctx.rec
    action = Action.SWAPPED_BACK if crossing.exchanged else Action.EXCLUDED
    found = [Finding(n, "crossed", action, crossing.evidence()) for n in crossing.sensors]
    return found, crossing.read_back(ctx.rec)


def _swapped(ctx: CheckContext, faulty: set[str]) -> tuple[list[Finding], Recording]:
    """A leg's thigh and shank sensors swapped (:func:`~pipeline.process.swap.swap_evidence`),
    on the legs whose three sensors passed: read back."""
    rec, found = ctx.rec, []
    for side in ("right", "left"):
        ev = swap_evidence(side, rec, faulty)
        if ev is not None and ev.swapped:
            found.append(Finding(ev.shank, "swapped", Action.SWAPPED_BACK, ev.evidence()))
            rec = ev.read_back(rec)
    return found, rec


@dataclass(frozen=True)
class Check:
    """A check's ``scope`` (:data:`SCOPES`) and its function: ``recording``: of the context,
    refusing with an :class:`~pipeline.errors.InputError`; ``sensor``: of (sensor name, its
    signals, the context), a finding or None; ``legs``: of (the context, the sensors already
    found faulty), the findings and the recording read back."""

    scope: str
    run: Callable


#: The scopes, in the order the checks run.
SCOPES = ("recording", "sensor", "legs")
#: Check name -> :class:`Check` (module docstring); within a scope in this order.
CHECKS: dict[str, Check] = {
    "units": Check("recording", lambda ctx: check_units(ctx.rec)),
    "quaternion order": Check("recording", lambda ctx: check_quaternion_order(ctx.rec)),
    "read": Check("sensor", _repaired_on_reading),  # first: an exclusion stops the sensor's
    "dead": Check("sensor", _dead),
    "dropout": Check("sensor", _dropout),
    "saturation": Check("sensor", _saturation),
    "orientations": Check("sensor", _orientations),
    "moves with its segment": Check("sensor", _moves_with_segment),
    "slipped": Check("sensor", _slipped),
    "crossed": Check("legs", _crossed),  # first: ``swapped`` needs each leg's own sensors
    "swapped": Check("legs", _swapped),
}
#: Kept for the names' users: the action of sensors read under their right names.
SWAPPED_BACK = Action.SWAPPED_BACK


def check_sensors(rec: Recording) -> tuple[Recording, list[Finding]]:
    """Every check of :data:`CHECKS` on ``rec`` as read (:func:`run_checks`; its missing samples
    bridged, :meth:`CheckContext.of_recording`): the checked recording and the findings."""
    ctx, findings = run_checks(CheckContext.of_recording(rec))
    return ctx.rec, findings


def run_checks(ctx: CheckContext) -> tuple[CheckContext, list[Finding]]:
    """Every check of :data:`CHECKS` by scope (module docstring) on the context's recording;
    the context of the checked recording (the excluded sensors left out, the unused
    magnetometers removed, the swapped sensors read back) and the findings."""
    of = {scope: [c for c in CHECKS.values() if c.scope == scope] for scope in SCOPES}
    for check in of["recording"]:
        check.run(ctx)
    findings: list[Finding] = []
    for name in ctx.rec.sensors:
        s = ctx.own(name)  # its missing samples NaN: judged on what it has
        for check in of["sensor"]:
            f = check.run(name, s, ctx)
            if f is not None:
                findings.append(f)
                if f.action == Action.EXCLUDED:  # one reason is enough
                    break
    ctx = ctx.of(apply_findings(ctx.rec, findings))  # each sensor's own faults first
    faulty = {f.sensor for f in findings
              if f.flagged and f.action != Action.MAGNETOMETER_NOT_USED}
    for check in of["legs"]:
        found, rec = check.run(ctx, faulty)
        findings += found
        ctx = ctx.of(apply_findings(rec, found))
    return ctx, findings
