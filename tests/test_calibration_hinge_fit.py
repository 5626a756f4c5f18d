"""Whole-trial closed-form hinge axes (SVD of the mean relative rotation) and motion weights."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.hinge_fit import hinge_fit, motion_weights
from pipeline.errors import InputError
from pipeline.rotations import angle_between, exp3, normalize, rot_z

DEG = np.pi / 180


def test_l2_identity_and_excitation_by_hand():
    """|M u - v|² = 2 - 2 vᵀ M u; pure hinge: axes exact, excitation = 1 - |mean e^{iθ}|."""
    rng = np.random.default_rng(0)
    theta = np.linspace(0, 1.5, 400)
    M0 = exp3(np.array([0.1, -0.2, 0.05]))
    a = normalize(np.array([0.1, 0.05, 1.0]))
    M = M0 @ exp3(theta[:, None] * a)
    u, v = normalize(rng.normal(size=3)), normalize(rng.normal(size=3))
    assert np.allclose(np.sum((M @ u - v) ** 2, axis=1), 2 - 2 * (M @ u) @ v)
    fit = hinge_fit(np.repeat(np.eye(3)[None], len(M), axis=0), M, weights="uniform")
    assert angle_between(fit.tibia_axis, a) < 1e-12
    assert angle_between(fit.femur_axis, M0 @ a) < 1e-12
    assert fit.excitation == pytest.approx(1 - np.abs(np.mean(np.exp(1j * theta))), abs=1e-12)


def test_motion_weights_at_constant_speed_and_rest():
    n, rate, speed = 400, 100.0, 30 * DEG  # knee turns at 30 deg/s for 2 s, then rests
    ang = np.minimum(np.arange(n), 200) / rate * speed
    F = np.repeat(np.eye(3)[None], n, axis=0)
    w = motion_weights(F, rot_z(-ang), rate, motion_window=0.5, static_speed=10 * DEG)
    assert w[100] == pytest.approx(30 / (30 + 10), abs=1e-9)  # φ/(φ + φ0), φ = ω · window
    assert np.all(w[226:] < 1e-9) and np.all(w[30:170] > 0.7)
    T = rot_z(-ang)
    T[50] = np.nan
    assert motion_weights(F, T)[50] == 0


def test_weights_given_as_array_and_missing_samples():
    """Zero weight (or a NaN sample) removes a sample: the fit equals the one without it."""
    rng = np.random.default_rng(2)
    n = 200
    a = normalize(np.array([0.2, -0.1, 1.0]))
    M0 = exp3(np.array([0.05, 0.1, -0.2]))
    theta = np.linspace(0.0, 1.2, n)
    F = exp3(rng.normal(scale=0.3, size=(n, 3)))  # arbitrary femur orientations
    T = F @ M0 @ exp3(theta[:, None] * a)
    T_bad = T.copy()
    T_bad[50:60] = T[50:60] @ exp3(np.array([0.5, 0.0, 0.0]))  # off-hinge samples
    w = np.ones(n)
    w[50:60] = 0.0
    fit = hinge_fit(F, T_bad, weights=w)
    assert angle_between(fit.tibia_axis, a) < 1e-9
    assert angle_between(fit.femur_axis, M0 @ a) < 1e-9
    assert fit.tibia_axis[2] > 0  # signed to point right
    T_nan = T_bad.copy()
    T_nan[50:60] = np.nan
    fit_nan = hinge_fit(F, T_nan, weights="uniform")
    np.testing.assert_allclose(fit_nan.mean_relative_rotation, fit.mean_relative_rotation)


def test_bad_inputs_raise():
    R = np.repeat(np.eye(3)[None], 10, axis=0)
    with pytest.raises(InputError, match="shape"):
        hinge_fit(R, R[:5])
    with pytest.raises(InputError, match="weights"):
        hinge_fit(R, R, weights="equal")
    with pytest.raises(InputError, match="weights"):
        hinge_fit(R, R, weights=np.ones(3))
    with pytest.raises(InputError, match="weights"):
        hinge_fit(R, R, weights=-np.ones(10))
    with pytest.raises(InputError, match="positive weight"):
        hinge_fit(R, R)  # knee never moves: all motion weights zero
