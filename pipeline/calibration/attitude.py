"""Single-IMU attitude by a PI (Mahony-type) complementary filter (Hu et al. 2021 §4.3, eq 43-50).

Per sample, with ``q`` the sensor -> world quaternion (wxyz, world z up):

* eq 45-46: estimated "up" direction in the sensor frame, ``v = R(q)^T e_z``
  (``[2(q1q3 - q0q2), 2(q2q3 + q0q1), q0^2 - q1^2 - q2^2 + q3^2]``);
* eq 47 (misprinted in the paper): error ``zeta = a_hat x v``, ``a_hat`` the normalised
  accelerometer reading (specific force, which points up when at rest);
* eq 48: integral ``zeta_I <- zeta_I + lambda_i zeta dt / 2``;
* eq 49: corrected rate ``w <- w + lambda_p zeta + zeta_I``;
* eq 50: ``q <- q (x) [1, w dt / 2]`` (first order), renormalised.

The integral term converges to minus the gyro bias component perpendicular to gravity (the
heading component is unobservable without a magnetometer); ``bias`` reports ``-zeta_I``.
Gains (default ``None``): the paper's ``lambda_p = 2 dt`` and ``lambda_i = 0.1 dt`` with ``dt``
the sample period (0.02 and 0.001 at 100 Hz). Such a small ``lambda_p`` trusts the gyro (tilt
RMS ~1 deg in simulated gait vs ~5 deg with ``lambda_p = 1``) but corrects a wrong start only
over ~1/lambda_p = 50 s, hence the default ``q0='acc'`` (tilt from the first accelerometer
sample); ``q0=None`` is eq 44's identity. The integral term needs ``lambda_i`` ~ 0.1-1 per
second to remove a bias within a minute.

Two extensions, off by default (the paper's filter) and on in :data:`TUNED` (what ``--filter pi``
uses), measured on BROAD (Laidig et al. 2021; ``scripts/bench_filters.py``):

* ``acc_lowpass_s``: the accelerometer enters eq 47 low-passed *in the estimated world frame*
  (``a_w = R a`` filtered with time constant ``tau``, then ``a_hat = R^T a_w``), so linear
  accelerations, which change direction in the world, average out while gravity does not (the
  idea of VQF's inclination correction, Laidig & Seel 2023). The paper's raw ``a_hat`` gives
  11.4 deg (its gains) or 9-19 deg (larger gains) inclination RMSE on the fast-translation trial.
* ``rest_start``: when the recording starts still (|gyro| < 0.05 rad/s and | |a| - g | < 0.3
  m/s^2 for at least 0.5 s), the initial attitude is the mean accelerometer direction of that
  rest and the integral starts at minus its mean gyro (the bias).

With ``lambda_p = 1/s``, ``lambda_i = 0.01/s^2``, ``tau = 3 s``: 0.68, 0.59 and 1.10 deg on BROAD
trials 01 (slow rotation), 15 (fast translation) and 28 (magnetic disturbance; 6-D, so unaffected),
against offline VQF's 0.37, 0.56 and 0.81 deg.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from pipeline.calibration.conventions import FILTERS
from pipeline.errors import InputError
from pipeline.rotations import matrix_from_quat, quat_from_matrix, rotation_aligning

__all__ = [
    "MAGNETOMETER_FILTERS",
    "TUNED",
    "AttitudeEstimate",
    "PIState",
    "REST_START_S",
    "filter_orientations",
    "mahony_filter",
    "rest_bias",
    "still_start",
    "tilt_error",
]

#: The gains and extensions ``--filter pi`` uses (module docstring; tuned on BROAD).
TUNED = {"lambda_p": 1.0, "lambda_i": 0.01, "acc_lowpass_s": 3.0, "rest_start": True}
_GRAVITY = 9.81
#: A still start this long (s) or longer gives the filter its first attitude and bias
#: (``rest_start``) and VQF its bias (:func:`rest_bias`).
REST_START_S = 0.5


@dataclass(frozen=True)
class AttitudeEstimate:
    """Filter output: ``quat`` (N,4) sensor -> world wxyz, ``bias`` (N,3) estimated gyro bias
    (rad/s, sensor frame), ``error`` (N,3) the eq-47 error vector."""

    time: np.ndarray
    quat: np.ndarray
    bias: np.ndarray
    error: np.ndarray


@dataclass
class PIState:
    """The filter's state between samples (eq 44-50): ``q`` the attitude (wxyz), ``integral`` the
    eq 48 term, ``force`` the low-passed specific force in the world (``acc_lowpass_s``), and its
    gains: what a live capture steps block by block (:meth:`run`) and :func:`mahony_filter`
    runs over a whole recording."""

    q: np.ndarray
    lambda_p: float
    lambda_i: float
    tau: float = 0.0
    integral: np.ndarray = field(default_factory=lambda: np.zeros(3))
    force: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, _GRAVITY]))

    def seed_at_rest(self, gyr_mean: np.ndarray, acc_mean: np.ndarray) -> None:
        """``rest_start``: upright by a still start's mean specific force, the integral minus its
        mean gyro (the bias)."""
        self.q = upright(acc_mean)
        self.integral = -np.asarray(gyr_mean, float)

    def run(self, gyr: np.ndarray, acc: np.ndarray, dts: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Eq 45-50 over samples (m, 3) with their steps ``dts`` (m,) s: each sample's attitude
        (m, 4), bias estimate ``-zeta_I`` (m, 3) and error ``zeta`` (m, 3); the state goes on."""
        q0_, q1, q2, q3 = (float(v) for v in self.q / np.linalg.norm(self.q))
        ix, iy, iz = (float(v) for v in self.integral)
        wx_, wy_, wz_ = (float(v) for v in self.force)
        lambda_p, lambda_i, tau = self.lambda_p, self.lambda_i, self.tau
        n = len(dts)
        out_q, out_b, out_e = np.empty((n, 4)), np.empty((n, 3)), np.empty((n, 3))
        for k in range(n):
            dt = dts[k]
            gx, gy, gz = gyr[k]
            ax, ay, az = acc[k]
            if tau > 0:  # low-pass in the estimated world frame (module docstring)
                r00, r01 = 1 - 2 * (q2 * q2 + q3 * q3), 2 * (q1 * q2 - q0_ * q3)
                r02, r10 = 2 * (q1 * q3 + q0_ * q2), 2 * (q1 * q2 + q0_ * q3)
                r11, r12 = 1 - 2 * (q1 * q1 + q3 * q3), 2 * (q2 * q3 - q0_ * q1)
                r20, r21 = 2 * (q1 * q3 - q0_ * q2), 2 * (q2 * q3 + q0_ * q1)
                r22 = 1 - 2 * (q1 * q1 + q2 * q2)
                al = min(1.0, dt / tau)
                wx_ += al * (r00 * ax + r01 * ay + r02 * az - wx_)
                wy_ += al * (r10 * ax + r11 * ay + r12 * az - wy_)
                wz_ += al * (r20 * ax + r21 * ay + r22 * az - wz_)
                ax = r00 * wx_ + r10 * wy_ + r20 * wz_
                ay = r01 * wx_ + r11 * wy_ + r21 * wz_
                az = r02 * wx_ + r12 * wy_ + r22 * wz_
            na = math.sqrt(ax * ax + ay * ay + az * az)
            ex = ey = ez = 0.0
            if na > 0:
                ax, ay, az = ax / na, ay / na, az / na
                vx = 2 * (q1 * q3 - q0_ * q2)  # eq 46
                vy = 2 * (q2 * q3 + q0_ * q1)
                vz = q0_ * q0_ - q1 * q1 - q2 * q2 + q3 * q3
                ex, ey, ez = ay * vz - az * vy, az * vx - ax * vz, ax * vy - ay * vx  # eq 47
                ix += lambda_i * ex * 0.5 * dt  # eq 48
                iy += lambda_i * ey * 0.5 * dt
                iz += lambda_i * ez * 0.5 * dt
            gx += lambda_p * ex + ix  # eq 49
            gy += lambda_p * ey + iy
            gz += lambda_p * ez + iz
            hx, hy, hz = 0.5 * dt * gx, 0.5 * dt * gy, 0.5 * dt * gz  # eq 50: q (x) [1, w dt/2]
            q0_, q1, q2, q3 = (
                q0_ - q1 * hx - q2 * hy - q3 * hz,
                q1 + q0_ * hx + q2 * hz - q3 * hy,
                q2 + q0_ * hy - q1 * hz + q3 * hx,
                q3 + q0_ * hz + q1 * hy - q2 * hx,
            )
            nq = math.sqrt(q0_ * q0_ + q1 * q1 + q2 * q2 + q3 * q3)
            q0_, q1, q2, q3 = q0_ / nq, q1 / nq, q2 / nq, q3 / nq
            out_q[k] = q0_, q1, q2, q3
            out_b[k] = -ix, -iy, -iz
            out_e[k] = ex, ey, ez
        self.q = np.array([q0_, q1, q2, q3])
        self.integral, self.force = np.array([ix, iy, iz]), np.array([wx_, wy_, wz_])
        return out_q, out_b, out_e


def upright(acc: np.ndarray) -> np.ndarray:
    """The attitude (wxyz) whose up is the specific force ``acc`` (3,), heading arbitrary."""
    return quat_from_matrix(rotation_aligning(acc, [0.0, 0.0, 1.0]))


def mahony_filter(
    time: np.ndarray,
    gyr: np.ndarray,
    acc: np.ndarray,
    *,
    lambda_p: float | None = None,
    lambda_i: float | None = None,
    q0: np.ndarray | str | None = "acc",
    acc_lowpass_s: float = 0.0,
    rest_start: bool = False,
) -> AttitudeEstimate:
    """Run the eq 44-50 filter over gyro (rad/s) and accelerometer (m/s^2) samples (N,3); the
    two extensions of the module docstring with ``acc_lowpass_s > 0`` and ``rest_start``."""
    t = np.asarray(time, dtype=float)
    gyr = np.asarray(gyr, dtype=float)
    acc = np.asarray(acc, dtype=float)
    n = t.size
    if gyr.shape != (n, 3) or acc.shape != (n, 3):
        raise InputError(f"expected gyr and acc of shape ({n}, 3), got {gyr.shape}, {acc.shape}")
    if n < 2:
        raise InputError(f"expected at least 2 samples, got {n}", field="time")
    period = float(np.median(np.diff(t)))
    lambda_p = 2.0 * period if lambda_p is None else lambda_p
    lambda_i = 0.1 * period if lambda_i is None else lambda_i
    if isinstance(q0, str):
        if q0 != "acc":
            raise InputError(f"expected q0 'acc', a quaternion or None, got {q0!r}", field="q0")
        q = upright(acc[0])
    else:
        q = np.array([1.0, 0.0, 0.0, 0.0]) if q0 is None else np.asarray(q0, float)  # eq 44
    state = PIState(q, lambda_p, lambda_i, float(acc_lowpass_s))
    if rest_start:
        n0 = still_start(gyr, acc)
        if n0 * period >= REST_START_S:
            state.seed_at_rest(gyr[:n0].mean(axis=0), acc[:n0].mean(axis=0))
    quat, bias, error = state.run(gyr, acc, np.diff(t, prepend=t[0] - period))
    return AttitudeEstimate(time=t, quat=quat, bias=bias, error=error)


def tilt_error(quat_est: np.ndarray, quat_true: np.ndarray) -> np.ndarray:
    """Angle (rad) between the estimated and true vertical seen from the sensor,
    ``angle(R_est^T e_z, R_true^T e_z)`` (heading is unobservable from gyro + accelerometer)."""
    ve = matrix_from_quat(quat_est)[..., 2, :]
    vt = matrix_from_quat(quat_true)[..., 2, :]
    return np.arctan2(np.linalg.norm(np.cross(ve, vt), axis=-1), np.sum(ve * vt, axis=-1))


def still_start(gyr: np.ndarray, acc: np.ndarray) -> int:
    """How many samples the recording starts with still: |gyro| < 0.05 rad/s and
    | |a| - g | < 0.3 m/s^2 (the rest test of ``rest_start`` and :func:`rest_bias`)."""
    still = (np.linalg.norm(gyr, axis=1) < 0.05) & (
        np.abs(np.linalg.norm(acc, axis=1) - _GRAVITY) < 0.3)
    return int(np.argmin(still)) if not still.all() else len(still)


def rest_bias(t: np.ndarray, gyr: np.ndarray, acc: np.ndarray) -> np.ndarray | None:
    """The gyro bias (rad/s) as the mean gyro over a still start (|gyro| < 0.05 rad/s and
    | |a| - g | < 0.3 m/s^2 for at least 0.5 s: the calibration pose), or None. Without a
    magnetometer the vertical component of the bias is unobservable in motion, and each sensor's
    heading would drift by it (0.005 rad/s is 4 deg in 15 s)."""
    n0 = still_start(gyr, acc)
    if n0 < 2 or t[n0 - 1] - t[0] < REST_START_S:
        return None
    return gyr[:n0].mean(axis=0)


def filter_orientations(
    time: np.ndarray,
    gyr: np.ndarray,
    acc: np.ndarray,
    mag: np.ndarray | None = None,
    *,
    method: str = "vqf",
) -> np.ndarray:
    """Sensor orientations ``(N, 4)`` (wxyz, sensor -> world, world z up) from raw signals.

    ``'vqf'``: VQF (Laidig & Seel 2023; PyPI ``vqf``, its offline variant, which also estimates
    the gyro bias), 9-D (world ENU, heading from the magnetometer) when ``mag`` is given, 6-D
    otherwise; a still start's mean gyro (:func:`rest_bias`) is removed first; ``'pi'``:
    :func:`mahony_filter` with :data:`TUNED` (6-D; a magnetometer is not
    used). Without a magnetometer each sensor's heading is its own, which the calibration pose
    absorbs into the sensor's placement. Samples must be evenly spaced (``time`` in s, ``gyr``
    rad/s, ``acc`` m/s^2, ``mag`` any unit).
    """
    if method not in FILTERS:
        raise InputError(f"expected a filter in {FILTERS}, got {method!r}", field="filter")
    t = np.asarray(time, dtype=float)
    gyr = np.ascontiguousarray(gyr, dtype=float)
    acc = np.ascontiguousarray(acc, dtype=float)
    for name, a in (("gyr", gyr), ("acc", acc)):
        if a.shape != (t.size, 3) or not np.all(np.isfinite(a)):
            bad = int(np.sum(~np.all(np.isfinite(a), axis=1))) if a.ndim == 2 else a.size
            raise InputError(f"expected {t.size} finite samples of 3 values, got shape "
                             f"{a.shape} with {bad} missing", field=name)
    return _FILTERS[method](t, gyr, acc, mag)


#: A recording that does not start still gets its first attitude from the filter run backwards
#: over at most this long (s) from there: several of the filter's time constants.
BACKWARD_START_S = 20.0


def _starts_moving(gyr: np.ndarray, acc: np.ndarray, period: float) -> bool:
    """Whether the sensor moves over its first half second: faster than 0.2 rad/s, or its
    specific force more than 1 m/s^2 from 1 g (a standing subject's sway stays well within)."""
    k = max(1, int(round(0.5 / period)))
    moving = np.linalg.norm(gyr[:k], axis=1) > 0.2
    return bool(moving.any() or np.any(np.abs(np.linalg.norm(acc[:k], axis=1) - _GRAVITY) > 1.0))


def _pi(t: np.ndarray, gyr: np.ndarray, acc: np.ndarray, mag: np.ndarray | None) -> np.ndarray:
    """Hu 2021's PI filter (eq 43-50) with :data:`TUNED` gains; 6-D (``mag`` is not used).

    Its first attitude: the still start's (``rest_start``) or the first accelerometer sample's
    where the sensor starts at rest (:func:`_starts_moving`), else the filter's own estimate at
    the first sample from a backward pass (time reversed: the gyroscope negated) over the first
    :data:`BACKWARD_START_S`. A recording that starts mid-walk otherwise starts from one
    accelerometer sample, which a swinging shank's centripetal and linear accelerations turn
    tens of degrees from the vertical, and the filter's gains take seconds to correct it (S02
    cut to start mid-walk: a leg's angles 17-50 deg RMS off)."""
    period = float(np.median(np.diff(t)))
    if not _starts_moving(gyr, acc, period) or len(t) < 3:
        return mahony_filter(t, gyr, acc, **TUNED).quat
    k = min(len(t), max(2, int(BACKWARD_START_S / period)))
    back = mahony_filter(t[:k], -gyr[:k][::-1], acc[:k][::-1],
                         **{**TUNED, "rest_start": False})
    return mahony_filter(t, gyr, acc, q0=back.quat[-1], **TUNED).quat


def _vqf(t: np.ndarray, gyr: np.ndarray, acc: np.ndarray, mag: np.ndarray | None) -> np.ndarray:
    """VQF (offline), 9-D with ``mag``, after a still start's gyro bias is removed."""
    from vqf import offlineVQF  # the field's reference filter (compiled)

    bias = rest_bias(t, gyr, acc)
    if bias is not None:
        gyr = np.ascontiguousarray(gyr - bias)
    period = float(np.median(np.diff(t)))
    if mag is not None:
        mag = np.ascontiguousarray(mag, dtype=float)
        if mag.shape != gyr.shape or not np.all(np.isfinite(mag)):
            raise InputError(f"expected {t.size} finite magnetometer samples", field="mag")
        return np.asarray(offlineVQF(gyr, acc, mag, period)["quat9D"])
    return np.asarray(offlineVQF(gyr, acc, None, period)["quat6D"])


#: Filter name (:data:`~pipeline.calibration.conventions.FILTERS`) -> the function that runs it.
_FILTERS = {"vqf": _vqf, "pi": _pi}
#: The filters that take a magnetometer (9-D) when the sensor has a trusted one.
MAGNETOMETER_FILTERS = ("vqf",)
