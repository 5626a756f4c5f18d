"""A leg's thigh and shank sensors swapped (their straps or their names exchanged): the foot
tells them apart.

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
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from pipeline.calibration.conventions import DEFAULT_METHOD
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SEGMENT_SENSOR

__all__ = ["CUTOFF_HZ", "MIN_RESIDUAL", "STEP", "SWAP_RATIO", "Swap", "swap_evidence"]

#: The worse fit must leave this many times the better's residual (eq 1).
SWAP_RATIO = 1.5
#: ... and at least this (m/s^2): the leg moved enough to tell the two apart.
MIN_RESIDUAL = 0.5
#: Low-pass cut-off (Hz) of the signals before the fits (as the heading alignment's centres),
#: and every how many samples the fits take (100 Hz -> 25 Hz: four times faster, still twice the
#: cut-off's rate).
CUTOFF_HZ, STEP = 6.0, 4


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
                and self.shank_residual >= MIN_RESIDUAL)  # fmt: skip

    def evidence(self) -> str:
        return (f"the foot's sensor {self.foot} fits an ankle with {self.thigh} (residual "
                f"{self.thigh_residual:.2f} m/s^2) better than with {self.shank} "
                f"({self.shank_residual:.2f}): the thigh's and the shank's sensors are swapped "
                "(check the straps or the sensor map)")


def _ankle_residual(rec: Recording, leg: SensorSignals, foot: SensorSignals) -> float:
    from pipeline.calibration.joint_constraints import joint_data, spherical_residual
    from pipeline.process.functional import fit_joint

    s1, s2 = (s.low_passed(rec.rate_hz, CUTOFF_HZ) for s in (leg, foot))
    fit = fit_joint(rec.time, s1, s2, slice(None, None, STEP), DEFAULT_METHOD, shared_world=False,
                    joint="spherical", verify_start=False)  # fmt: skip
    e = spherical_residual(fit.position_1_m, fit.position_2_m,
                           joint_data(rec.time, s1.gyr, s1.acc, s2.gyr, s2.acc))  # fmt: skip
    return float(np.sqrt(np.nanmean(e**2)))


def swap_evidence(side: str, rec: Recording, faulty: Collection[str] = ()) -> Swap | None:
    """Eq (1)'s residuals for the ``side`` leg; None without raw signals of its thigh's, shank's
    and foot's sensors, complete, or when one of them is ``faulty`` (a faulty foot or shank
    could make either fit the worse)."""
    names = [SEGMENT_SENSOR[f"{side}_{seg}"] for seg in ("femur", "tibia", "foot")]
    sensors = [rec.sensors.get(n) for n in names]
    if any(n in faulty for n in names) or any(
            s is None or s.gyr is None or s.acc is None
            or not (np.isfinite(s.gyr).all() and np.isfinite(s.acc).all()) for s in sensors):
        return None
    thigh, shank, foot = sensors
    return Swap(*names, _ankle_residual(rec, shank, foot), _ankle_residual(rec, thigh, foot))
