"""Tests of pipeline.ik.block: the strided solver (anchors in sequence, blocks between) against
the sequential one (``stride=1``)."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from test_ik_solver import FRAMES, gait, leg_model

from pipeline.errors import InputError
from pipeline.ik.block import block_setup
from pipeline.ik.problem import setup_ik
from pipeline.ik.solver import frame_rotations, solve_ik
from pipeline.rotations import exp3


def _noisy_targets(m, q, sd, seed, pelvis=False):
    rng = np.random.default_rng(seed)
    R = frame_rotations(m, q, FRAMES + ["right_femur_imu"] + (["pelvis"] if pelvis else []))
    return {f: v @ exp3(rng.normal(0, sd, (len(q), 3))) for f, v in R.items()}


@pytest.mark.parametrize(("knee", "root"), [("free", "fixed"), ("hinge", "fixed"),
                                            ("hinge", "spherical")])
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
                               np.arctan2(np.sin(a), np.cos(a)), atol=1e-6)


def test_stride_must_be_a_positive_integer():
    m = leg_model("free")
    R = frame_rotations(m, gait(5), FRAMES)
    for bad in (0, -3, 2.5):
        with pytest.raises(InputError, match="stride"):
            solve_ik(m, R, stride=bad)
