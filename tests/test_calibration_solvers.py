"""Hu 2021 eq 7-29 solvers (GN, DWPSO, GWO) and the CasADi/IPOPT formulation on simulated truth."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.calibrate import calibrate
from pipeline.calibration.ipopt import calibrate_ipopt
from pipeline.calibration.joint_constraints import joint_data, project_hinge_positions
from pipeline.calibration.solvers import dwpso, gauss_newton, gwo
from pipeline.errors import InputError
from pipeline.rotations import angle_between, exp3
from pipeline.simulate.joint_trials import hinge_trial, spherical_trial

SWARM = {"particles": 30, "wolves": 30, "iterations": 100}


def _data(tr):
    return joint_data(tr.time, tr.imu_1.gyr, tr.imu_1.acc, tr.imu_2.gyr, tr.imu_2.acc)


def _errors(tr, r):
    """(axis 1, axis 2) errors in degrees, signs included, and position errors in mm (eq 16)."""
    if tr.axis_1 is None:
        return (
            None,
            None,
            *(
                1000 * np.linalg.norm(r.position_1_m - tr.position_1),
                1000 * np.linalg.norm(r.position_2_m - tr.position_2),
            ),
        )
    p1, p2 = project_hinge_positions(tr.position_1, tr.position_2, tr.axis_1, tr.axis_2)
    return (
        np.degrees(angle_between(r.axis_1, tr.axis_1)),
        np.degrees(angle_between(r.axis_2, tr.axis_2)),
        1000 * np.linalg.norm(r.position_1_m - p1),
        1000 * np.linalg.norm(r.position_2_m - p2),
    )


@pytest.fixture(scope="module")
def hinge():
    tr = hinge_trial("rich", duration=8.0)
    return tr, _data(tr)


@pytest.fixture(scope="module")
def sphere():
    tr = spherical_trial("rich", duration=8.0)
    return tr, _data(tr)


def test_gauss_newton_solves_a_linear_problem_in_one_step():
    A = np.array([[1.0, 2.0], [0.0, 1.0], [3.0, -1.0]])
    b = np.array([1.0, 2.0, 0.5])
    x, cost, it = gauss_newton(lambda x: A @ x - b, lambda x: A, np.zeros(2))
    np.testing.assert_allclose(x, np.linalg.lstsq(A, b, rcond=None)[0], atol=1e-12)
    assert it <= 2


@pytest.mark.parametrize("opt", [dwpso, gwo])
def test_swarms_find_a_known_minimum(opt):
    target = np.array([0.1, -0.05, 0.15])
    lo, hi = np.full(3, -0.2), np.full(3, 0.2)
    x, c, _ = opt(lambda X: np.sum((X - target) ** 2, axis=1), lo, hi, seed=1)
    np.testing.assert_allclose(x, target, atol=1e-3)
    x2, _, _ = opt(lambda X: np.sum((X - target) ** 2, axis=1), lo, hi, seed=1)
    np.testing.assert_array_equal(x, x2)  # deterministic with a seed


@pytest.mark.parametrize(
    ("method", "axis_deg", "pos_mm"), [("gn", 0.2, 2.0), ("dwpso", 1.0, 5.0), ("gwo", 2.0, 15.0)]
)
def test_hinge_truth_recovered(hinge, method, axis_deg, pos_mm):
    tr, d = hinge
    r = calibrate(
        d,
        "hinge",
        method,
        seed=0,
        quat_1=tr.imu_1.quat,
        quat_2=tr.imu_2.quat,
        reference_1=tr.axis_1,
        **SWARM,
    )
    e1, e2, p1, p2 = _errors(tr, r)
    assert e1 < axis_deg and e2 < axis_deg  # signs consistent and right
    assert p1 < pos_mm and p2 < pos_mm
    assert r.method == method and r.seconds > 0 and r.iterations > 0
    assert r.observability.undetermined == ()


@pytest.mark.parametrize(("method", "pos_mm"), [("gn", 3.0), ("dwpso", 5.0), ("gwo", 15.0)])
def test_spherical_truth_recovered(sphere, method, pos_mm):
    tr, d = sphere
    r = calibrate(d, "spherical", method, seed=0, **SWARM)
    _, _, p1, p2 = _errors(tr, r)
    assert p1 < pos_mm and p2 < pos_mm
    assert r.axis_1 is None


def test_seeded_runs_are_identical(hinge):
    _, d = hinge
    a = calibrate(d, "hinge", "dwpso", seed=3, particles=10, iterations=20)
    b = calibrate(d, "hinge", "dwpso", seed=3, particles=10, iterations=20)
    np.testing.assert_array_equal(a.position_1_m, b.position_1_m)
    np.testing.assert_array_equal(a.axis_2, b.axis_2)
    with pytest.raises(InputError):
        calibrate(d, "hinge", "simplex")
    with pytest.raises(InputError):
        calibrate(d, "saddle")


def test_ipopt_rich_trial_meets_targets():
    tr = hinge_trial("rich", duration=15.0)
    r = calibrate_ipopt(
        _data(tr), "hinge", quat_1=tr.imu_1.quat, quat_2=tr.imu_2.quat, reference_1=tr.axis_1
    )
    e1, e2, p1, p2 = _errors(tr, r)
    assert max(e1, e2) < 0.1 and max(p1, p2) < 2.0
    assert r.axis_1 @ r.position_1_m + r.axis_2 @ r.position_2_m == pytest.approx(0, abs=1e-8)
    assert np.linalg.norm(r.axis_1) == pytest.approx(1.0)
    assert r.observability.solver_status == "Solve_Succeeded"


def test_ipopt_spherical_and_robust_loss_against_outliers(sphere, hinge):
    tr, d = sphere
    _, _, p1, p2 = _errors(tr, calibrate_ipopt(d, "spherical"))
    assert max(p1, p2) < 3.0
    tr, _ = hinge
    rng = np.random.default_rng(1)
    acc1, gyr2 = tr.imu_1.acc.copy(), tr.imu_2.gyr.copy()
    idx = rng.choice(acc1.shape[0], 40, replace=False)
    acc1[idx] += rng.normal(0, 15, (40, 3))
    gyr2[idx] += rng.normal(0, 2, (40, 3))
    d = joint_data(tr.time, tr.imu_1.gyr, acc1, gyr2, tr.imu_2.acc)
    errs = {}
    for loss in ("l2", "cauchy"):
        r = calibrate_ipopt(
            d, "hinge", loss=loss, quat_1=tr.imu_1.quat, quat_2=tr.imu_2.quat, reference_1=tr.axis_1
        )
        errs[loss] = _errors(tr, r)
    assert max(errs["cauchy"][:2]) < 0.3 < max(errs["l2"][:2])
    assert max(errs["cauchy"][2:]) < 0.5 * max(errs["l2"][2:])
    with pytest.raises(InputError):
        calibrate_ipopt(d, "hinge", loss="l1")


def test_still_thigh_flagged_and_prior_keeps_the_axis():
    tr = hinge_trial("still_thigh", duration=10.0, seed=1)
    d = _data(tr)
    r = calibrate(d, "hinge", "gn", quat_1=tr.imu_1.quat, quat_2=tr.imu_2.quat)
    assert "axis_1 (sensor 1)" in r.observability.undetermined
    prior = exp3(np.deg2rad([2.0, -1.5, 0.0])) @ tr.axis_1  # a population axis 2.5 deg off
    rp = calibrate_ipopt(d, "hinge", prior_axis_1=prior, prior_weight=1.0)
    e1, e2, _, _ = _errors(tr, rp)
    assert e1 < 3.0 and e2 < 0.5  # the prior also fixes the signs
    assert "prior" in rp.observability.message


def test_observability_is_typed_and_serialises_to_the_cli_layout(hinge):
    from pipeline.calibration.observability import Observability

    tr, d = hinge
    r = calibrate(d, "hinge", "gn", quat_1=tr.imu_1.quat, quat_2=tr.imu_2.quat)
    obs = r.observability
    assert isinstance(obs, Observability) and obs.determined
    assert obs.axes is not None and obs.axes.condition >= 1.0 and obs.axes.sd.shape == (4,)
    layout = obs.as_dict()
    assert list(layout) == ["undetermined", "expected", "axes", "positions", "message"]
    assert layout["expected"] == ["position along the hinge axis"]


def test_subproblem_is_typed(hinge):
    from pipeline.calibration.solvers import Subproblem, subproblem

    _, d = hinge
    axes, positions = subproblem(d, "axes"), subproblem(d, "positions")
    assert isinstance(axes, Subproblem) and axes.lo.shape == axes.hi.shape == (4,)
    assert list(axes.wrap) == [False, True, False, True] and not positions.wrap.any()
    x = 0.5 * (positions.lo + positions.hi)
    assert positions.population_cost(x[None]).shape == (1,)
    assert positions.jacobian(x).shape == (positions.residual(x).size, 6)


def test_ipopt_reuses_one_solver_per_shape_and_its_data_is_a_parameter():
    """The NLP is built once per (joint, samples, loss): a second trial of the same length
    solves in it with its own data (its own truth found), a prior switches on by its weight."""
    import pipeline.calibration.ipopt as ipopt

    ipopt._solver.cache_clear()
    a, b = hinge_trial("rich", duration=6.0, seed=1), hinge_trial("rich", duration=6.0, seed=2)
    ra, rb = (calibrate_ipopt(_data(t), "hinge", quat_1=t.imu_1.quat, quat_2=t.imu_2.quat,
                              reference_1=t.axis_1) for t in (a, b))
    info = ipopt._solver.cache_info()
    assert info.misses == 1 and info.hits == 1
    for tr, r in ((a, ra), (b, rb)):
        e1, e2, *_ = _errors(tr, r)
        assert max(e1, e2) < 0.5, (e1, e2)
    # a heavy prior on a wrong axis pulls the fit to it (the weight is live), a zero one does not
    wrong = exp3(np.array([0.4, 0.0, 0.0])) @ a.axis_1
    pulled = calibrate_ipopt(_data(a), "hinge", prior_axis_1=wrong, prior_weight=1e4)
    assert np.degrees(angle_between(pulled.axis_1, wrong)) < 2.0  # the prior is 23 deg off
    assert np.degrees(angle_between(pulled.axis_1, a.axis_1)) > 20.0
    assert ipopt._solver.cache_info().misses == 1


def test_ipopt_from_a_given_start_turns_with_the_sensor(hinge):
    """A start given in the sensors' frames (``start``) replaces the Gauss-Newton steps' random
    one (with no iteration the result is the start), and the same signals seen by a sensor
    mounted turned by ``Q`` end in the same centre turned by ``Q^T``."""
    tr, d = hinge
    Q = exp3(np.array([0.7, -1.9, 0.4]))
    turned = joint_data(tr.time, tr.imu_1.gyr @ Q, tr.imu_1.acc @ Q, tr.imu_2.gyr, tr.imu_2.acc)
    o1, o2 = np.array([0.05, -0.1, 0.02]), np.array([0.0, 0.12, -0.03])
    still = calibrate_ipopt(d, "spherical", start=(o1, o2), max_iter=0)
    assert np.allclose(still.position_1_m, o1) and np.allclose(still.position_2_m, o2)
    a = calibrate_ipopt(d, "spherical", start=(o1, o2))
    b = calibrate_ipopt(turned, "spherical", start=(Q.T @ o1, o2))
    assert np.linalg.norm(a.position_1_m - o1) > 0.01  # it moved from the start
    assert np.linalg.norm(Q.T @ a.position_1_m - b.position_1_m) < 1e-6
    assert np.linalg.norm(a.position_2_m - b.position_2_m) < 1e-6
