"""Tests of pipeline.ik.batch: the strided solver (anchors in sequence, blocks between) against
the sequential one (``stride=1``)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from test_ik_solver import FRAMES, gait, leg_model

from pipeline.errors import InputError
from pipeline.ik.batch import block_setup
from pipeline.ik.problem import setup_ik
from pipeline.ik.solver import frame_rotations, solve_ik
from pipeline.rotations import exp3


def _noisy_targets(m, q, sd, seed, pelvis=False):
    rng = np.random.default_rng(seed)
    R = frame_rotations(m, q, FRAMES + ["right_femur_imu"] + (["pelvis"] if pelvis else []))
    return {f: v @ exp3(rng.normal(0, sd, (len(q), 3))) for f, v in R.items()}


@pytest.mark.parametrize(("knee", "root"), [("free", "fixed"), ("hinge", "fixed"),
                                            ("hinge", "spherical")])  # fmt: skip
def test_strided_reaches_the_sequential_optima(knee, root):
    m = leg_model(knee, root=root, knee_limits=[(0.0, 0.9)] if knee == "hinge" else None)
    q = gait(700, seed=2)  # knee flexion 0.05..1.15 rad: the 0.9 limit is active
    if knee == "hinge":
        q = np.c_[q[:, :3], q[:, 3], q[:, 6:]]
    if root == "spherical":
        ph = np.linspace(0, 6, 700)
        quat = np.c_[0.2 * np.sin(ph), np.zeros(700), 0.3 * np.cos(ph), np.ones(700)]
        quat /= np.linalg.norm(quat, axis=1, keepdims=True)
        q = np.c_[quat, q]
    targets = _noisy_targets(m, q, 0.03, seed=5, pelvis=root != "fixed")
    seq = solve_ik(m, targets, stride=1)
    for stride in (8, 64):
        res = solve_ik(m, targets, stride=stride)
        assert res.converged.all()
        # each is within tol (1e-4 rad) of the same optimum
        assert np.abs(res.q - seq.q).max() < 2e-4
        np.testing.assert_allclose(res.residual_rms, seq.residual_rms, atol=1e-6)
    if knee == "hinge":
        iq = m.joints[m.getJointId("right_knee_0")].idx_q
        assert res.q[:, iq].max() == 0.9 and seq.q[:, iq].max() == 0.9  # on the bound, exactly


def test_missing_targets_take_the_sequential_path_and_hold_unobserved_dofs():
    m = leg_model("free")
    q = gait(300)
    targets = _noisy_targets(m, q, 0.01, seed=1)
    targets["right_foot"][100:140] = np.nan  # the ankle is unobserved there
    for f in targets:
        targets[f][200:203] = np.nan  # no target at all
    seq = solve_ik(m, targets, stride=1)
    res = solve_ik(m, targets)
    assert np.isnan(res.q[200:203]).all() and (res.iterations[200:203] == 0).all()
    ok = np.isfinite(seq.q).all(axis=1)
    assert np.abs(res.q[ok] - seq.q[ok]).max() < 2e-4
    np.testing.assert_allclose(res.q[100:140, 6:], np.repeat(res.q[99:100, 6:], 40, 0), atol=0)


def test_models_the_block_cannot_vectorise_use_the_sequential_solver():
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelRUBX(), pin.SE3.Identity(), "unbounded")  # nq = 2
    m.addFrame(pin.Frame("link", j, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    a = np.linspace(0.0, 7.0, 50)
    R = np.array([pin.rpy.rpyToMatrix(x, 0.0, 0.0) for x in a])
    p = setup_ik(m, {"link": R})
    assert block_setup(p) is None
    res = solve_ik(m, {"link": R})
    np.testing.assert_allclose(res.q, solve_ik(m, {"link": R}, stride=1).q, atol=0)
    np.testing.assert_allclose(np.arctan2(res.q[:, 1], res.q[:, 0]),
                               np.arctan2(np.sin(a), np.cos(a)), atol=1e-6)  # fmt: skip


def test_stride_must_be_a_positive_integer():
    m = leg_model("free")
    R = frame_rotations(m, gait(5), FRAMES)
    for bad in (0, -3, 2.5):
        with pytest.raises(InputError, match="stride"):
            solve_ik(m, R, stride=bad)


def test_fast_turns_and_splices_get_closer_anchors_and_the_sequential_optima():
    """A pelvis turning 3 full turns in 2 s and a trial spliced end to end (a jump): anchors
    every 64 frames would interpolate across half turns; the motion-adaptive anchors do not."""
    from pipeline.ik.solver import ANCHOR_TURN_RAD, _anchors

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
    anchors = _anchors(p, 64)
    assert np.diff(anchors).max() <= 64 and 199 in anchors and 200 in anchors
    turn = [np.arccos(np.clip((np.trace(targets["pelvis"][a].T @ targets["pelvis"][b]) - 1) / 2,
                              -1, 1)) for a, b in zip(anchors[:-1], anchors[1:], strict=True)
            if b - a > 1]  # fmt: skip
    assert max(turn) <= ANCHOR_TURN_RAD + 0.2  # no frame is interpolated across a large turn
    seq, res = solve_ik(m, targets, stride=1), solve_ik(m, targets)
    assert res.converged.all() and np.abs(res.q - seq.q).max() < 2e-4


def test_anchors_follow_the_rotations_at_the_joints():
    """Each target's turn counts relative to the target on the joint above it (the pelvis: in
    the world), as the interpolated joint coordinates do: a hip and a knee flexing together by
    4 rad each (summed over the trial) turn the shank 8 rad in the world, but the anchors come
    every ~1 rad of either joint; a body turning round sets them by the pelvis. The anchors are
    solved loosely in sequence, then to tol with the other frames: the sequential optima."""
    from pipeline.ik.solver import ANCHOR_TURN_RAD, _anchors, _parent_tasks

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
    parents = _parent_tasks(p)
    assert [names[i] for i, j in enumerate(parents) if j < 0] == ["pelvis"], (names, parents)
    assert names[parents[names.index("right_tibia")]] == "right_femur"
    inner = len(_anchors(p, 1000)) - 2
    assert 4 / ANCHOR_TURN_RAD - 2 <= inner <= 4 / ANCHOR_TURN_RAD + 1  # not ~8: the shank's
    yaw = np.linspace(0.0, 4 * np.pi, n)  # the body turning twice, joints still
    turning = np.c_[np.zeros(n), np.sin(yaw / 2), np.zeros(n), np.cos(yaw / 2)]
    turned = _noisy_targets(m, np.c_[turning, np.tile(legs[:1], (n, 1))], 0.0, seed=1,
                            pelvis=True)  # fmt: skip
    assert abs(len(_anchors(setup_ik(m, turned), 1000)) - 4 * np.pi / ANCHOR_TURN_RAD) <= 3
    noisy = _noisy_targets(m, np.c_[still, legs], 0.02, seed=4, pelvis=True)
    seq, res = solve_ik(m, noisy, stride=1), solve_ik(m, noisy)
    assert res.converged.all() and np.abs(res.q - seq.q).max() < 2e-4
