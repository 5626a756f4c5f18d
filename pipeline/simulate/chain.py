"""Signal-level IMU simulator: gyroscope and accelerometer signals of sensors on moving segments.

Core (generic, reusable by a model-based layer):

* :func:`imu_signals` - a sensor rigidly fixed on a segment with pose ``(R_seg, p_seg)``:
  ``gyr = R_imu^T w``, with ``w`` the segment's body angular velocity (``[w]x = R^T dR/dt``), and
  ``acc = (R_seg R_imu)^T (p_ddot_sensor - g)`` (specific force, reads ``+9.81`` up at rest), where
  ``p_ddot_sensor = p_ddot + R (dw x r + w x (w x r))`` (:func:`point_acceleration`).
  Derivatives are exact when passed in (analytic trajectories), otherwise they come from a
  quintic interpolating spline through the dense poses (:func:`pose_derivatives`).
* :func:`chain_kinematics` - exact orientation, body angular velocity and acceleration of a
  product of constant rotations and rotations about fixed axes by angles ``theta(t)``:
  ``w_i = R_i^T w_{i-1} + e_i theta_dot_i`` and
  ``dw_i = R_i^T dw_{i-1} - theta_dot_i e_i x (R_i^T w_{i-1}) + e_i theta_ddot_i``.

Trial generators (seeded): :func:`hinge_trial` (thigh + shank, knee hinge about a known axis) and
:func:`spherical_trial` (pelvis + thigh, ball-and-socket hip), with motion kinds ``'rich'``
(gait-like, multi-axis), ``'supine_hip_flexion'`` (lying, hip and knee flexion in one plane, as in
the Wang 2023 recordings) and ``'still_thigh'`` / ``'poor'`` (proximal segment nearly still).
World frame: z up (gravity ``(0, 0, -9.81)``); segment frames ISB (x anterior, y up, z right).
Truth (joint centre and axis in each *sensor* frame) is returned with the signals.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import make_interp_spline

from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.rotations import exp3, normalize, quat_from_matrix, rot_x

__all__ = [
    "UPRIGHT",
    "JointTrial",
    "Sinusoids",
    "chain_kinematics",
    "gravity_vector",
    "imu_signals",
    "point_acceleration",
    "pose_derivatives",
]

G = 9.81
#: An upright ISB segment (y up, z right) in the simulator's z-up world, facing +x.
UPRIGHT = rot_x(np.pi / 2)
AngleFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class JointTrial:
    """Two IMUs on two segments joined by a joint, with the truth in each sensor frame.

    ``position_*``: joint centre in the sensor frame (sensor -> joint, m). ``axis_*``: hinge axis
    (unit, same physical direction in both frames, pointing to the subject's right), or None.
    ``gyr_dot_*``: noise-free angular acceleration in the sensor frames (for tests only).
    """

    imu_1: Recording
    imu_2: Recording
    joint: str
    kind: str
    position_1: np.ndarray
    position_2: np.ndarray
    axis_1: np.ndarray | None
    axis_2: np.ndarray | None
    gyr_dot_1: np.ndarray
    gyr_dot_2: np.ndarray
    R_imu_1: np.ndarray
    R_imu_2: np.ndarray

    @property
    def time(self) -> np.ndarray:
        return self.imu_1.time


def gravity_vector(up: str = "z", g: float = G) -> np.ndarray:
    """Gravity in a world whose vertical axis is ``up`` ('x', 'y' or 'z'): ``-g e_up``."""
    if up not in ("x", "y", "z"):
        raise InputError(f"expected up axis 'x', 'y' or 'z', got {up!r}", field="up")
    out = np.zeros(3)
    out["xyz".index(up)] = -g
    return out


@dataclass(frozen=True)
class Sinusoids:
    """``theta(t) = offset + rate t + sum_k amp_k sin(2 pi freq_k t + phase_k)``, exact rates."""

    offset: float = 0.0
    amp: Sequence[float] = ()
    freq: Sequence[float] = ()
    phase: Sequence[float] = ()
    rate: float = 0.0

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        th = self.offset + self.rate * t
        dth = np.full_like(t, self.rate)
        ddth = np.zeros_like(t)
        for a, f, p in zip(self.amp, self.freq, self.phase, strict=True):
            w = 2 * np.pi * f
            th = th + a * np.sin(w * t + p)
            dth = dth + a * w * np.cos(w * t + p)
            ddth = ddth - a * w * w * np.sin(w * t + p)
        return th, dth, ddth


def chain_kinematics(
    time: np.ndarray, elements: Sequence[np.ndarray | tuple[np.ndarray, AngleFn]]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact ``R (N,3,3)``, body ``w (N,3)`` and ``dw (N,3)`` of ``R = prod_i R_i``.

    Each element is a constant ``(3,3)`` rotation or ``(axis, angle_fn)``: a rotation by
    ``theta(t)`` about the fixed unit ``axis``; ``angle_fn(t) -> (theta, theta_dot, theta_ddot)``.
    """
    t = np.asarray(time, dtype=float)
    n = t.size
    R = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    w = np.zeros((n, 3))
    dw = np.zeros((n, 3))
    for el in elements:
        if isinstance(el, tuple):
            e = normalize(np.asarray(el[0], dtype=float))
            th, dth, ddth = el[1](t)
            Ri = exp3(th[:, None] * e)
            wr = np.einsum("nji,nj->ni", Ri, w)
            dw = (
                np.einsum("nji,nj->ni", Ri, dw) - dth[:, None] * np.cross(e, wr) + np.outer(ddth, e)
            )
            w = wr + np.outer(dth, e)
        else:
            Ri = np.broadcast_to(np.asarray(el, dtype=float), (n, 3, 3))
            w = np.einsum("nji,nj->ni", Ri, w)
            dw = np.einsum("nji,nj->ni", Ri, dw)
        R = R @ Ri
    return R, w, dw


def point_acceleration(
    R: np.ndarray, w: np.ndarray, dw: np.ndarray, acc_origin: np.ndarray, r: np.ndarray
) -> np.ndarray:
    """World acceleration of the point ``r`` (segment frame): ``a + R (dw x r + w x (w x r))``."""
    local = np.cross(dw, r) + np.cross(w, np.cross(w, r))
    return acc_origin + np.einsum("nij,nj->ni", R, local)


def pose_derivatives(
    time: np.ndarray, R: np.ndarray, p: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body ``w``, ``dw`` and world ``p_ddot`` of dense poses by quintic interpolating splines.

    ``[w]x = R^T R'`` and ``[dw]x = R'^T R' + R^T R''`` (skew parts, since ``R`` is only
    approximately orthonormal between samples).
    """
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or t.size < 6 or np.any(np.diff(t) <= 0):
        raise InputError("expected >= 6 strictly increasing time samples", field="time")
    sR = make_interp_spline(t, np.asarray(R, dtype=float).reshape(-1, 9), k=5)
    sp = make_interp_spline(t, np.asarray(p, dtype=float), k=5)
    R1 = sR.derivative(1)(t).reshape(-1, 3, 3)
    R2 = sR.derivative(2)(t).reshape(-1, 3, 3)
    Rt = np.swapaxes(R, 1, 2)
    W = Rt @ R1
    DW = np.swapaxes(R1, 1, 2) @ R1 + Rt @ R2

    def vee(M: np.ndarray) -> np.ndarray:
        A = 0.5 * (M - np.swapaxes(M, 1, 2))
        return np.stack([A[:, 2, 1], A[:, 0, 2], A[:, 1, 0]], axis=1)

    return vee(W), vee(DW), sp.derivative(2)(t)


def imu_signals(
    time: np.ndarray,
    R_seg: np.ndarray,
    p_seg: np.ndarray,
    r_imu: np.ndarray,
    R_imu: np.ndarray,
    *,
    omega: np.ndarray | None = None,
    omega_dot: np.ndarray | None = None,
    acc_origin: np.ndarray | None = None,
    gravity: np.ndarray | Sequence[float] = (0.0, 0.0, -G),
    gyro_noise: float = 0.0,
    acc_noise: float = 0.0,
    gyro_bias: np.ndarray | Sequence[float] = (0.0, 0.0, 0.0),
    rng: np.random.Generator | int | None = None,
) -> Recording:
    """Gyro and accelerometer signals of a sensor at ``r_imu`` with orientation ``R_imu`` (both in
    the segment frame) on a segment with pose ``R_seg (N,3,3)``, ``p_seg (N,3)``.

    ``omega``/``omega_dot`` (body frame of the segment) and ``acc_origin`` (world acceleration of
    the segment origin) are used when given (exact), otherwise differentiated from the poses.
    White noise of SD ``gyro_noise`` / ``acc_noise`` and a constant ``gyro_bias`` are added.
    """
    t = np.asarray(time, dtype=float)
    R_seg = np.asarray(R_seg, dtype=float)
    p_seg = np.asarray(p_seg, dtype=float)
    n = t.size
    if R_seg.shape != (n, 3, 3) or p_seg.shape != (n, 3):
        raise InputError(
            f"expected R_seg (N,3,3) and p_seg (N,3) with N={n}, got {R_seg.shape}, {p_seg.shape}"
        )
    if omega is None or omega_dot is None or acc_origin is None:
        w, dw, a0 = pose_derivatives(t, R_seg, p_seg)
        omega = w if omega is None else omega
        omega_dot = dw if omega_dot is None else omega_dot
        acc_origin = a0 if acc_origin is None else acc_origin
    r = np.asarray(r_imu, dtype=float)
    Ri = np.asarray(R_imu, dtype=float)
    acc_world = point_acceleration(R_seg, omega, omega_dot, acc_origin, r)
    R_s = R_seg @ Ri
    gyr = omega @ Ri
    acc = np.einsum("nji,nj->ni", R_s, acc_world - np.asarray(gravity, dtype=float))
    gen = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    if gyro_noise > 0:
        gyr = gyr + gen.normal(0.0, gyro_noise, gyr.shape)
    if acc_noise > 0:
        acc = acc + gen.normal(0.0, acc_noise, acc.shape)
    gyr = gyr + np.asarray(gyro_bias, dtype=float)
    return Recording.single("imu", t, gyr=gyr, acc=acc, quat=quat_from_matrix(R_s))
