"""CasADi forward kinematics generated from a pin.Model == pinocchio.framesForwardKinematics."""

from __future__ import annotations

from dataclasses import replace

import casadi as ca
import numpy as np
import pinocchio as pin
import pytest

from pipeline.errors import InputError
from pipeline.model import Skeleton, SubjectGeometry
from pipeline.model.casadi_kinematics import (
    CasadiKinematics,
    axis_rotation_sym,
    exp3_sym,
    matrix_from_quat_xyzw_sym,
)
from pipeline.rotations import exp3, matrix_from_quat, normalize, rotation_aligning, skew

# A tilted AoR so that the hinge is a RevoluteUnaligned joint with a non-trivial placement.
AXIS_F = normalize(np.array([0.12, 0.06, 1.0]))
AXIS_T = normalize(np.array([-0.05, 0.09, 1.0]))
VARIANTS = [
    (knee, root, legs)
    for knee in ("hinge", "free")
    for root in ("fixed", "freeflyer", "spherical")
    for legs in (("right", "left"), ("right",), ("left",))
]


def _geometry() -> SubjectGeometry:
    g = SubjectGeometry.default(1.75, "m", "right")
    return replace(g, knee_axis_femur=AXIS_F, knee_axis_tibia=AXIS_T)


def _skeleton(knee: str, root: str, legs: tuple[str, ...]) -> Skeleton:
    return Skeleton.build(_geometry(), knee=knee, root=root, legs=legs)


def _random_q(model: pin.Model, rng: np.random.Generator, unit_quat: bool = True) -> np.ndarray:
    """Uniform within the joint limits; free-flyer translation ~ N(0, 1); random quaternion."""
    q = np.zeros(model.nq)
    for j in range(1, model.njoints):
        jm = model.joints[j]
        sl = slice(jm.idx_q, jm.idx_q + jm.nq)
        name = jm.shortname()
        if name in ("JointModelFreeFlyer", "JointModelSpherical"):
            quat = rng.normal(size=4)
            quat = quat / np.linalg.norm(quat) if unit_quat else quat
            q[sl] = np.concatenate([rng.normal(size=3), quat]) if jm.nq == 7 else quat
        else:
            q[sl] = rng.uniform(model.lowerPositionLimit[sl], model.upperPositionLimit[sl])
    return q


def _all_frames_error(model: pin.Model, f: ca.Function, q: np.ndarray) -> float:
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    out = f(q)
    err = 0.0
    for i in range(len(model.frames)):
        R, p = np.array(out[2 * i]), np.array(out[2 * i + 1]).ravel()
        err = max(err, np.abs(R - data.oMf[i].rotation).max())
        err = max(err, np.abs(p - data.oMf[i].translation).max())
    return err


@pytest.mark.parametrize(("knee", "root", "legs"), VARIANTS)
def test_equals_pinocchio_on_every_frame(knee, root, legs):
    sk = _skeleton(knee, root, legs)
    kin = CasadiKinematics(sk.model)
    assert kin.nq == sk.model.nq
    f = kin.function(range(len(sk.model.frames)))
    rng = np.random.default_rng(VARIANTS.index((knee, root, legs)))
    for _ in range(5):
        assert _all_frames_error(sk.model, f, _random_q(sk.model, rng)) < 1e-9
    if root != "fixed":  # same convention as Pinocchio for a non-unit quaternion too
        assert _all_frames_error(sk.model, f, _random_q(sk.model, rng, unit_quat=False)) < 1e-9


def test_named_frame_api_matches_skeleton():
    sk = _skeleton("hinge", "freeflyer", ("right", "left"))
    kin = CasadiKinematics(sk.model)
    q = _random_q(sk.model, np.random.default_rng(3))
    sk.forward(q)
    for name in ("right_tibia", "left_femur", "right_MM", "pelvis_imu", "left_tibia_imu"):
        R, p = kin.frame_placement(name, q)
        assert np.allclose(np.array(R), sk.frame_rotation(name), atol=1e-12)
        assert np.allclose(np.array(p).ravel(), sk.frame_position(name), atol=1e-12)
        assert kin.frame_id(name) == sk.frame_id(name)
    R, p = kin.joint_placement("right_knee", q)
    data = sk.model.createData()
    pin.forwardKinematics(sk.model, data, q)
    oMi = data.oMi[sk.model.getJointId("right_knee")]
    assert np.allclose(np.array(R), oMi.rotation)
    assert np.allclose(np.array(p).ravel(), oMi.translation)
    # the package's contract for bad names is InputError (it was KeyError)
    with pytest.raises(InputError, match="no_such_frame"):
        kin.frame_id("no_such_frame")
    with pytest.raises(InputError, match="frame index"):
        kin.frame_id(10_000)
    with pytest.raises(InputError, match="no_such_joint"):
        kin.joint_placement("no_such_joint", q)
    # symbolic in, symbolic out (SX and MX)
    for sym in (ca.SX.sym("x", kin.nq), ca.MX.sym("x", kin.nq)):
        assert isinstance(kin.frame_position("right_LM", sym), type(sym))


@pytest.mark.parametrize("knee", ["hinge", "free"])
def test_jacobians_equal_pinocchio_frame_jacobians(knee):
    """d p_f / d q == LOCAL_WORLD_ALIGNED linear Jacobian; (dR/dq_i) R^T == [angular_i]x."""
    sk = _skeleton(knee, "fixed", ("right", "left"))
    model, data = sk.model, sk.model.createData()
    kin = CasadiKinematics(model)
    q_sym = ca.SX.sym("q", kin.nq)
    rng = np.random.default_rng(7)
    names = ["right_tibia", "right_MM", "right_foot_imu", "left_LM", "left_femur_imu"]
    funs = {}
    for n in names:
        R, p = kin.frame_placement(n, q_sym)
        dR = [ca.jacobian(ca.vec(R), q_sym[i]) for i in range(kin.nq)]
        funs[n] = ca.Function("j", [q_sym], [ca.jacobian(p, q_sym), R, *dR])
    for _ in range(3):
        q = _random_q(model, rng)
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        for n in names:
            J = pin.getFrameJacobian(model, data, sk.frame_id(n), pin.LOCAL_WORLD_ALIGNED)
            out = funs[n](q)
            assert np.allclose(np.array(out[0]), J[:3], atol=1e-9)
            R = np.array(out[1])
            for i in range(kin.nq):
                dR = np.array(out[2 + i]).reshape(3, 3, order="F")
                assert np.allclose(dR @ R.T, skew(J[3:, i]), atol=1e-9)


@pytest.mark.parametrize("root", ["freeflyer", "spherical"])
def test_jacobian_matches_finite_differences_with_quaternion_root(root):
    sk = _skeleton("hinge", root, ("right", "left"))
    model, data = sk.model, sk.model.createData()
    kin = CasadiKinematics(model)
    q_sym = ca.SX.sym("q", kin.nq)
    fid = sk.frame_id("right_LM")
    J_fun = ca.Function("J", [q_sym], [ca.jacobian(kin.frame_position(fid, q_sym), q_sym)])
    q = _random_q(model, np.random.default_rng(11))
    J_fd, h = np.zeros((3, kin.nq)), 1e-6
    for i in range(kin.nq):
        dq = np.zeros(kin.nq)
        dq[i] = h
        pin.framesForwardKinematics(model, data, q + dq)
        p_plus = data.oMf[fid].translation.copy()
        pin.framesForwardKinematics(model, data, q - dq)
        J_fd[:, i] = (p_plus - data.oMf[fid].translation) / (2 * h)
    assert np.allclose(np.array(J_fun(q)), J_fd, atol=1e-7)


def test_other_joint_types_against_pinocchio():
    """Hand-built model: RevoluteUnaligned, RUBZ (cos, sin), PX and PrismaticUnaligned."""
    model = pin.Model()
    M = pin.SE3(exp3(np.array([0.2, -0.1, 0.3])), np.array([0.1, 0.2, -0.3]))
    a = normalize(np.array([1.0, 2.0, -0.5]))
    j1 = model.addJoint(0, pin.JointModelRevoluteUnaligned(*a), M, "rev")
    j2 = model.addJoint(j1, pin.JointModelRUBZ(), M, "rub")
    j3 = model.addJoint(j2, pin.JointModelPX(), M, "px")
    j4 = model.addJoint(j3, pin.JointModelPrismaticUnaligned(*a), M, "pu")
    model.addFrame(pin.Frame("tip", j4, M, pin.FrameType.OP_FRAME))
    kin = CasadiKinematics(model)
    f = kin.function(range(len(model.frames)))
    rng = np.random.default_rng(5)
    for _ in range(3):
        th = rng.uniform(-3, 3)
        q = np.array([rng.uniform(-3, 3), np.cos(th), np.sin(th), rng.normal(), rng.normal()])
        assert _all_frames_error(model, f, q) < 1e-12
    # hand check of the first joint: R = M.R exp(q a), p = M.p
    q = np.array([0.7, 1.0, 0.0, 0.0, 0.0])
    R, p = kin.joint_placement("rev", q)
    assert np.allclose(np.array(R), M.rotation @ exp3(0.7 * a), atol=1e-14)
    assert np.allclose(np.array(p).ravel(), M.translation, atol=1e-14)


def test_unsupported_joint_raises():
    model = pin.Model()
    model.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "planar")
    with pytest.raises(NotImplementedError, match="JointModelPlanar"):
        CasadiKinematics(model)


def test_symbolic_rotation_helpers():
    rng = np.random.default_rng(2)
    w = ca.SX.sym("w", 3)
    exp_f = ca.Function("e", [w], [exp3_sym(w)])
    jac_f = ca.Function("j", [w], [ca.jacobian(ca.vec(exp3_sym(w)), w)])
    for v in [*rng.normal(size=(3, 3)), np.array([1e-6, -2e-6, 3e-7]), np.zeros(3)]:
        assert np.allclose(np.array(exp_f(v)), exp3(v), atol=1e-14)
        assert np.all(np.isfinite(np.array(jac_f(v))))
    # d exp(w) / dw at 0 is the generator basis: d/dw_i = [e_i]x
    J0 = np.array(jac_f(np.zeros(3)))
    for i in range(3):
        assert np.allclose(J0[:, i].reshape(3, 3, order="F"), skew(np.eye(3)[i]))
    a = normalize(np.array([0.3, -1.0, 0.4]))
    assert np.allclose(np.array(axis_rotation_sym(a, np.cos(0.9), np.sin(0.9))), exp3(0.9 * a))
    quat = normalize(rng.normal(size=4))  # x, y, z, w
    R = np.array(matrix_from_quat_xyzw_sym(ca.DM(quat)))
    assert np.allclose(R, matrix_from_quat(quat[[3, 0, 1, 2]]), atol=1e-14)


def test_hinge_keeps_the_aor_fixed_in_both_segments():
    """On the hinge model, R_F^T R_T a_T = a_F for every q (the model's hinge structure)."""
    sk = _skeleton("hinge", "fixed", ("right",))
    kin = CasadiKinematics(sk.model)
    q = ca.SX.sym("q", kin.nq)
    rel = ca.mtimes(kin.frame_rotation("right_femur", q).T, kin.frame_rotation("right_tibia", q))
    f = ca.Function("rel", [q], [rel])
    rng = np.random.default_rng(1)
    for _ in range(5):
        M = np.array(f(_random_q(sk.model, rng)))
        assert np.allclose(M @ AXIS_T, AXIS_F, atol=1e-12)
    M0 = np.array(f(np.zeros(kin.nq)))
    assert np.allclose(M0, rotation_aligning(AXIS_T, AXIS_F), atol=1e-12)
