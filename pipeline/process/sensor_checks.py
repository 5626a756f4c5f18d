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

The signal checks (``dead``, ``dropout``, ``saturation``, ``moves with its segment``) are
:mod:`pipeline.process.signal_checks`'s.

* ``dead``: a gyroscope or accelerometer axis that never changes (all zero, or frozen at one
  value) cannot give an orientation: the sensor is **excluded** (its joints are not written). A
  magnetometer that never changes is **not used** (the sensor is filtered 6-D, its heading from
  the joints).
* ``dropout``: a sensor missing samples for longer than
  :data:`~pipeline.io.gaps.DEFAULT_MAX_GAP_S` (a radio dropout, a late start or an early end;
  shorter gaps the readers fill): **noted** with its spans, the sensor kept and what needs it
  blank there (:mod:`pipeline.process.missing`: never bridged); missing ``MAX_MISSING`` of
  the recording or more: **excluded**.
* ``saturation``: samples held at the range's limit (plateaus: runs of at least
  ``PLATEAU_SAMPLES`` samples and ``PLATEAU_S`` within ``PLATEAU_TOL`` of the
  largest magnitude) or an angular speed no human segment reaches
  (``MAX_HUMAN_GYRO_DPS``): the integrated orientation is wrong from the first such sample
  on. Gyroscope: **excluded** when more than ``MAX_SATURATED`` of the samples are, else
  **noted**; accelerometer (heel strikes clip a +-8 g range for a sample or two): **noted**
  unless more than ``MAX_SATURATED``, then excluded.
* ``orientations`` (:func:`~pipeline.process.recording_checks.turn_agreement`): a sensor whose
  own orientations do not turn as its gyroscope does (a wrong component order, direction or
  handedness of that sensor alone; the whole recording's order is refused first): its
  orientation comes **from its raw signals** (its world then its own, aligned by the joints).
* ``moves with its segment``: a sensor whose median angular speed (a foot's: its upper quartile,
  ``FOOT_QUANTILE``, as a walking foot rests through mid-stance) stays below
  ``MIN_SPEED_RATIO`` of the slowest of its neighbours' while all of them move (a sensor that
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

from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.check_context import CheckContext
from pipeline.process.findings import Action, Finding, apply_findings
from pipeline.process.recording_checks import (
    MIN_TURN_COSINE,
    check_quaternion_order,
    check_units,
    turn_agreement,
)
from pipeline.process.signal_checks import (
    dead_channels,
    dropout,
    moves_with_segment,
    saturated,
)
from pipeline.process.slip import slip_step, unchecked
from pipeline.process.swap import crossing_evidence, swap_evidence

__all__ = ["CHECKS", "SCOPES", "SWAPPED_BACK", "Action", "Check", "Finding", "check_sensors",
           "run_checks"]


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
    "dead": Check("sensor", dead_channels),
    "dropout": Check("sensor", dropout),
    "saturation": Check("sensor", saturated),
    "orientations": Check("sensor", _orientations),
    "moves with its segment": Check("sensor", moves_with_segment),
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
