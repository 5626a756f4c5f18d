"""Tests of pipeline.model.batch_kinematics against Pinocchio's forward kinematics."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from test_ik_solver import leg_model

from pipeline.model.batch_kinematics import JointRotations
from pipeline.model.geometry import SubjectGeometry
from pipeline.model.skeleton import Skeleton


def _random_q(model, n, rng):
    return np.array([pin.integrate(model, pin.neutral(model), rng.uniform(-2, 2, model.nv))
                     for _ in range(n)])


@pytest.mark.parametrize(("knee", "root"), [("free", "fixed"), ("hinge", "spherical"),
                                            ("hinge", "freeflyer")])
def test_joint_rotations_and_integrate_match_pinocchio(knee, root):
    m = leg_model(knee, root=root)
    rng = np.random.default_rng(0)
    Q = _random_q(m, 20, rng)
    kin = JointRotations(m, set(range(1, m.njoints)))
    Rw = kin.world(Q)
    d = m.createData()
    for n in range(len(Q)):
        pin.forwardKinematics(m, d, Q[n])
        for j in range(1, m.njoints):
            np.testing.assert_allclose(Rw[j][n], d.oMi[j].rotation, atol=1e-13)
    cols = np.arange(m.nv) if root != "freeflyer" else np.arange(3, m.nv)  # no translations
    _, _, plan = kin.tangent_plan(m, cols)
    dv = rng.normal(size=(len(Q), cols.size))
    ours = kin.integrate(Q, dv, plan)
    for n in range(len(Q)):
        v = np.zeros(m.nv)
        v[cols] = dv[n]
        np.testing.assert_allclose(ours[n], pin.integrate(m, Q[n], v), atol=1e-12)




@pytest.mark.parametrize("root", ["fixed", "spherical", "freeflyer"])
def test_poses_and_frame_poses_match_pinocchio(root):
    sk = Skeleton.build(SubjectGeometry.default(), knee="hinge", root=root)
    m = sk.model
    rng = np.random.default_rng(1)
    Q = _random_q(m, 15, rng)
    kin = JointRotations(m, set(range(1, m.njoints)))
    poses = kin.poses(Q)
    fids = [m.getFrameId(n) for n in ("right_LM", "left_MM", "pelvis_imu", "right_foot_imu")]
    R, p = kin.frame_poses(m, Q, fids)
    d = m.createData()
    for n in range(len(Q)):
        pin.forwardKinematics(m, d, Q[n])
        pin.updateFramePlacements(m, d)
        for j in range(1, m.njoints):
            np.testing.assert_allclose(poses[j][0][n], d.oMi[j].rotation, atol=1e-13)
            np.testing.assert_allclose(poses[j][1][n], d.oMi[j].translation, atol=1e-13)
        for i, f in enumerate(fids):
            np.testing.assert_allclose(R[i, n], d.oMf[f].rotation, atol=1e-13)
            np.testing.assert_allclose(p[i, n], d.oMf[f].translation, atol=1e-13)


def test_other_joint_types_are_refused():
    m = pin.Model()
    m.addJoint(0, pin.JointModelPX(), pin.SE3.Identity(), "slider")
    with pytest.raises(ValueError, match="not vectorised"):
        JointRotations(m, {1})
