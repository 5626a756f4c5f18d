"""Still windows: where in a recording every sensor rests, where a calibration pose can be read.

A calibration pose (:mod:`pipeline.process.pose`) is a moment in which the subject holds a known
pose: standing, lying or seated, every sensor at rest. It is looked for over the whole recording,
not assumed at its first sample: trimmed files, protocols without a static pose and sensors started
late begin mid-movement, and a recording may stand still at its end or pause in its middle. A
sample rests when every sensor's signals, low-passed at :data:`CUTOFF_HZ`, show

    |w| < STILL_GYR_RAD_S   and   | |a| - g | < STILL_ACC_M_S2                     (1)

(gyroscope and accelerometer; a sensor with orientations only: the angular speed between its
successive orientations); a still window is a run of such samples lasting :data:`MIN_WINDOW_S` or
more. Measured on the real recordings (low-passed, every sensor): S02's standing start and end stay
below 0.1 rad/s and 0.5 m/s^2 (0.0-10.9 s and 22.1-25.0 s; its walk never rests on all seven
sensors at once for more than 0.3 s), the x-IMU3 walk's still start and end likewise (0.0-1.2 s,
16.7-18.6 s). In walking the stance leg's thigh and shank turn at about 1 rad/s through the stance,
so a window of every sensor at rest for half a second is not a step.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.filtering import lowpass
from pipeline.io.gaps import true_runs
from pipeline.io.recording import Recording, SensorSignals
from pipeline.rotations import log3, matrix_from_quat

__all__ = ["CUTOFF_HZ", "MIN_WINDOW_S", "STILL_ACC_M_S2", "STILL_GYR_RAD_S", "StillWindow",
           "resting", "still_windows"]

#: Eq (1)'s thresholds: angular speed (rad/s) and the specific force's distance from 1 g (m/s^2).
STILL_GYR_RAD_S = 0.1
STILL_ACC_M_S2 = 0.5
#: Low-pass cut-off (Hz) of the signals eq (1) reads: a standing subject's sway and the sensors'
#: noise, not a movement.
CUTOFF_HZ = 2.0
#: The shortest still window (s) a pose is read in (as long as the still run whose mean
#: accelerometer gives a sensor's vertical, :data:`pipeline.process.pose.MIN_STILL_S`).
MIN_WINDOW_S = 0.5
_G = 9.81


@dataclass(frozen=True)
class StillWindow:
    """Samples ``[start, stop)`` at rest on every sensor; ``t0``, ``t1`` their first and last
    times (s)."""

    start: int
    stop: int
    t0: float
    t1: float

    @property
    def span(self) -> str:
        return f"{self.t0:.2f}-{self.t1:.2f} s"

    @property
    def rows(self) -> slice:
        return slice(self.start, self.stop)


def _orientation_speed(quat: np.ndarray, rate_hz: float) -> np.ndarray:
    """The angular speed (rad/s) between successive orientations, per sample (the last repeated)."""
    R = matrix_from_quat(quat)
    turn = np.linalg.norm(log3(np.swapaxes(R[:-1], 1, 2) @ R[1:]), axis=-1) * rate_hz
    return np.append(turn, turn[-1:]) if len(turn) else np.zeros(len(quat))


def resting(s: SensorSignals, rate_hz: float) -> np.ndarray | None:
    """Eq (1) per sample for one sensor (bool (N,)), None for a sensor with no signal to judge."""
    if s.gyr is not None and s.acc is not None:
        ok = np.all(np.isfinite(s.gyr), axis=1) & np.all(np.isfinite(s.acc), axis=1)
        w = np.linalg.norm(lowpass(np.nan_to_num(s.gyr), rate_hz, CUTOFF_HZ), axis=1)
        a = np.linalg.norm(lowpass(np.nan_to_num(s.acc), rate_hz, CUTOFF_HZ), axis=1)
        return ok & (w < STILL_GYR_RAD_S) & (np.abs(a - _G) < STILL_ACC_M_S2)
    if s.quat is not None and len(s.quat) > 1:
        ok = np.all(np.isfinite(s.quat), axis=1)
        speed = _orientation_speed(np.where(ok[:, None], s.quat, [1.0, 0, 0, 0]), rate_hz)
        return ok & (lowpass(speed, rate_hz, CUTOFF_HZ) < STILL_GYR_RAD_S)
    return None


def still_windows(rec: Recording, sensors=None) -> list[StillWindow]:
    """The still windows (module docstring) of ``rec``'s ``sensors`` (default: all), in time
    order; a sensor's missing samples (bridged, :meth:`~pipeline.io.recording.Recording.present`)
    neither make a rest nor break one: the others' stillness decides there."""
    names = list(rec.sensors) if sensors is None else list(sensors)
    still = np.ones(rec.n_samples, dtype=bool)
    judged = False
    for name in names:
        r = resting(rec.sensors[name], rec.rate_hz)
        if r is not None:
            still &= r | ~rec.present(name)
            judged = True
    if names:  # some sensor's own samples: a stretch no sensor has is not a rest
        still &= np.any([rec.present(n) for n in names], axis=0)
    if not judged:
        return []
    least = MIN_WINDOW_S * rec.rate_hz
    return [StillWindow(a, b, float(rec.time[a]), float(rec.time[b - 1]))
            for a, b in true_runs(still) if b - a >= least]
