"""Two leg sensors swapped (their straps or their names exchanged): across the legs the stride's
rhythm tells them apart, within a leg the foot.

The ankle joins the shank and the foot: the specific force at its centre, seen by the two
sensors, has one magnitude (Hu 2021 eq 1-3, the spherical calibration,
:func:`pipeline.process.functional.fit_joint`), so the shank's sensor and the foot's fit it to
within their soft tissue, while the thigh's sensor, a knee away, cannot. With ``e_S`` the RMS
residual of eq 3 after the fit of sensor ``S`` with the foot's, a leg whose

    e_thigh * SWAP_RATIO < e_shank   and   e_shank >= MIN_RESIDUAL                       (1)

has its thigh's and shank's sensors read as swapped back (the run says so, a flag: ``--strict``
stops on it). Measured (m/s^2, shank + foot / thigh + foot): S02 0.21 / 1.34 and 0.24 / 1.60,
the x-IMU3 walk 0.90 / 2.17 and 0.78 / 2.11, the simulated walk 0.27-0.34 / 2.68-3.56 (seeds
0-2), the simulated sinusoidal gait 0.05-0.08 / 0.90-1.42: 2.4-28 times apart; :data:`SWAP_RATIO`
lies between 1 and the smallest (2.4), a margin of 1.6 both ways. Lying or standing still the
two fits leave noise alike (0.02-0.05 on the simulator's supine and static trials):
:data:`MIN_RESIDUAL` keeps them from deciding. The hip does not tell the two apart as well
(S02: pelvis + thigh 0.45, pelvis + shank 0.46 and 0.60). The fits take 0.15-0.3 s a run (S02).

Across the legs (the right shank's sensor named the left's, or the feet's): in walking a leg's
segments swing once a stride together and the two legs half a stride apart, so the angular
speeds ``|w|`` of one leg's sensors, band-passed to the stride's rhythm (:data:`RHYTHM_BAND_HZ`),
rise and fall together, and the other leg's against them. With ``r`` their correlation (``t``
shank, ``f`` foot, ``F`` thigh; ``R``, ``L`` the legs as named),

    P = r(t_R, f_L) + r(t_L, f_R) - r(t_R, f_R) - r(t_L, f_L) >= MIN_GAIN                (2)

says that each shank's sensor and foot's swing with the other leg's: the shanks' or the feet's
sensors are exchanged between the legs. Which: the thighs swing with the legs read one way or
the other,

    T = [r(F_R, t_L) + r(F_R, f_R) + r(F_L, t_R) + r(F_L, f_L)]
      - [r(F_R, t_R) + r(F_R, f_L) + r(F_L, t_L) + r(F_L, f_R)]                         (3)

the shanks' with ``T >= MIN_THIGH_GAIN``, the feet's with ``T <= -MIN_THIGH_GAIN``: they are
read back (before eq 1, which needs each leg's own sensors); between the two the four sensors
are excluded, named. Measured, each exchange injected (``P``; ``T`` for the shanks' exchange, the
feet's the same negated): S02 2.87 / 2.03, the x-IMU3 walk 3.20 / 5.05, the qmt recording (16
sensors, no truth; strides of 1 s at 5-7 rad/s: running) 3.04 / -1.22 (its first 65 s 2.89 /
-1.39), the simulated walk 2.45-2.87 / 3.18-4.25 (seeds 0-5); as named ``P`` is the same
negated. :data:`MIN_GAIN` lies halfway to the smallest ``P``; in running the thighs mislead
(qmt's read the wrong way), and S02's left thigh swings with its leg weakly (0.07 and 0.16,
0.48 with the other thigh): :data:`MIN_THIGH_GAIN` lies halfway between qmt's 1.39 and S02's
2.03, so that qmt's four sensors would be excluded and S02's exchange read back.
Only a walk decides (:data:`~pipeline.process.gait.MIN_STRIDES` strides a leg; the simulator's
sinusoidal gait, whose legs do not take turns, has none). The band holds strides of 0.7 to 2 s.
A thigh named for the other leg alone leaves eq (2) as named; the hips see it
(:mod:`pipeline.process.sides`), and whether the shanks and feet go with the thighs, the thighs'
rhythm tells:

    W = sum over both legs and (t, f) of r(F_own, t_own) - r(F_own, t_other)               (4)

``W >= MIN_THIGH_GAIN``: each thigh swings with its named leg (S02 2.03, the x-IMU3 walk 5.05,
the simulated walk 3.18-4.25; the same as eq 3's with a shank exchanged, its terms being
those), ``W <= -MIN_THIGH_GAIN``: with the other (the thighs alone exchanged). Eq (2)-(4) and the
strides take 0.02 s (S02).
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SEGMENT_SENSOR

__all__ = ["CUTOFF_HZ", "MIN_GAIN", "MIN_RESIDUAL", "MIN_THIGH_GAIN", "RHYTHM_BAND_HZ", "STEP",
           "SWAP_RATIO", "Crossing", "Swap", "crossing_evidence", "swap_evidence"]

#: The worse fit must leave this many times the better's residual (eq 1).
SWAP_RATIO = 1.5
#: ... and at least this (m/s^2): the leg moved enough to tell the two apart.
MIN_RESIDUAL = 0.5
#: Low-pass cut-off (Hz) of the signals before the fits (as the heading alignment's centres),
#: and every how many samples the fits take (100 Hz -> 25 Hz: four times faster, still twice the
#: cut-off's rate).
CUTOFF_HZ, STEP = 6.0, 4
#: Eq (2)'s band (Hz): a stride's rhythm (strides take 0.9-1.3 s in a walk), above a walk's
#: starts and stops.
RHYTHM_BAND_HZ = (0.5, 1.5)
#: Eq (2): the shanks' and feet's sensors pair across the legs better by this much (of 4 at most).
MIN_GAIN = 1.2
#: Eq (3): the thighs tell which were exchanged when they prefer one reading by this much.
MIN_THIGH_GAIN = 1.7
_PARTS = ("tibia", "foot")  # what eq (2) may find exchanged between the legs (the thighs fixed)


@dataclass(frozen=True)
class Swap:
    """One leg's evidence: its sensors' names and eq (1)'s residuals (m/s^2)."""

    thigh: str
    shank: str
    foot: str
    shank_residual: float
    thigh_residual: float

    @property
    def swapped(self) -> bool:
        """Eq (1)."""
        return (self.thigh_residual * SWAP_RATIO < self.shank_residual
                and self.shank_residual >= MIN_RESIDUAL)

    def read_back(self, rec: Recording) -> Recording:
        """``rec`` with the thigh's and the shank's sensors exchanged."""
        return rec.with_sensors({**rec.sensors, self.thigh: rec.sensors[self.shank],
                                 self.shank: rec.sensors[self.thigh]})

    def evidence(self) -> str:
        return (f"the foot's sensor {self.foot} fits an ankle with {self.thigh} (residual "
                f"{self.thigh_residual:.2f} m/s^2) better than with {self.shank} "
                f"({self.shank_residual:.2f}): the thigh's and the shank's sensors are swapped "
                "(check the straps or the sensor map)")


def _ankle_residual(rec: Recording, leg: SensorSignals, foot: SensorSignals) -> float:
    from pipeline.process.functional import joint_residual

    return joint_residual(rec.time, rec.rate_hz, leg, foot, cutoff_hz=CUTOFF_HZ, step=STEP)


def swap_evidence(side: str, rec: Recording, faulty: Collection[str] = ()) -> Swap | None:
    """Eq (1)'s residuals for the ``side`` leg; None without raw signals of its thigh's, shank's
    and foot's sensors, complete, or when one of them is ``faulty`` (a faulty foot or shank
    could make either fit the worse)."""
    names = [SEGMENT_SENSOR[f"{side}_{seg}"] for seg in ("femur", "tibia", "foot")]
    sensors = [rec.sensors.get(n) for n in names]
    if any(n in faulty for n in names) or any(s is None or not s.complete for s in sensors):
        return None
    thigh, shank, foot = sensors
    return Swap(*names, _ankle_residual(rec, shank, foot), _ankle_residual(rec, thigh, foot))


@dataclass(frozen=True)
class Crossing:
    """Eq (2)-(4): ``pairing`` the gain of the shanks' and feet's sensors paired across the legs
    over as named, ``thighs`` the thighs' preference for the shanks' over the feet's exchange,
    ``with_legs`` the thighs' for their named legs' shanks and feet over the other legs'."""

    pairing: float
    thighs: float
    with_legs: float

    @property
    def crossed(self) -> bool:
        """The shanks' or the feet's sensors are exchanged between the legs (eq 2)."""
        return self.pairing >= MIN_GAIN

    @property
    def exchanged(self) -> str | None:
        """Which (``'tibia'`` or ``'foot'``) by eq (3); None where the thighs do not tell."""
        if not self.crossed or abs(self.thighs) < MIN_THIGH_GAIN:
            return None
        return "tibia" if self.thighs > 0 else "foot"

    @property
    def sensors(self) -> list[str]:
        """The sensors exchanged (the right leg's), or all four where eq (3) does not tell."""
        segments = _PARTS if self.exchanged is None else (self.exchanged,)
        return [SEGMENT_SENSOR[f"{side}_{seg}"] for seg in segments
                for side in (("right",) if self.exchanged else ("right", "left"))]

    def read_back(self, rec: Recording) -> Recording:
        """``rec`` with the :attr:`exchanged` segment's sensors exchanged between the legs, or
        without the four :attr:`sensors` where eq (3) does not tell."""
        if self.exchanged is None:
            return rec.with_sensors({n: s for n, s in rec.sensors.items() if n not in self.sensors})
        right, left = (SEGMENT_SENSOR[f"{side}_{self.exchanged}"] for side in ("right", "left"))
        return rec.with_sensors({**rec.sensors, right: rec.sensors[left],
                                 left: rec.sensors[right]})

    def evidence(self) -> str:
        said = (f"each leg's shank and foot sensors swing in a stride's rhythm with the other "
                f"leg's, not with each other (eq 2: by {self.pairing:.2f}, of 4)")
        if self.exchanged is None:
            return (said + f"; the thighs do not tell whether the shanks' or the feet's are "
                    f"swapped (eq 3: {self.thighs:+.2f}): check the straps or the sensor map")
        part = {"tibia": "shanks'", "foot": "feet's"}[self.exchanged]
        return (said + f"; the thighs swing with the shanks and feet so read by "
                f"{abs(self.thighs):.2f} (eq 3): the right and left {part} sensors are swapped "
                "(check the straps or the sensor map)")


def crossing_evidence(ctx, faulty: Collection[str] = ()) -> Crossing | None:
    """Eq (2)-(3) on the recording of ``ctx`` (its
    :class:`~pipeline.process.check_context.CheckContext`); None without the gyroscopes of all six
    leg sensors, complete, when one of them is ``faulty``, or unless each leg walked
    :data:`~pipeline.process.gait.MIN_STRIDES` strides (the context's gait)."""
    from pipeline.filtering import lowpass
    from pipeline.process.gait import walked

    rec = ctx.rec
    names = {(side[0], seg): SEGMENT_SENSOR[f"{side}_{seg}"]
             for side in ("right", "left") for seg in ("femur", *_PARTS)}
    sensors = {k: rec.sensors.get(n) for k, n in names.items()}
    if any(n in faulty for n in names.values()) or any(
            s is None or s.gyr is None or not np.isfinite(s.gyr).all() for s in sensors.values()):
        return None
    if not walked(ctx.gait.strides):
        return None
    low, high = RHYTHM_BAND_HZ
    rhythm = {}
    for k, s in sensors.items():
        speed = np.linalg.norm(s.gyr, axis=1)
        rhythm[k] = lowpass(speed, rec.rate_hz, high) - lowpass(speed, rec.rate_hz, low)

    def r(a: tuple[str, str], b: tuple[str, str]) -> float:
        return float(np.corrcoef(rhythm[a], rhythm[b])[0, 1])

    pairing = (r(("r", "tibia"), ("l", "foot")) + r(("l", "tibia"), ("r", "foot"))
               - r(("r", "tibia"), ("r", "foot")) - r(("l", "tibia"), ("l", "foot")))
    thighs = (r(("r", "femur"), ("l", "tibia")) + r(("r", "femur"), ("r", "foot"))
              + r(("l", "femur"), ("r", "tibia")) + r(("l", "femur"), ("l", "foot"))
              - r(("r", "femur"), ("r", "tibia")) - r(("r", "femur"), ("l", "foot"))
              - r(("l", "femur"), ("l", "tibia")) - r(("l", "femur"), ("r", "foot")))
    with_legs = sum(r((x, "femur"), (x, seg)) - r((x, "femur"), (y, seg))
                    for x, y in (("r", "l"), ("l", "r")) for seg in _PARTS)
    return Crossing(pairing, thighs, with_legs)
