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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import matrix_from_quat, quat_from_matrix, rotation_aligning

__all__ = ["AttitudeEstimate", "mahony_filter", "tilt_error"]


@dataclass(frozen=True)
class AttitudeEstimate:
    """Filter output: ``quat`` (N,4) sensor -> world wxyz, ``bias`` (N,3) estimated gyro bias
    (rad/s, sensor frame), ``error`` (N,3) the eq-47 error vector."""

    time: np.ndarray
    quat: np.ndarray
    bias: np.ndarray
    error: np.ndarray


def mahony_filter(
    time: np.ndarray,
    gyr: np.ndarray,
    acc: np.ndarray,
    *,
    lambda_p: float | None = None,
    lambda_i: float | None = None,
    q0: np.ndarray | str | None = "acc",
) -> AttitudeEstimate:
    """Run the eq 44-50 filter over gyro (rad/s) and accelerometer (m/s^2) samples (N,3)."""
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
        q = quat_from_matrix(rotation_aligning(acc[0], [0.0, 0.0, 1.0]))
    else:
        q = np.array([1.0, 0.0, 0.0, 0.0]) if q0 is None else np.asarray(q0, float)  # eq 44
    q0_, q1, q2, q3 = (float(v) for v in q / np.linalg.norm(q))
    ix = iy = iz = 0.0
    dts = np.diff(t, prepend=t[0] - period)
    out_q = np.empty((n, 4))
    out_b = np.empty((n, 3))
    out_e = np.empty((n, 3))
    for k in range(n):
        dt = dts[k]
        gx, gy, gz = gyr[k]
        ax, ay, az = acc[k]
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
    return AttitudeEstimate(time=t, quat=out_q, bias=out_b, error=out_e)


def tilt_error(quat_est: np.ndarray, quat_true: np.ndarray) -> np.ndarray:
    """Angle (rad) between the estimated and true vertical seen from the sensor,
    ``angle(R_est^T e_z, R_true^T e_z)`` (heading is unobservable from gyro + accelerometer)."""
    ve = matrix_from_quat(quat_est)[..., 2, :]
    vt = matrix_from_quat(quat_true)[..., 2, :]
    return np.arctan2(np.linalg.norm(np.cross(ve, vt), axis=-1), np.sum(ve * vt, axis=-1))
