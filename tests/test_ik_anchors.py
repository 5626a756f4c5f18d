"""Tests of pipeline.ik.anchors: where the strided IK solves frames in sequence (fast turns,
splices, joint rotations), checked against the sequential solver's optima."""

from __future__ import annotations

import numpy as np
from test_ik_block import _noisy_targets
from test_ik_solver import gait, leg_model

from pipeline.ik.anchors import ANCHOR_TURN_RAD, anchor_frames, interpolate, parent_tasks
from pipeline.ik.problem import setup_ik
from pipeline.ik.solver import solve_ik


def test_fast_turns_and_splices_get_closer_anchors_and_the_sequential_optima():
    """A pelvis turning 3 full turns in 2 s and a trial spliced end to end (a jump): anchors
    every 64 frames would interpolate across half turns; the motion-adaptive anchors do not."""

    m = leg_model("hinge", root="spherical", knee_limits=[(0.0, 0.9)])
    n = 400
    legs = gait(n, seed=3)
    legs = np.c_[legs[:, :3], legs[:, 3], legs[:, 6:]]
    yaw = np.linspace(0.0, 6 * np.pi, n)
    yaw[200:] -= 2.0  # the splice: a 2 rad jump of heading between two frames
    quat = np.c_[np.zeros(n), np.sin(yaw / 2), np.zeros(n), np.cos(yaw / 2)]
    q = np.c_[quat, legs]
    targets = _noisy_targets(m, q, 0.02, seed=8, pelvis=True)
    p = setup_ik(m, targets)
    anchors = anchor_frames(p, 64)
    assert np.diff(anchors).max() <= 64 and 199 in anchors and 200 in anchors
    turn = [np.arccos(np.clip((np.trace(targets["pelvis"][a].T @ targets["pelvis"][b]) - 1) / 2,
                              -1, 1)) for a, b in zip(anchors[:-1], anchors[1:], strict=True)
            if b - a > 1]
    assert max(turn) <= ANCHOR_TURN_RAD + 0.2  # no frame is interpolated across a large turn
    seq, res = solve_ik(m, targets, stride=1), solve_ik(m, targets)
    assert res.converged.all() and np.abs(res.q - seq.q).max() < 2e-4


def test_anchors_follow_the_rotations_at_the_joints():
    """Each target's turn counts relative to the target on the joint above it (the pelvis: in
    the world), as the interpolated joint coordinates do: a hip and a knee flexing together by
    4 rad each (summed over the trial) turn the shank 8 rad in the world, but the anchors come
    every ~1 rad of either joint; a body turning round sets them by the pelvis. The anchors are
    solved loosely in sequence, then to tol with the other frames: the sequential optima."""

    m = leg_model("free", root="spherical")
    n = 400
    t = np.linspace(0.0, 2.0, n)
    legs = np.zeros((n, m.nq - 4))
    legs[:, 0] = 0.5 * np.sin(2 * np.pi * t)  # hip: 4 rad of |change| over two cycles
    legs[:, 3] = 0.6 + 0.5 * np.sin(2 * np.pi * t)  # knee, in phase
    still = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    targets = _noisy_targets(m, np.c_[still, legs], 0.0, seed=1, pelvis=True)
    p = setup_ik(m, targets)
    names = [t.frame for t in p.tasks]
    parents = parent_tasks(p)
    assert [names[i] for i, j in enumerate(parents) if j < 0] == ["pelvis"], (names, parents)
    assert names[parents[names.index("right_tibia")]] == "right_femur"
    inner = len(anchor_frames(p, 1000)) - 2
    assert 4 / ANCHOR_TURN_RAD - 2 <= inner <= 4 / ANCHOR_TURN_RAD + 1  # not ~8: the shank's
    yaw = np.linspace(0.0, 4 * np.pi, n)  # the body turning twice, joints still
    turning = np.c_[np.zeros(n), np.sin(yaw / 2), np.zeros(n), np.cos(yaw / 2)]
    turned = _noisy_targets(m, np.c_[turning, np.tile(legs[:1], (n, 1))], 0.0, seed=1,
                            pelvis=True)
    assert abs(len(anchor_frames(setup_ik(m, turned), 1000)) - 4 * np.pi / ANCHOR_TURN_RAD) <= 3
    noisy = _noisy_targets(m, np.c_[still, legs], 0.02, seed=4, pelvis=True)
    seq, res = solve_ik(m, noisy, stride=1), solve_ik(m, noisy)
    assert res.converged.all() and np.abs(res.q - seq.q).max() < 2e-4


def test_interpolation_is_exact_for_cubic_motion_and_linear_at_jumps():
    """The starting points: the cubic through two solved frames on each side reproduces a cubic
    (checked by hand at frame 5 between nodes 0, 4, 8, 12), and a side with a jump (> 0.5 rad in
    a coordinate) falls back to the straight line between the nearest nodes."""
    ref = np.array([0, 4, 8, 12])
    f = lambda x: 0.001 * x**3 - 0.02 * x**2 + 0.1 * x + 1.0  # noqa: E731
    known = np.zeros((13, 1))
    known[ref, 0] = f(ref.astype(float))
    np.testing.assert_allclose(interpolate(ref, known, np.array([5, 6]))[:, 0],
                               f(np.array([5.0, 6.0])), rtol=1e-12)
    known[12, 0] += 2.0  # a jump after node 8
    start = interpolate(ref, known, np.array([6]))[0, 0]
    assert start == (known[4, 0] + known[8, 0]) / 2
