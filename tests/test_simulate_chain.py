"""Signal-level IMU simulator: signals vs finite differences of the poses, truth consistency."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.rotations import exp3, matrix_from_quat
from pipeline.simulate.chain import Sinusoids, chain_kinematics, gravity_vector, imu_signals
from pipeline.simulate.joint_trials import hinge_trial, spherical_trial

RATE = 1000.0
T = np.arange(int(2 * RATE)) / RATE
R_IMU = exp3(np.array([0.3, -1.1, 0.7]))
R_OFF = np.array([0.05, -0.2, 0.08])


def _motion():
    elements = [
        exp3(np.array([1.2, 0.1, 0.0])),
        (np.array([0.0, 1.0, 0.0]), Sinusoids(0.1, [0.6, 0.2], [0.7, 1.9], [0.3, 1.0])),
        (np.array([1.0, 0.0, 1.0]), Sinusoids(0.0, [0.4], [1.3], [0.2])),
        (np.array([0.0, 0.0, 1.0]), Sinusoids(-0.5, [0.8, 0.1], [0.9, 2.5], [1.0, 0.1])),
    ]
    R, w, dw = chain_kinematics(T, elements)
    fx, fy, fz = (
        Sinusoids(c, [a], [f], [p])
        for c, a, f, p in ((0.0, 0.3, 0.5, 0.1), (1.0, 0.1, 1.1, 0.7), (0.9, 0.05, 2.0, 0.0))
    )
    p = np.stack([f(T)[0] for f in (fx, fy, fz)], axis=1)
    a = np.stack([f(T)[2] for f in (fx, fy, fz)], axis=1)
    return R, p, w, dw, a


def _vee(M):
    return 0.5 * np.stack(
        [M[..., 2, 1] - M[..., 1, 2], M[..., 0, 2] - M[..., 2, 0], M[..., 1, 0] - M[..., 0, 1]],
        axis=-1,
    )


def test_signals_match_finite_differences_of_poses():
    R, p, w, dw, a = _motion()
    sig = imu_signals(T, R, p, R_OFF, R_IMU, omega=w, omega_dot=dw, acc_origin=a)
    Rs = matrix_from_quat(sig.quat)
    np.testing.assert_allclose(Rs, R @ R_IMU, atol=1e-12)
    h = 1.0 / RATE
    # gyro: [w]x = R^T dR/dt, central differences
    w_fd = _vee(np.swapaxes(Rs[1:-1], 1, 2) @ (Rs[2:] - Rs[:-2]) / (2 * h))
    assert np.max(np.abs(w_fd - sig.gyr[1:-1])) < 1e-4 * np.max(np.abs(sig.gyr)) + 1e-5
    # accelerometer: second difference of the sensor position, minus gravity, in the sensor frame
    ps = p + R @ R_OFF
    a_fd = (ps[2:] - 2 * ps[1:-1] + ps[:-2]) / h**2 - gravity_vector("z")
    acc_fd = np.einsum("nji,nj->ni", Rs[1:-1], a_fd)
    assert np.max(np.abs(acc_fd - sig.acc[1:-1])) < 1e-3
    # angular acceleration: central difference of the exact body rate
    dw_fd = (w[2:] - w[:-2]) / (2 * h)
    assert np.max(np.abs(dw_fd - dw[1:-1])) < 1e-4 * np.max(np.abs(dw))


def test_spline_derivatives_match_exact_ones():
    R, p, w, dw, a = _motion()
    exact = imu_signals(
        T[::10],
        R[::10],
        p[::10],
        R_OFF,
        R_IMU,
        omega=w[::10],
        omega_dot=dw[::10],
        acc_origin=a[::10],
    )
    spline = imu_signals(T[::10], R[::10], p[::10], R_OFF, R_IMU)  # 100 Hz, differentiated
    inner = slice(5, -5)
    assert np.max(np.abs(spline.gyr[inner] - exact.gyr[inner])) < 1e-4
    assert np.max(np.abs(spline.acc[inner] - exact.acc[inner])) < 5e-3


def test_static_sensor_reads_gravity_up_and_noise_sd():
    n = 2000
    t = np.arange(n) / 100.0
    R = np.broadcast_to(np.eye(3), (n, 3, 3))
    sig = imu_signals(
        t,
        R,
        np.zeros((n, 3)),
        np.zeros(3),
        np.eye(3),
        gyro_noise=0.01,
        acc_noise=0.05,
        gyro_bias=[0.1, 0, 0],
        rng=3,
    )
    np.testing.assert_allclose(sig.acc.mean(axis=0), [0, 0, 9.81], atol=0.01)
    np.testing.assert_allclose(sig.acc.std(axis=0), 0.05, rtol=0.1)
    np.testing.assert_allclose(sig.gyr.std(axis=0), 0.01, rtol=0.1)
    np.testing.assert_allclose(sig.gyr.mean(axis=0), [0.1, 0, 0], atol=0.002)
    np.testing.assert_allclose(gravity_vector("y"), [0, -9.81, 0])


@pytest.mark.parametrize("make", [hinge_trial, spherical_trial])
@pytest.mark.parametrize("kind", ["rich", "supine_hip_flexion", "still_thigh"])
def test_truth_is_consistent(make, kind):
    tr = make(kind, duration=3.0, gyro_noise=0.0, acc_noise=0.0)
    R1, R2 = matrix_from_quat(tr.imu_1.quat), matrix_from_quat(tr.imu_2.quat)

    # the specific force at the joint centre is one physical vector (Hu eq 1-2)
    def joint_force(s, dw, o):
        return s.acc + np.cross(s.gyr, np.cross(s.gyr, o)) + np.cross(dw, o)

    f1 = np.einsum("nij,nj->ni", R1, joint_force(tr.imu_1, tr.gyr_dot_1, tr.position_1))
    f2 = np.einsum("nij,nj->ni", R2, joint_force(tr.imu_2, tr.gyr_dot_2, tr.position_2))
    np.testing.assert_allclose(f1, f2, atol=1e-9)
    assert np.all(np.abs(tr.position_1) <= 0.2) and np.all(np.abs(tr.position_2) <= 0.2)
    if tr.joint == "hinge":
        a1, a2 = R1 @ tr.axis_1, R2 @ tr.axis_2
        np.testing.assert_allclose(a1, a2, atol=1e-12)
        rel = np.einsum("nij,nj->ni", R2, tr.imu_2.gyr) - np.einsum("nij,nj->ni", R1, tr.imu_1.gyr)
        np.testing.assert_allclose(np.cross(rel, a1), 0, atol=1e-9)  # rotation about the axis
    if kind == "still_thigh":
        assert np.max(np.abs(tr.imu_1.gyr)) < 0.1 < np.max(np.abs(tr.imu_2.gyr))


def test_seeded_and_validated():
    a, b = hinge_trial(seed=4, duration=1.0), hinge_trial(seed=4, duration=1.0)
    c = hinge_trial(seed=5, duration=1.0)
    np.testing.assert_array_equal(a.imu_1.acc, b.imu_1.acc)
    assert not np.allclose(a.imu_1.acc, c.imu_1.acc)
    noisy = hinge_trial(seed=4, duration=1.0)
    clean = hinge_trial(seed=4, duration=1.0, gyro_noise=0.0, acc_noise=0.0)
    assert 0.007 < np.std(noisy.imu_1.gyr - clean.imu_1.gyr) < 0.013
    with pytest.raises(InputError):
        hinge_trial("jumping")
    with pytest.raises(InputError):
        imu_signals(T[:5], np.zeros((4, 3, 3)), np.zeros((5, 3)), np.zeros(3), np.eye(3))
