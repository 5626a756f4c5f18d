"""The sensor check of :func:`pipeline.process.process_recording`: each sensor's raw signals
checked before anything is estimated, every fault named and handled.

The checks are a registry (:data:`CHECKS`: name -> a function of one sensor's signals returning a
:class:`Finding` or None); adding one is one function and one entry. What each finds and what is
done about it:

* ``dead``: a gyroscope or accelerometer axis that never changes (all zero, or frozen at one
  value) cannot give an orientation: the sensor is **excluded** (its joints are not written). A
  magnetometer that never changes is **not used** (the sensor is filtered 6-D, its heading from
  the joints).
* ``dropout``: a gyroscope or accelerometer with missing samples (NaN) for longer than
  :data:`~pipeline.io.gaps.DEFAULT_MAX_GAP_S` (a radio dropout; shorter gaps the readers fill):
  **excluded**.
* ``saturation``: samples held at the range's limit (plateaus: runs of at least
  :data:`PLATEAU_SAMPLES` samples and :data:`PLATEAU_S` within :data:`PLATEAU_TOL` of the
  largest magnitude) or an angular speed no human segment reaches
  (:data:`MAX_HUMAN_GYRO_DPS`): the integrated orientation is wrong from the first such sample
  on. Gyroscope: **excluded** when more than :data:`MAX_SATURATED` of the samples are, else
  **noted**; accelerometer (heel strikes clip a +-8 g range for a sample or two): **noted**
  unless more than :data:`MAX_SATURATED`, then excluded.
* ``units`` (:func:`check_units`, the whole recording): the gyroscopes against the
  accelerometers, which show each sensor's inclination whatever the unit: the rate at which
  gravity's direction turns in the sensor frame, ``|du/dt| = |w x u|`` (``u = a/|a|``
  low-passed), is compared with the gyroscope's own ``|w x u|``. The ratio is 1 for rad/s and
  57.3 for deg/s given as rad/s, whatever the speed (slow trials too, where the magnitude test of
  :func:`pipeline.io.checks.check_gyro_units` passes deg/s). Linear accelerations turn ``a`` too:
  a sensor's ratio ranges 0.01-1.7 (measured: a still leg's, a foot's in gait), the median over
  a recording's sensors 0.33 (x-IMU3 walk), 0.65 (S02) and 0.75-1.0 (simulated gait, supine,
  seated), 57 times that with the wrong unit: a median outside :data:`UNIT_RATIO` is
  **refused**.
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

* ``quaternion order`` (:func:`check_quaternion_order`, the whole recording, where it has
  orientations and accelerometers): orientations that keep gravity along a world axis far better
  read as x, y, z, w than as w, x, y, z are **refused** (median tilt: S02's vendor quaternions
  0.2-1.0 deg, 3.4-40 deg read the other way; the simulator's 0.3-8 deg, 7-88 deg).

* ``slipped`` (:mod:`pipeline.process.slip`): a leg or pelvis sensor whose own view of its
  segment (the flexion axis or the pelvis's once-a-stride rocking axis, gravity at mid-stance)
  turns between the strides before and after some stride by more than
  :data:`~pipeline.process.slip.SLIP_DEG`: it slipped on its segment, its placement is wrong from
  then on: **excluded**. Checked in walking (four strides or more on its leg); a leg
  that walked fewer has its sensors **listed** as not checked (not a flag), and so has a sensor
  whose step beyond the limit the leg's other sensors and the other leg's share (the movement
  changed: turns on the spot, shuffles; the x-IMU3 walk's sensors step 20-86 deg so).

* ``read``: what the reader of a sensor's own file repaired or noticed (dropped samples or
  packets filled, an irregular clock kept; ``Recording.sensor_notes``): **listed** in the sensor
  table (the run's notes say it too: not a flag, ``--strict`` does not stop on it).

Magnetometer trust is :mod:`pipeline.calibration.magnetometer`'s; the sensor table shows both.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.filtering import lowpass
from pipeline.io.gaps import DEFAULT_MAX_GAP_S, true_runs
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.process.signals import gravity_in_world
from pipeline.process.slip import slip_step, unchecked
from pipeline.process.swap import crossing_evidence, swap_evidence

__all__ = ["CHECKS", "FOOT_QUANTILE", "MAX_HUMAN_GYRO_DPS", "MAX_SATURATED", "MIN_SPEED_RATIO",
           "ORDER_RATIO", "PLATEAU_SAMPLES", "Finding", "check_quaternion_order", "check_sensors",
           "check_units", "gyro_unit_ratio"]

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
#: The accepted range of the gyroscope's to the accelerometer's turn of gravity.
UNIT_RATIO = (0.1, 10.0)


@dataclass(frozen=True)
class Finding:
    """One fault of one sensor: ``check`` (a :data:`CHECKS` name), ``action`` (``'excluded'``,
    ``'magnetometer not used'``, ``'read as swapped back'``, ``'noted'`` or ``'listed'``) and the
    ``evidence`` a summary prints. Every action but ``'listed'`` is also a flag (:attr:`flagged`);
    a listed finding is the sensor table's only (the reader's repairs, among the run's notes)."""

    sensor: str
    check: str
    action: str
    evidence: str

    @property
    def flagged(self) -> bool:
        return self.action != "listed"

    def line(self) -> str:
        return f"sensor {self.sensor}: {self.check}: {self.evidence} ({self.action})"


def _constant_axes(x: np.ndarray | None) -> list[str]:
    if x is None:
        return []
    finite = x[np.all(np.isfinite(x), axis=1)]
    if len(finite) < 2:
        return list("xyz")
    return [a for a, k in zip("xyz", range(3), strict=True) if np.ptp(finite[:, k]) == 0.0]


def _dead(name: str, s: SensorSignals, rec: Recording) -> Finding | None:
    for field, what in (("gyr", "gyroscope"), ("acc", "accelerometer")):
        axes = _constant_axes(getattr(s, field))
        if axes:
            return Finding(name, "dead", "excluded", f"{what} axes {''.join(axes)} never change")
    axes = _constant_axes(s.mag)
    if axes:
        return Finding(name, "dead", "magnetometer not used",
                       f"magnetometer axes {''.join(axes)} never change")  # fmt: skip
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


def _saturation(name: str, s: SensorSignals, rec: Recording) -> Finding | None:
    if s.gyr is None or s.acc is None:
        return None
    speed = np.linalg.norm(np.nan_to_num(s.gyr), axis=1)
    fast = float(np.mean(speed > np.radians(MAX_HUMAN_GYRO_DPS)))
    g_share, g_level = _plateau_share(s.gyr, np.radians(250.0), rec.rate_hz)  # smallest range
    a_share, a_level = _plateau_share(s.acc, 2 * 9.81, rec.rate_hz)  # 2 g: the smallest range
    found = []
    if fast > 0:
        found.append((fast, f"gyroscope beyond a human segment's speed ({MAX_HUMAN_GYRO_DPS:.0f} "
                            f"deg/s, peak {np.degrees(speed.max()):.0f})"))  # fmt: skip
    if g_share > 0:
        found.append((g_share, f"gyroscope held at {np.degrees(g_level):.0f} deg/s (its range's "
                               "limit?)"))  # fmt: skip
    if a_share > 0:
        found.append((a_share, f"accelerometer held at {a_level / 9.81:.1f} g (its range's "
                               "limit?)"))  # fmt: skip
    if not found:
        return None
    share, what = max(found)
    action = "excluded" if share > MAX_SATURATED else "noted"
    return Finding(name, "saturation", action, f"{what} in {100 * share:.2f}% of the samples")


def _turn_rates(s: SensorSignals, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """``(|du/dt|, |w x u|)`` per sample, ``u`` gravity's direction in the sensor frame."""
    cut = min(2.0, 0.2 * rate_hz)
    a = lowpass(np.nan_to_num(s.acc), rate_hz, cut)
    u = a / np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-9)
    du = np.linalg.norm(np.gradient(u, axis=0), axis=1) * rate_hz
    w = lowpass(np.nan_to_num(s.gyr), rate_hz, cut)
    return du, np.linalg.norm(np.cross(w, u), axis=1)


def gyro_unit_ratio(rec: Recording) -> tuple[float, dict[str, float]]:
    """The median over the sensors of ``|w x u| / |du/dt|`` (module docstring) and each sensor's,
    over its samples near 1 g whose gravity direction turns faster than 5 deg/s (nan without
    enough of them)."""
    each = {}
    for name, s in rec.sensors.items():
        if s.gyr is None or s.acc is None or len(rec.time) < 20:
            continue
        du, wu = _turn_rates(s, rec.rate_hz)
        a = np.linalg.norm(np.nan_to_num(s.acc), axis=1)
        calm = (np.abs(a - 9.81) < 0.2 * 9.81) & (du > np.radians(5.0))
        if np.sum(calm) >= 10:
            each[name] = float(np.median(wu[calm]) / np.median(du[calm]))
    return (float(np.median(list(each.values()))) if each else float("nan")), each


def check_units(rec: Recording) -> None:
    """Refuse gyroscopes whose unit is not rad/s (module docstring, ``units``)."""
    ratio, each = gyro_unit_ratio(rec)
    if not np.isfinite(ratio) or UNIT_RATIO[0] <= ratio <= UNIT_RATIO[1]:
        return
    hint = "deg/s read as rad/s" if ratio > UNIT_RATIO[1] else "rad/s read as deg/s"
    per = ", ".join(f"{n} {r:.3g}" for n, r in each.items())
    raise InputError(f"the gyroscopes turn {ratio:.3g} times as fast as gravity's direction "
                     f"turns in the accelerometers (median; {per}; 0.3-1.7 in rad/s, 57.3 times "
                     f"that for deg/s): they look like {hint}", file=rec.source,
                     field="gyr")  # fmt: skip


#: Quaternion order: refused as x, y, z, w when, read that way, the orientations keep gravity
#: along a world axis this much better (the median over the sensors of the ratio of the tilts,
#: :func:`_gravity_tilt`) than read as w, x, y, z.
ORDER_RATIO = 0.5


def _gravity_tilt(quat: np.ndarray, acc: np.ndarray) -> float:
    """The median angle (deg) between ``R(q) a`` over the samples near 1 g and the vertical
    world axis (y or z, the one nearest its median direction: every world the readers know):
    small when the orientations agree with the accelerometer."""
    up = gravity_in_world(quat, acc)
    if up is None:
        return float("nan")
    mid = np.median(up, axis=0)
    k = 1 + int(np.argmax(np.abs(mid[1:])))
    return float(np.median(np.degrees(np.arccos(np.clip(np.sign(mid[k]) * up[:, k], -1, 1)))))


def check_quaternion_order(rec: Recording) -> None:
    """Refuse orientations that are x, y, z, w read as w, x, y, z (:data:`ORDER_RATIO`), where
    the recording has both orientations and accelerometers."""
    ratios, each = [], []
    for name, s in rec.sensors.items():
        if s.quat is None or s.acc is None:
            continue
        given = _gravity_tilt(s.quat, s.acc)
        other = _gravity_tilt(s.quat[:, [3, 0, 1, 2]], s.acc)
        if np.isfinite(given) and np.isfinite(other) and given > 0:
            ratios.append(other / given)
            each.append(f"{name} {given:.0f} vs {other:.0f}")
    if ratios and np.median(ratios) < ORDER_RATIO:
        raise InputError("the orientations keep gravity vertical far better read as x, y, z, w "
                         f"than as w, x, y, z (median tilt, deg: {', '.join(each)}): "
                         "give the quaternions scalar first (w, x, y, z)", file=rec.source,
                         field="quat")  # fmt: skip


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
            for s in ((side,) if side else ("right", "left"))}  # fmt: skip
    return [n for n, g in seg.items() if g in want and rec.sensors[n].gyr is not None]


def _moves_with_segment(name: str, s: SensorSignals, rec: Recording) -> Finding | None:
    if s.gyr is None:
        return None
    near = _neighbours(name, rec)
    speeds = [_speed(rec.sensors[n]) for n in near]
    if not speeds or min(speeds) < MOVING_SPEED:  # a still neighbour: a still segment is normal
        return None
    foot = SENSOR_TO_SEGMENT.get(name, "").endswith("foot")
    mine = _speed(s, FOOT_QUANTILE if foot else 0.5)
    if mine >= MIN_SPEED_RATIO * min(speeds):
        return None
    return Finding(name, "moves with its segment", _action_on_stillness(near),
                   f"it turns at {np.degrees(mine):.0f} deg/s "
                   f"({'upper quartile' if foot else 'median'}) while its neighbours "
                   f"({', '.join(near)}) turn at {np.degrees(min(speeds)):.0f} or more: it does "
                   "not follow a segment (loose or fallen off?)")  # fmt: skip


def _action_on_stillness(neighbours: list[str]) -> str:
    """Excluded when two or more neighbours move around it; with one neighbour (a foot) only
    noted: a foot rests on the floor while its shank turns (squats, sit-to-stand)."""
    return "excluded" if len(neighbours) >= 2 else "noted"


def _dropout(name: str, s: SensorSignals, rec: Recording) -> Finding | None:
    for field, what in (("gyr", "gyroscope"), ("acc", "accelerometer")):
        x = getattr(s, field)
        if x is None:
            continue
        runs = true_runs(~np.all(np.isfinite(x), axis=1))
        long = [(a, b) for a, b in runs if (b - a) / rec.rate_hz > DEFAULT_MAX_GAP_S]
        if long:
            a, b = max(long, key=lambda r: r[1] - r[0])
            return Finding(name, "dropout", "excluded",
                           f"{what} missing for {(b - a) / rec.rate_hz:.1f} s (t = "
                           f"{rec.time[a]:.2f}-{rec.time[b - 1]:.2f} s; {len(long)} gap(s) "
                           f"longer than {DEFAULT_MAX_GAP_S:g} s)")  # fmt: skip
    return None


def _repaired_on_reading(name: str, s: SensorSignals, rec: Recording) -> Finding | None:
    said = rec.sensor_notes.get(name, ())
    if not said:
        return None
    return Finding(name, "read", "listed", "its file's reader: " + "; ".join(
        n.split(": ", 1)[1] if rec.source and n.startswith(str(rec.source)) else n
        for n in said))  # fmt: skip


def _slipped(name: str, s: SensorSignals, rec: Recording) -> Finding | None:
    step = slip_step(name, rec)
    if step is None:
        why = unchecked(name, rec)
        return None if why is None else Finding(name, "slipped", "listed", why)
    if step.inconclusive or step.slipped:
        return Finding(name, "slipped", "listed" if step.inconclusive else "excluded",
                       step.evidence())  # fmt: skip
    return None


#: Check name -> function of (sensor name, its signals, the recording).
CHECKS: dict[str, Callable[[str, SensorSignals, Recording], Finding | None]] = {
    "read": _repaired_on_reading,  # first: an exclusion below stops the sensor's checks
    "dead": _dead,
    "dropout": _dropout,
    "saturation": _saturation,
    "moves with its segment": _moves_with_segment,
    "slipped": _slipped,
}
SWAPPED_BACK = "read as swapped back"  # sensors exchanged (pipeline.process.swap, .sides)


def check_sensors(rec: Recording) -> tuple[Recording, list[Finding]]:
    """The gyroscopes' unit (refused when wrong), then every check on every sensor with raw
    signals; the recording without the excluded sensors and with the unused magnetometers
    removed, and the findings."""
    check_units(rec)
    check_quaternion_order(rec)
    findings = []
    for name, s in rec.sensors.items():
        for fn in CHECKS.values():
            f = fn(name, s, rec)
            if f is not None:
                findings.append(f)
                if f.action == "excluded":  # one reason is enough
                    break
    sensors = dict(rec.sensors)  # each sensor's own faults first
    for f in findings:
        if f.action == "excluded":
            sensors.pop(f.sensor, None)
        elif f.action == "magnetometer not used" and f.sensor in sensors:
            sensors[f.sensor] = sensors[f.sensor].replace(mag=None)
    rec = rec.with_sensors(sensors)
    faulty = {f.sensor for f in findings if f.flagged and f.action != "magnetometer not used"}
    crossing = crossing_evidence(rec, faulty)  # first: eq 1 needs each leg's own sensors
    if crossing is not None and crossing.crossed:  # read back, or the four excluded
        action = SWAPPED_BACK if crossing.exchanged else "excluded"
        findings += [Finding(n, "crossed", action, crossing.evidence()) for n in crossing.sensors]
        rec = crossing.read_back(rec)
    for side in ("right", "left"):  # a leg whose three sensors passed: its thigh's and shank's
        ev = swap_evidence(side, rec, faulty)
        if ev is not None and ev.swapped:
            findings.append(Finding(ev.shank, "swapped", SWAPPED_BACK, ev.evidence()))
            rec = ev.read_back(rec)
    return rec, findings
