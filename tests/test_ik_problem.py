"""pipeline.ik.problem: the per-trial setup of orientation IK, checked on a one-leg model."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.ik.problem import setup_ik
from pipeline.ik.solver import frame_rotations, solve_frame
from pipeline.model import Skeleton, SubjectGeometry


@pytest.fixture(scope="module")
def leg():
    return Skeleton.build(SubjectGeometry.default(1.75, "m", "right"), knee="free", legs=("right",))


def test_observed_dofs_and_support_masks(leg):
    q = leg.neutral()
    femur = frame_rotations(leg.model, q[None], ["right_femur"])
    p = setup_ik(leg.model, femur)
    # a femur target observes the three hip rotations only, each of which moves the femur
    assert p.cols.size == 3 and p.masks.shape == (1, 3) and p.masks.all()
    both = frame_rotations(leg.model, q[None], ["right_femur", "right_tibia"])
    p2 = setup_ik(leg.model, both)
    # hip (3) + free knee (3); the femur task is not moved by the knee DoFs
    assert p2.cols.size == 6
    np.testing.assert_array_equal(p2.masks, [[1, 1, 1, 0, 0, 0], [1, 1, 1, 1, 1, 1]])
    assert p2.euclid and p2.has_limits and p2.n_frames == 1


def test_one_frame_step_reaches_an_exact_target(leg):
    rng = np.random.default_rng(0)
    lo, hi = leg.lower_limits, leg.upper_limits
    q_true = lo + (hi - lo) * rng.uniform(0.4, 0.6, leg.nq)
    targets = frame_rotations(leg.model, q_true[None], ["right_femur", "right_tibia", "right_foot"])
    p = setup_ik(leg.model, targets)
    q, iterations, converged = solve_frame(p, 0, p.q_ref.copy())
    assert converged and 1 <= iterations <= p.max_iters
    np.testing.assert_allclose(q, q_true, atol=1e-5)


def test_setup_refuses_bad_inputs(leg):
    with pytest.raises(InputError, match="no frame named"):
        setup_ik(leg.model, {"nose": np.eye(3)})
    with pytest.raises(InputError, match="q0"):
        setup_ik(leg.model, {"right_femur": np.eye(3)}, q0=np.zeros(2))
