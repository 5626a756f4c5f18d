"""Hu 2021 eq 1-16: residuals, Jacobians, angular acceleration, signs."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.joint_constraints import (
    JointData,
    angular_acceleration,
    axis_from_spherical,
    consistent_axis_signs,
    gamma,
    hinge_jacobian,
    hinge_jacobian_spherical,
    hinge_residual,
    joint_data,
    project_hinge_positions,
    spherical_from_axis,
    spherical_jacobian,
    spherical_residual,
)
from pipeline.errors import InputError
from pipeline.simulate.joint_trials import hinge_trial, spherical_trial


def _exact(tr) -> JointData:
    return JointData(
        tr.imu_1.gyr, tr.imu_2.gyr, tr.imu_1.acc, tr.imu_2.acc, tr.gyr_dot_1, tr.gyr_dot_2
    )


@pytest.fixture(scope="module")
def clean_hinge():
    return hinge_trial("rich", duration=4.0, gyro_noise=0.0, acc_noise=0.0)


def test_gamma_by_hand():
    o = np.array([1.0, 0.0, 0.0])
    # pure spin about z at 1 rad/s: centripetal term -o; pure angular acceleration 2 about z
    np.testing.assert_allclose(gamma(np.array([[0, 0, 1.0]]), np.zeros((1, 3)), o), [[-1, 0, 0]])
    np.testing.assert_allclose(gamma(np.zeros((1, 3)), np.array([[0, 0, 2.0]]), o), [[0, 2, 0]])


@pytest.mark.parametrize("make", [hinge_trial, spherical_trial])
def test_residuals_vanish_at_truth_without_noise(make):
    tr = make("rich", duration=4.0, gyro_noise=0.0, acc_noise=0.0)
    d = _exact(tr)
    assert np.max(np.abs(spherical_residual(tr.position_1, tr.position_2, d))) < 1e-10
    wrong = spherical_residual(tr.position_1 + [0.02, 0, 0], tr.position_2, d)
    assert np.sqrt(np.mean(wrong**2)) > 1e-3
    if tr.axis_1 is not None:
        e = hinge_residual(tr.axis_1, tr.axis_2, tr.imu_1.gyr, tr.imu_2.gyr)
        assert np.max(np.abs(e)) < 1e-12
        e = hinge_residual(-tr.axis_1, tr.axis_2, tr.imu_1.gyr, tr.imu_2.gyr)  # sign-blind
        assert np.max(np.abs(e)) < 1e-12
        tilted = axis_from_spherical(*(np.array(spherical_from_axis(tr.axis_1)) + 0.05))
        assert (
            np.sqrt(np.mean(hinge_residual(tilted, tr.axis_2, tr.imu_1.gyr, tr.imu_2.gyr) ** 2))
            > 1e-3
        )


def _fd(f, x, h=1e-6):
    return np.stack([(f(x + h * e) - f(x - h * e)) / (2 * h) for e in np.eye(x.size)], axis=1)


def test_jacobians_match_finite_differences(clean_hinge):
    tr = clean_hinge
    d = _exact(tr)
    x = np.concatenate([tr.position_1, tr.position_2]) + 0.01
    num = _fd(lambda v: spherical_residual(v[:3], v[3:], d), x)
    np.testing.assert_allclose(spherical_jacobian(x[:3], x[3:], d), num, atol=1e-6)
    j = np.concatenate([tr.axis_1, tr.axis_2]) + [0.1, -0.05, 0.02, 0.03, 0.0, -0.1]
    g1, g2 = tr.imu_1.gyr, tr.imu_2.gyr
    num = _fd(lambda v: hinge_residual(v[:3], v[3:], g1, g2), j)
    np.testing.assert_allclose(hinge_jacobian(j[:3], j[3:], g1, g2), num, atol=1e-6)
    s = np.array([0.4, 1.0, -0.3, 2.5])
    num = _fd(
        lambda v: hinge_residual(
            axis_from_spherical(v[0], v[1]), axis_from_spherical(v[2], v[3]), g1, g2
        ),
        s,
    )
    np.testing.assert_allclose(hinge_jacobian_spherical(s, g1, g2), num, atol=1e-6)


def test_spherical_coordinates():
    j = axis_from_spherical(np.array([0.0, np.pi / 2, 0.3]), np.array([0.0, 1.0, 2.0]))
    np.testing.assert_allclose(j[:2], [[1, 0, 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(np.linalg.norm(j, axis=1), 1.0)
    p, y = spherical_from_axis(j[2])
    assert (p, y) == pytest.approx((0.3, 2.0))


def test_angular_acceleration_filtered_beats_raw_differences():
    t = np.arange(1500) / 100.0
    w = np.stack([np.sin(2 * np.pi * 0.9 * t), np.cos(2 * np.pi * 1.3 * t), 0 * t], axis=1)
    dw = np.stack(
        [
            2 * np.pi * 0.9 * np.cos(2 * np.pi * 0.9 * t),
            -2 * np.pi * 1.3 * np.sin(2 * np.pi * 1.3 * t),
            0 * t,
        ],
        axis=1,
    )
    inner = slice(10, -10)
    assert np.max(np.abs(angular_acceleration(t, w) - dw)[inner]) < 0.01
    noisy = w + np.random.default_rng(0).normal(0, 0.01, w.shape)
    err_sg = np.std((angular_acceleration(t, noisy) - dw)[inner])
    raw = (-noisy[4:] + 8 * noisy[3:-1] - 8 * noisy[1:-3] + noisy[:-4]) / (12 * 0.01)
    err_raw = np.std(raw - dw[2:-2])
    assert err_sg < 0.3 * err_raw  # about 4x less noise
    with pytest.raises(InputError):
        angular_acceleration(t[::-1], w)


def test_eq16_projection_removes_the_shift_along_the_axis(clean_hinge):
    tr = clean_hinge
    p1, p2 = project_hinge_positions(tr.position_1, tr.position_2, tr.axis_1, tr.axis_2)
    assert tr.axis_1 @ p1 + tr.axis_2 @ p2 == pytest.approx(0.0, abs=1e-15)
    q1, q2 = project_hinge_positions(
        tr.position_1 + 0.03 * tr.axis_1, tr.position_2 + 0.03 * tr.axis_2, tr.axis_1, tr.axis_2
    )
    np.testing.assert_allclose([q1, q2], [p1, p2], atol=1e-15)
    d = _exact(tr)
    assert np.max(np.abs(spherical_residual(p1, p2, d))) < 1e-10  # still on the axis


def test_axis_signs_made_consistent():
    tr = hinge_trial("rich", duration=6.0)
    d = joint_data(tr.time, tr.imu_1.gyr, tr.imu_1.acc, tr.imu_2.gyr, tr.imu_2.acc)
    for kw in (
        {"quat_1": tr.imu_1.quat, "quat_2": tr.imu_2.quat},
        {"data": d, "o1": tr.position_1, "o2": tr.position_2},
    ):
        j1, j2 = consistent_axis_signs(tr.axis_1, -tr.axis_2, reference_1=tr.axis_1, **kw)
        np.testing.assert_allclose([j1, j2], [tr.axis_1, tr.axis_2])
        j1, j2 = consistent_axis_signs(-tr.axis_1, tr.axis_2, reference_1=tr.axis_1, **kw)
        np.testing.assert_allclose([j1, j2], [tr.axis_1, tr.axis_2])


def test_savgol_derivative_is_scipys_and_exact_on_cubics():
    """The hand-written Savitzky-Golay derivative (scipy.signal's import costs a command ~1 s)
    returns what scipy.signal.savgol_filter(..., deriv=1) does, edges included, and is exact on
    a cubic (a degree-3 fit reproduces it, so its derivative is exact at every sample)."""
    from scipy.signal import savgol_filter

    from pipeline.calibration.joint_constraints import savgol_derivative

    rng = np.random.default_rng(0)
    for n, window, order in ((200, 11, 3), (50, 7, 2), (11, 11, 3), (300, 21, 4)):
        y = rng.normal(size=(n, 3)).cumsum(axis=0)
        ours = savgol_derivative(y, window, order, 0.01)
        theirs = savgol_filter(y, window, order, deriv=1, delta=0.01, axis=0)
        np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12 * np.abs(theirs).max())
    t = np.arange(40) * 0.01
    cubic = np.stack([2 - t + 3 * t**2 - 5 * t**3, t**3], axis=1)
    slope = np.stack([-1 + 6 * t - 15 * t**2, 3 * t**2], axis=1)
    np.testing.assert_allclose(savgol_derivative(cubic, 9, 3, 0.01), slope, atol=1e-9)
    with pytest.raises(InputError, match="odd window"):
        savgol_derivative(cubic, 8, 3, 0.01)
    with pytest.raises(InputError, match="odd window"):
        savgol_derivative(cubic[:5], 9, 3, 0.01)
