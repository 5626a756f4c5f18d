"""Two-segment trials with known truth on the model-free chain (:mod:`pipeline.simulate.chain`):
a hinge or spherical joint between two IMUs, with motions rich in excitation or deliberately poor
(a still thigh, a supine hip flexion), for the Hu 2021 calibration tests and benchmarks."""

from __future__ import annotations

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import exp3, normalize, rot_x
from pipeline.simulate.chain import (
    UPRIGHT,
    JointTrial,
    Sinusoids,
    chain_kinematics,
    imu_signals,
    point_acceleration,
)

__all__ = ["hinge_trial", "spherical_trial"]


# ----------------------------------------------------------------------------- trial generators

_KINDS = ("rich", "supine_hip_flexion", "still_thigh", "poor")
_X, _Y, _Z = np.eye(3)
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
            UPRIGHT,
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
            UPRIGHT,
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
