"""Box-constrained Gauss-Newton step for joint limits (pipeline.ik.bounds).

The box QP ``argmin 1/2 d^T H d + g^T d, lo <= d <= hi`` is checked on 2-D cases solved by hand
(interior optimum, one face, a corner, a bound the unconstrained step violates but the optimum does
not touch) and on random problems against ``scipy.optimize.lsq_linear`` (with ``H = L L^T`` the
objective is ``1/2 |L^T d + L^-1 g|^2 + const``).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import lsq_linear

from pipeline.ik.bounds import box_margin, box_step, joint_box

H2 = np.array([[2.0, 0.5], [0.5, 1.0]])  # det 1.75, H^-1 = [[1, -0.5], [-0.5, 2]] / 1.75


def _step(H, g, lo, hi):
    d0 = -np.linalg.solve(H, g)
    return box_step(H, g, np.asarray(lo, float), np.asarray(hi, float), d0)


def _kkt_ok(H, g, lo, hi, d, tol=1e-10):
    """Projected gradient vanishes: grad = 0 when free, >= 0 at lo, <= 0 at hi."""
    grad = H @ d + g
    at_lo, at_hi = np.isclose(d, lo), np.isclose(d, hi)
    free = ~(at_lo | at_hi)
    return (
        np.all(np.abs(grad[free]) < tol)
        and np.all(grad[at_lo & ~at_hi] > -tol)
        and np.all(grad[at_hi & ~at_lo] < tol)
    )


def test_unconstrained_optimum_inside_box_returned():
    g = np.array([-1.0, -1.0])  # d0 = H^-1 (1, 1) = (0.5, 1.5) / 1.75 = (2/7, 6/7)
    d = _step(H2, g, [-1, -1], [1, 1])
    np.testing.assert_allclose(d, [2 / 7, 6 / 7], atol=1e-14)


def test_optimum_clamped_to_a_face():
    # d0 = (2/7, 6/7) violates y <= 0.5; with y = 0.5: 2x + 0.25 - 1 = 0 -> x = 0.375, and
    # dE/dy = 0.5 * 0.375 + 0.5 - 1 = -0.3125 <= 0 at the upper bound (KKT holds)
    g = np.array([-1.0, -1.0])
    d = _step(H2, g, [-1, -1], [1, 0.5])
    np.testing.assert_allclose(d, [0.375, 0.5], atol=1e-14)
    assert _kkt_ok(H2, g, np.array([-1, -1.0]), np.array([1, 0.5]), d)


def test_optimum_clamped_to_a_corner():
    # d0 = H^-1 (10, 10) = (5, 15) / 1.75 outside [-1, 1]^2; at (1, 1) the gradient
    # H (1, 1) + g = (2.5 - 10, 1.5 - 10) is negative in both: both upper bounds are active
    g = np.array([-10.0, -10.0])
    d = _step(H2, g, [-1, -1], [1, 1])
    np.testing.assert_array_equal(d, [1.0, 1.0])


def test_bound_violated_by_unconstrained_step_released():
    # H = [[1, .9], [.9, 1]], g = (-1, 1): d0 = (10, -10) violates x <= 5 and y >= -1. With both
    # fixed, dE/dx = 5 - 0.9 - 1 = 3.1 > 0 at the upper bound: x must be freed. Then
    # x = -(g_x + 0.9 y) = 1.9 inside the box, dE/dy = 0.9 * 1.9 - 1 + 1 = 1.71 >= 0 at y = -1.
    H = np.array([[1.0, 0.9], [0.9, 1.0]])
    g = np.array([-1.0, 1.0])
    d0 = -np.linalg.solve(H, g)
    np.testing.assert_allclose(d0, [10.0, -10.0], atol=1e-12)
    d = _step(H, g, [-np.inf, -1.0], [5.0, np.inf])
    np.testing.assert_allclose(d, [1.9, -1.0], atol=1e-14)


def test_input_not_modified_and_result_in_box():
    g = np.array([-10.0, -10.0])
    d0 = -np.linalg.solve(H2, g)
    keep = d0.copy()
    lo, hi = np.array([-1.0, -1.0]), np.array([1.0, 1.0])
    d = box_step(H2, g, lo, hi, d0)
    np.testing.assert_array_equal(d0, keep)
    assert np.all(d >= lo) and np.all(d <= hi)


@pytest.mark.parametrize("seed", range(5))
def test_random_box_qp_matches_lsq_linear(seed):
    rng = np.random.default_rng(seed)
    n = 6
    A = rng.normal(size=(n + 2, n))
    H = A.T @ A + 0.1 * np.eye(n)
    g = rng.normal(size=n) * 3.0
    lo = -rng.uniform(0.05, 1.0, n)
    hi = rng.uniform(0.05, 1.0, n)
    lo[0], hi[1] = -np.inf, np.inf  # unbounded sides, as for DoFs without limits
    d = _step(H, g, lo, hi)
    L = np.linalg.cholesky(H)
    ref = lsq_linear(L.T, -np.linalg.solve(L, g), bounds=(lo, hi), method="bvls", tol=1e-14)
    np.testing.assert_allclose(d, ref.x, atol=1e-9)
    assert _kkt_ok(H, g, lo, hi, d, tol=1e-9)
    assert np.any(np.isclose(d, lo) | np.isclose(d, hi))  # the box does bind


def test_box_margin_hand_values():
    lo, hi = np.array([0.0, -1.0]), np.array([0.9, 1.0])
    assert box_margin(np.array([0.8, 0.5]), lo, hi) == pytest.approx(0.1)
    assert box_margin(np.array([0.3, -0.8]), lo, hi) == pytest.approx(0.2)
    assert box_margin(np.empty(0), np.empty(0), np.empty(0)) == np.inf


def test_joint_box_reads_one_dof_limits_only():
    m = pin.Model()
    j1 = m.addJoint(
        0,
        pin.JointModelRZ(),
        pin.SE3.Identity(),
        "knee",
        np.array([1.0]),
        np.array([1.0]),
        np.array([-0.2]),
        np.array([2.1]),
    )
    j2 = m.addJoint(j1, pin.JointModelSpherical(), pin.SE3.Identity(), "ankle")
    big = np.finfo(float).max
    m.addJoint(
        j2,
        pin.JointModelRX(),
        pin.SE3.Identity(),
        "toe",
        np.array([1.0]),
        np.array([1.0]),
        np.array([-big]),
        np.array([big]),
    )
    cols = np.arange(m.nv)  # knee (v 0), ankle (v 1-3), toe (v 4)
    lo, hi, qidx = joint_box(m, cols)
    np.testing.assert_array_equal(lo, [-0.2, -np.inf, -np.inf, -np.inf, -np.inf])
    np.testing.assert_array_equal(hi, [2.1, np.inf, np.inf, np.inf, np.inf])
    # the toe is a 1-DoF joint (bounded coordinate, q index 5 after the ankle's 4 quaternion
    # entries) with no finite limit; the spherical ankle is not bounded
    np.testing.assert_array_equal(qidx, [0, -1, -1, -1, 5])
    lo, hi, qidx = joint_box(m, cols[[4, 0]])
    np.testing.assert_array_equal(qidx, [5, 0])
    np.testing.assert_array_equal(hi, [np.inf, 2.1])
    lo, hi, qidx = joint_box(m, cols, limits=False)
    assert np.all(lo == -np.inf) and np.all(hi == np.inf) and np.all(qidx == -1)
