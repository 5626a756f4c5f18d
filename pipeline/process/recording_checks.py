"""The sensor checks whose scope is the whole recording (:data:`pipeline.process.sensor_checks.
CHECKS`): what one sensor alone cannot tell. A fault here refuses the recording (one line naming
the file, the field and what was expected).

* ``units`` (:func:`check_units`): the gyroscopes against the
  accelerometers, which show each sensor's inclination whatever the unit: the rate at which
  gravity's direction turns in the sensor frame, ``|du/dt| = |w x u|`` (``u = a/|a|``
  low-passed), is compared with the gyroscope's own ``|w x u|``. The ratio is 1 for rad/s and
  57.3 for deg/s given as rad/s, whatever the speed (slow trials too, where the magnitude test of
  :func:`pipeline.io.checks.check_gyro_units` passes deg/s). Linear accelerations turn ``a`` too:
  a sensor's ratio ranges 0.01-1.7 (measured: a still leg's, a foot's in gait), the median over
  a recording's sensors 0.33 (x-IMU3 walk), 0.65 (S02) and 0.75-1.0 (simulated gait, supine,
  seated), 57 times that with the wrong unit: a median outside :data:`UNIT_RATIO` is
  **refused**.
* ``quaternion order`` (:func:`check_quaternion_order`, where the recording has orientations
  and accelerometers): orientations that keep gravity along a world axis far better
  read as x, y, z, w than as w, x, y, z are **refused** (median tilt: S02's vendor quaternions
  0.2-1.0 deg, 3.4-40 deg read the other way; the simulator's 0.3-8 deg, 7-88 deg).

"""

from __future__ import annotations

import numpy as np

from pipeline.errors import InputError
from pipeline.filtering import lowpass
from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.signals import gravity_in_world

__all__ = ["MIN_TURN_COSINE", "ORDER_RATIO", "UNIT_RATIO", "UNIT_TURNING_DPS", "UNIT_TURNING_S",
           "check_quaternion_order", "check_units", "gyro_unit_ratio", "turn_agreement"]

#: The accepted range of the gyroscope's to the accelerometer's turn of gravity.
UNIT_RATIO = (0.1, 10.0)


def _turn_rates(s: SensorSignals, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
    """``(|du/dt|, |w x u|)`` per sample, ``u`` gravity's direction in the sensor frame."""
    cut = min(2.0, 0.2 * rate_hz)
    a = lowpass(np.nan_to_num(s.acc), rate_hz, cut)
    u = a / np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-9)
    du = np.linalg.norm(np.gradient(u, axis=0), axis=1) * rate_hz
    w = lowpass(np.nan_to_num(s.gyr), rate_hz, cut)
    return du, np.linalg.norm(np.cross(w, u), axis=1)


#: The unit ratio is taken over samples whose gravity direction turns faster than this (deg/s),
#: at least :data:`UNIT_TURNING_S` of them: a standing subject's sway never does (S02's 11 s
#: standing: no sample; at 5 deg/s, its noise, 6-64 samples per sensor gave ratios of 0.04-0.34,
#: which refused a standing-only trial as "rad/s read as deg/s"), walking for hundreds of samples
#: (S02 300-670 per sensor, the x-IMU3 walk 220-500, ratios as at 5 deg/s within 0.1).
UNIT_TURNING_DPS = 20.0
UNIT_TURNING_S = 0.5


def gyro_unit_ratio(rec: Recording) -> tuple[float, dict[str, float]]:
    """The median over the sensors of ``|w x u| / |du/dt|`` (module docstring) and each sensor's,
    over its samples near 1 g whose gravity direction turns faster than
    :data:`UNIT_TURNING_DPS` (nan without :data:`UNIT_TURNING_S` of them: too little movement to
    tell)."""
    each = {}
    for name, s in rec.sensors.items():
        if s.gyr is None or s.acc is None or len(rec.time) < 20:
            continue
        du, wu = _turn_rates(s, rec.rate_hz)
        a = np.linalg.norm(np.nan_to_num(s.acc), axis=1)
        calm = (np.abs(a - 9.81) < 0.2 * 9.81) & (du > np.radians(UNIT_TURNING_DPS))
        if np.sum(calm) >= max(10, UNIT_TURNING_S * rec.rate_hz):
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
                     field="gyr")


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
                         field="quat")


#: A sensor's orientations turn as its gyroscope says when the median cosine between their rates
#: (:func:`turn_agreement`) is at least this: real sensors' 0.995-0.999 (S02's seven, the x-IMU3
#: walk's seven); read as x, y, z, w 0.78 at most (-0.88 to 0.78), as world -> sensor -0.70 to 0.12.
MIN_TURN_COSINE = 0.9


def turn_agreement(s: SensorSignals, rate_hz: float) -> float | None:
    """The median, over the samples turning faster than 0.5 rad/s, of the cosine between the
    rotation rate the orientations make between samples (in the sensor frame,
    ``log(R_k^T R_{k+1}) / dt``) and the gyroscope's: 1 for orientations of the sensor's own
    (whatever their world: a fixed turn of the world leaves it), low for a wrong component
    order, direction (world -> sensor) or handedness; None without 20 such samples."""
    from pipeline.rotations import log3, matrix_from_quat

    if s.quat is None or s.gyr is None or len(s.quat) < 3:
        return None
    ok = np.all(np.isfinite(s.quat), axis=1) & np.all(np.isfinite(s.gyr), axis=1)
    R = matrix_from_quat(np.where(ok[:, None], s.quat, [1.0, 0.0, 0.0, 0.0]))
    made = log3(np.swapaxes(R[:-1], 1, 2) @ R[1:]) * rate_hz
    w = 0.5 * (s.gyr[:-1] + s.gyr[1:])
    speed = np.linalg.norm(np.nan_to_num(w), axis=1)
    use = ok[:-1] & ok[1:] & (speed > 0.5) & (np.linalg.norm(made, axis=1) > 0)
    if use.sum() < 20:
        return None
    cos = np.sum(made[use] * w[use], axis=1) / (np.linalg.norm(made[use], axis=1) * speed[use])
    return float(np.median(cos))
