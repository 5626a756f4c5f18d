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
from pipeline.rotations import exp3, normalize, quat_from_matrix, rot_x

__all__ = [
    "ImuSignals",
    "JointTrial",
    "Sinusoids",
    "chain_kinematics",
    "gravity_vector",
    "hinge_trial",
    "imu_signals",
    "point_acceleration",
    "pose_derivatives",
    "spherical_trial",
]

G = 9.81
AngleFn = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray]]


@dataclass(frozen=True)
class ImuSignals:
    """Signals of one IMU: ``gyr`` (rad/s) and ``acc`` (m/s^2, specific force incl. gravity) in
    the sensor frame, and the sensor orientation ``quat`` (sensor -> world, wxyz)."""

    time: np.ndarray
    gyr: np.ndarray
    acc: np.ndarray
    quat: np.ndarray


@dataclass(frozen=True)
class JointTrial:
    """Two IMUs on two segments joined by a joint, with the truth in each sensor frame.

    ``position_*``: joint centre in the sensor frame (sensor -> joint, m). ``axis_*``: hinge axis
    (unit, same physical direction in both frames, pointing to the subject's right), or None.
    ``gyr_dot_*``: noise-free angular acceleration in the sensor frames (for tests only).
    """

    imu_1: ImuSignals
    imu_2: ImuSignals
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
) -> ImuSignals:
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
    return ImuSignals(time=t, gyr=gyr, acc=acc, quat=quat_from_matrix(R_s))


# ----------------------------------------------------------------------------- trial generators

_KINDS = ("rich", "supine_hip_flexion", "still_thigh", "poor")
_X, _Y, _Z = np.eye(3)
_STANDING = rot_x(np.pi / 2)  # ISB segment (y up) -> z-up world
_SUPINE = rot_x(np.pi / 2) @ np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]])  # y -> head, x -> up


def _deg(*a: float) -> list[float]:
    return [np.deg2rad(x) for x in a]


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    return exp3(normalize(rng.normal(size=3)) * rng.uniform(0.3, np.pi))


def _proximal_motion(kind: str, rng: np.random.Generator, t: np.ndarray):
    """Chain elements and position/acceleration of the proximal segment origin."""
    ph = rng.uniform(0, 2 * np.pi, 8)
    if kind == "rich":
        base = [
            _STANDING,
            (_Y, Sinusoids(0.0, _deg(25, 8), [0.21, 0.9], ph[:2])),
            (_Z, Sinusoids(np.deg2rad(10), _deg(25, 8), [0.9, 1.7], ph[2:4])),
            (_X, Sinusoids(0.0, _deg(8, 4), [0.6, 1.3], ph[4:6])),
            (_Y, Sinusoids(0.0, _deg(10, 5), [0.45, 1.1], ph[6:8])),
        ]
        pos = [
            Sinusoids(0.0, [0.1, 0.03], [0.3, 0.9], ph[:2]),
            Sinusoids(0.0, [0.05, 0.02], [0.45, 0.9], ph[2:4]),
            Sinusoids(0.9, [0.03, 0.01], [1.8, 0.9], ph[4:6]),
        ]
    elif kind == "supine_hip_flexion":
        base = [
            _SUPINE,
            (_Z, Sinusoids(np.deg2rad(30), _deg(28, 4), [0.25, 0.6], ph[:2])),
            (_X, Sinusoids(0.0, _deg(1.5, 0.7), [0.37, 1.1], ph[2:4])),
            (_Y, Sinusoids(0.0, _deg(2.0, 0.8), [0.31, 0.9], ph[4:6])),
        ]
        pos = [Sinusoids(0.0, [0.002], [0.4], ph[:1]), Sinusoids(0.0), Sinusoids(0.2)]
    else:  # still proximal segment: seated, thigh horizontal, physiological tremor only
        base = [
            _STANDING,
            (_Z, Sinusoids(np.deg2rad(90), _deg(0.3, 0.1), [0.5, 3.1], ph[:2])),
            (_X, Sinusoids(0.0, _deg(0.2, 0.1), [0.7, 2.7], ph[2:4])),
            (_Y, Sinusoids(0.0, _deg(0.2), [0.6], ph[4:5])),
        ]
        pos = [Sinusoids(0.0), Sinusoids(0.0), Sinusoids(0.5, [0.0005], [0.8], ph[5:6])]
    p = np.stack([f(t)[0] for f in pos], axis=1)
    a = np.stack([f(t)[2] for f in pos], axis=1)
    return base, p, a


def _distal_angles(joint: str, kind: str, rng: np.random.Generator) -> list[Sinusoids]:
    ph = rng.uniform(0, 2 * np.pi, 6)
    if joint == "hinge":
        if kind == "rich":
            return [Sinusoids(np.deg2rad(-35), _deg(30, 8), [0.9, 1.8], ph[:2])]
        if kind == "supine_hip_flexion":
            return [Sinusoids(np.deg2rad(-45), _deg(40, 5), [0.25, 0.6], ph[:2])]
        return [Sinusoids(np.deg2rad(-50), _deg(35, 10), [0.4, 1.1], ph[:2])]
    if kind == "rich":
        return [
            Sinusoids(0.0, _deg(30, 8), [0.9, 1.6], ph[:2]),
            Sinusoids(0.0, _deg(12, 5), [0.55, 1.3], ph[2:4]),
            Sinusoids(0.0, _deg(15, 5), [0.4, 1.2], ph[4:6]),
        ]
    if kind == "supine_hip_flexion":
        return [
            Sinusoids(np.deg2rad(30), _deg(35, 5), [0.25, 0.6], ph[:2]),
            Sinusoids(0.0, _deg(2), [0.4], ph[2:3]),
            Sinusoids(0.0, _deg(2), [0.3], ph[4:5]),
        ]
    return [
        Sinusoids(np.deg2rad(20), _deg(30, 8), [0.4, 1.1], ph[:2]),
        Sinusoids(0.0, _deg(8), [0.5], ph[2:3]),
        Sinusoids(0.0, _deg(10), [0.35], ph[4:5]),
    ]


def _two_segment_trial(
    joint: str,
    kind: str,
    seed: int,
    duration: float,
    rate: float,
    gyro_noise: float,
    acc_noise: float,
    gyro_bias: float,
) -> JointTrial:
    if kind not in _KINDS:
        raise InputError(f"expected a motion kind in {_KINDS}, got {kind!r}", field="kind")
    if duration <= 0 or rate <= 0:
        raise InputError(f"expected positive duration and rate, got {duration}, {rate}")
    rng = np.random.default_rng(seed)
    t = np.arange(int(round(duration * rate))) / rate
    if joint == "hinge":  # thigh (origin hip) + shank (origin knee centre)
        joint_in_1 = np.array([0.0, -0.42, 0.0])
        r1 = np.array([0.03, -0.25, 0.07]) + rng.uniform(-0.01, 0.01, 3)
        r2 = np.array([0.03, -0.15, 0.05]) + rng.uniform(-0.01, 0.01, 3)
    else:  # pelvis (origin mid-hip) + thigh (origin right hip centre)
        joint_in_1 = np.array([0.0, 0.0, 0.085])
        r1 = np.array([-0.10, 0.05, 0.0]) + rng.uniform(-0.01, 0.01, 3)
        r2 = np.array([0.03, -0.17, 0.07]) + rng.uniform(-0.01, 0.01, 3)
    R_imu_1, R_imu_2 = _random_rotation(rng), _random_rotation(rng)
    base, p1, a1 = _proximal_motion(kind, rng, t)
    R1, w1, dw1 = chain_kinematics(t, base)
    if joint == "hinge":
        axis = exp3(np.deg2rad([4.0, 6.0, 0.0]) * rng.uniform(-1, 1, 3)) @ _Z
        distal = [(axis, f) for f in _distal_angles(joint, kind, rng)]
    else:
        axis = None
        distal = list(zip((_Z, _X, _Y), _distal_angles(joint, kind, rng), strict=True))
    R2, w2, dw2 = chain_kinematics(t, base + distal)
    p2 = p1 + R1 @ joint_in_1
    a2 = point_acceleration(R1, w1, dw1, a1, joint_in_1)
    sig = []
    for R, p, a, w, dw, r, Ri in (
        (R1, p1, a1, w1, dw1, r1, R_imu_1),
        (R2, p2, a2, w2, dw2, r2, R_imu_2),
    ):
        sig.append(
            imu_signals(
                t,
                R,
                p,
                r,
                Ri,
                omega=w,
                omega_dot=dw,
                acc_origin=a,
                gyro_noise=gyro_noise,
                acc_noise=acc_noise,
                gyro_bias=rng.normal(0.0, gyro_bias, 3) if gyro_bias else (0, 0, 0),
                rng=rng,
            )
        )
    return JointTrial(
        imu_1=sig[0],
        imu_2=sig[1],
        joint=joint,
        kind=kind,
        position_1=R_imu_1.T @ (joint_in_1 - r1),
        position_2=R_imu_2.T @ (-r2),
        axis_1=None if axis is None else R_imu_1.T @ axis,
        axis_2=None if axis is None else R_imu_2.T @ axis,
        gyr_dot_1=dw1 @ R_imu_1,
        gyr_dot_2=dw2 @ R_imu_2,
        R_imu_1=R_imu_1,
        R_imu_2=R_imu_2,
    )


def hinge_trial(
    kind: str = "rich",
    *,
    seed: int = 0,
    duration: float = 15.0,
    rate: float = 100.0,
    gyro_noise: float = 0.01,
    acc_noise: float = 0.05,
    gyro_bias: float = 0.0,
) -> JointTrial:
    """Thigh and shank IMUs across a knee hinge (axis ~ the thigh z axis, tilted a few degrees).

    ``kind``: 'rich' (walking-like: pelvis yaw, 3-D hip motion, knee 0-80 deg flexion, trunk
    translation), 'supine_hip_flexion' (lying, hip and knee flexing about near-parallel axes),
    'still_thigh'/'poor' (seated knee swings, thigh tremor < 0.5 deg). ``gyro_bias`` is the SD of
    a constant per-sensor bias (rad/s).
    """
    return _two_segment_trial("hinge", kind, seed, duration, rate, gyro_noise, acc_noise, gyro_bias)


def spherical_trial(
    kind: str = "rich",
    *,
    seed: int = 0,
    duration: float = 15.0,
    rate: float = 100.0,
    gyro_noise: float = 0.01,
    acc_noise: float = 0.05,
    gyro_bias: float = 0.0,
) -> JointTrial:
    """Pelvis (sacrum) and thigh IMUs across a spherical hip joint; kinds as :func:`hinge_trial`
    ('still_thigh'/'poor' here means the pelvis, the proximal segment, is nearly still)."""
    return _two_segment_trial(
        "spherical", kind, seed, duration, rate, gyro_noise, acc_noise, gyro_bias
    )
