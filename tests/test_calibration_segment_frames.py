"""Hu 2021 eq 30-42: segment frames from a calibration; the ZXY joint angles of eq 39-42 (their
one home is pipeline.rotations) on the joint rotations those frames give."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.segment_frames import (
    joint_rotation,
    parallel_frame,
    segment_orientation,
    shank_frame,
    thigh_frame,
)
from pipeline.errors import InputError
from pipeline.rotations import (
    euler_zxy_from_matrix,
    exp3,
    matrix_from_euler_zxy,
    rot_x,
    rot_y,
    rot_z,
)
from pipeline.simulate.chain import Sinusoids, chain_kinematics


def test_zxy_by_hand_and_round_trip():
    np.testing.assert_allclose(euler_zxy_from_matrix(rot_z(0.5)), [0.5, 0, 0], atol=1e-15)
    np.testing.assert_allclose(euler_zxy_from_matrix(rot_x(-0.2)), [0, -0.2, 0], atol=1e-15)
    np.testing.assert_allclose(euler_zxy_from_matrix(rot_y(1.0)), [0, 0, 1.0], atol=1e-15)
    rng = np.random.default_rng(0)
    ang = rng.uniform([-3, -1.4, -3], [3, 1.4, 3], (200, 3))
    R = matrix_from_euler_zxy(ang)
    np.testing.assert_allclose(euler_zxy_from_matrix(R), ang, atol=1e-12)
    # eq 39 entries: r32 = sin(b), r12 = -sin(a) cos(b), r31 = -cos(b) sin(c)
    a, b, c = ang[0]
    assert R[0, 2, 1] == pytest.approx(np.sin(b))
    assert R[0, 0, 1] == pytest.approx(-np.sin(a) * np.cos(b))
    assert R[0, 2, 0] == pytest.approx(-np.cos(b) * np.sin(c))


@pytest.mark.parametrize("b", [np.pi / 2, -np.pi / 2])
def test_gimbal_lock_eq41_42(b):
    R = matrix_from_euler_zxy([0.7, b, -0.4])
    out = euler_zxy_from_matrix(R, gimbal_tol=1e-6)
    assert out[0] == 0.0 and out[1] == pytest.approx(b)
    np.testing.assert_allclose(matrix_from_euler_zxy(out), R, atol=1e-9)


def test_thigh_and_shank_frames_by_hand():
    hip, knee, z = np.array([0.0, 0.3, 0.0]), np.array([0.0, -0.1, 0.05]), np.array([0, 0, 1.0])
    np.testing.assert_allclose(thigh_frame(hip, knee, z), np.eye(3), atol=1e-15)
    ankle = np.array([0.02, -0.45, 0.01])
    F = shank_frame(ankle, knee, z)
    np.testing.assert_allclose(F[:, 2], z, atol=1e-15)
    np.testing.assert_allclose(F[:, 1], [-0.02, 0.35, 0] / np.hypot(0.02, 0.35), atol=1e-15)
    np.testing.assert_allclose(F.T @ F, np.eye(3), atol=1e-15)
    assert np.linalg.det(F) == pytest.approx(1.0)
    with pytest.raises(InputError):
        thigh_frame(knee, knee, z)


def test_frames_from_sensor_truth_give_the_knee_angle():
    t = np.arange(500) / 100.0
    flex = Sinusoids(-0.6, [0.5], [0.8], [0.0])
    R_thigh, _, _ = chain_kinematics(
        t, [rot_x(np.pi / 2), (np.array([0, 0, 1.0]), Sinusoids(0.2, [0.4], [0.5], [1.0]))]
    )
    R_shank = R_thigh @ rot_z(flex(t)[0])
    Ri1, Ri2 = exp3(np.array([0.4, 1.2, -0.3])), exp3(np.array([-2.0, 0.1, 0.5]))
    r1, r2 = np.array([0.03, -0.25, 0.07]), np.array([0.03, -0.15, 0.05])
    # truth in sensor frames: hip at the thigh origin, knee at (0, -0.42, 0), ankle at (0, -0.4, 0)
    F_thigh = thigh_frame(Ri1.T @ -r1, Ri1.T @ ([0, -0.42, 0] - r1), Ri1.T @ [0, 0, 1.0])
    F_shank = shank_frame(Ri2.T @ ([0, -0.4, 0] - r2), Ri2.T @ -r2, Ri2.T @ [0, 0, 1.0])
    np.testing.assert_allclose(F_thigh, Ri1.T, atol=1e-12)
    np.testing.assert_allclose(F_shank, Ri2.T, atol=1e-12)
    R1 = segment_orientation(R_thigh @ Ri1, F_thigh)
    R2 = segment_orientation(R_shank @ Ri2, F_shank)
    np.testing.assert_allclose(R1, R_thigh, atol=1e-12)
    ang = euler_zxy_from_matrix(joint_rotation(R1, R2))
    np.testing.assert_allclose(ang[:, 0], flex(t)[0], atol=1e-12)
    np.testing.assert_allclose(ang[:, 1:], 0, atol=1e-12)


def test_parallel_frame_eq37():
    Ra0, Rb0 = exp3(np.array([0.1, 0.5, -0.2])), exp3(np.array([1.0, -0.3, 0.2]))
    Fa = exp3(np.array([0.0, 0.3, 0.9]))
    Fb = parallel_frame(Fa, Ra0, Rb0)
    np.testing.assert_allclose(Rb0 @ Fb, Ra0 @ Fa, atol=1e-15)
