"""Tests of pipeline.ik.solver on leg models built here with the Pinocchio API and on human.urdf."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import minimize

from pipeline.errors import InputError
from pipeline.ik.problem import OrientationTask
from pipeline.ik.solver import frame_rotations, orientation_residuals, solve_ik
from pipeline.rotations import exp3, log3, normalize, rot_x, rot_y, rot_z

HIP = np.array([0.0, -0.08, 0.08])  # right hip centre in the pelvis frame (ISB: y up, z right)
THIGH, SHANK = 0.42, 0.40
P_EFL, P_EFM = np.array([0.0, -THIGH, 0.045]), np.array([0.0, -THIGH, -0.045])  # femoral frame
P_LM, P_MM = np.array([-0.01, -SHANK, 0.035]), np.array([0.005, -0.39, -0.035])  # tibial frame
HINGE_AXIS = normalize(np.array([0.06, 0.12, 1.0]))
IMU_PLACEMENT = pin.SE3(exp3(np.array([0.3, -1.2, 0.5])), np.array([0.05, -0.2, 0.04]))


def _chain(model, parent, axes, placement, prefix, lims=None):
    joints = {"x": pin.JointModelRX, "y": pin.JointModelRY, "z": pin.JointModelRZ}
    for i, a in enumerate(axes):
        jm = joints[a]() if isinstance(a, str) else pin.JointModelRevoluteUnaligned(a)
        lo, hi = (-1e3, 1e3) if lims is None else lims[i]
        parent = model.addJoint(
            parent,
            jm,
            placement if i == 0 else pin.SE3.Identity(),
            f"{prefix}_{i}",
            np.array([100.0]),
            np.array([100.0]),
            np.array([lo]),
            np.array([hi]),
        )
    return parent


def leg_model(knee="free", root="fixed", knee_limits=None):
    """Pelvis root + right hip ZXY + knee (ZXY 'free' or tilted-axis 'hinge') + ankle ZX."""
    m = pin.Model()
    top = 0
    if root == "freeflyer":
        top = m.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    elif root == "spherical":
        top = m.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "root")
    m.addFrame(pin.Frame("pelvis", top, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    hip = _chain(m, top, "zxy", pin.SE3(np.eye(3), HIP), "right_hip")
    kp = pin.SE3(np.eye(3), np.array([0.0, -THIGH, 0.0]))
    if knee == "free":
        kn = _chain(m, hip, "zxy", kp, "right_knee")
    else:
        kn = _chain(m, hip, [HINGE_AXIS], kp, "right_knee", knee_limits)
    ank = _chain(m, kn, "zx", pin.SE3(np.eye(3), np.array([0.0, -SHANK, 0.0])), "right_ankle")
    for name, j, plc in [
        ("right_femur", hip, pin.SE3.Identity()),
        ("right_femur_imu", hip, IMU_PLACEMENT),
        ("right_tibia", kn, pin.SE3.Identity()),
        ("right_foot", ank, pin.SE3.Identity()),
        ("EFL", hip, pin.SE3(np.eye(3), P_EFL)),
        ("EFM", hip, pin.SE3(np.eye(3), P_EFM)),
        ("LM", kn, pin.SE3(np.eye(3), P_LM)),
        ("MM", kn, pin.SE3(np.eye(3), P_MM)),
    ]:
        m.addFrame(pin.Frame(name, j, 0, plc, pin.FrameType.OP_FRAME))
    return m


def gait(n=200, seed=0):
    """Smooth hip ZXY, knee ZXY (flexion + off-axis) and ankle ZX angles, (n, 8)."""
    t = np.linspace(0.0, 2.0, n)
    ph = 2 * np.pi * t
    rng = np.random.default_rng(seed)
    off = rng.uniform(0, 2 * np.pi, 8)
    hip = np.c_[0.5 * np.sin(ph + off[0]), 0.15 * np.sin(ph + off[1]), 0.2 * np.sin(ph + off[2])]
    knee = np.c_[0.6 - 0.55 * np.cos(ph), 0.08 * np.sin(ph + off[3]), 0.12 * np.sin(ph + off[4])]
    ankle = np.c_[0.3 * np.sin(ph + off[5]), 0.1 * np.sin(ph + off[6])]
    return np.c_[hip, knee, ankle]


FRAMES = ["right_femur", "right_tibia", "right_foot"]
TIGHT = 1e-10  # tol of the exactness checks (the default 1e-4 rad is ample for IMU data)


def cost(model, q, targets, weights):
    return sum(
        w * np.sum(log3(targets[f].T @ frame_rotations(model, q, [f])[f][0]) ** 2)
        for f, w in weights.items()
    )


def test_jacobian_matches_finite_differences():
    m = leg_model("hinge", root="freeflyer")
    rng = np.random.default_rng(1)
    q = pin.integrate(m, pin.neutral(m), rng.uniform(-1, 1, m.nv))
    targets = {f: exp3(rng.normal(size=3)) for f in ["pelvis", *FRAMES, "right_femur_imu"]}
    r, J = orientation_residuals(m, q, targets)
    h = 1e-6
    for j in range(m.nv):
        dv = np.zeros(m.nv)
        dv[j] = h
        rp = orientation_residuals(m, pin.integrate(m, q, dv), targets)[0]
        rm = orientation_residuals(m, pin.integrate(m, q, -dv), targets)[0]
        np.testing.assert_allclose((rp - rm) / (2 * h), J[:, j], atol=1e-7)
    # the identity solve_ik's exact gradient rests on: Jlog3(M)^T log3(M) = log3(M)
    for rv in rng.normal(size=(5, 3)):
        M = exp3(rv)
        np.testing.assert_allclose(pin.Jlog3(M).T @ pin.log3(M), pin.log3(M), atol=1e-12)


def test_exact_targets_free_knee_reproduce_wang_eq15_17():
    m = leg_model("free")
    q_true = gait(300)
    R = frame_rotations(m, q_true, [*FRAMES, "right_femur_imu"])
    res = solve_ik(m, {f: R[f] for f in FRAMES}, tol=TIGHT)
    assert res.converged.all() and res.task_errors.max() < 1e-9
    assert res.residual_rms.max() < 1e-9
    np.testing.assert_allclose(res.q, q_true, atol=1e-8)
    assert res.iterations[1:].mean() <= 4  # warm start: few GN steps per frame
    default = solve_ik(m, {f: R[f] for f in FRAMES})  # tol 1e-4 rad: ~2 steps per frame
    assert default.task_errors.max() < 1e-6 and default.iterations[1:].mean() <= 2.5
    # Wang eq 15-17 by hand from the targets (hip fixed at HIP)
    RF, RT = R["right_femur"], R["right_tibia"]
    t_efl, t_efm = HIP + RF @ P_EFL, HIP + RF @ P_EFM
    t_knee = (t_efl + t_efm) / 2
    t_lm, t_mm = RT @ P_LM + t_knee, RT @ P_MM + t_knee
    d = m.createData()
    for n in range(0, 300, 7):
        pin.framesForwardKinematics(m, d, res.q[n])
        for name, t in [("EFL", t_efl), ("EFM", t_efm), ("LM", t_lm), ("MM", t_mm)]:
            assert np.linalg.norm(d.oMf[m.getFrameId(name)].translation - t[n]) < 1e-6
    # IMU frames are targets like any other: same solution from the femur IMU
    res_imu = solve_ik(
        m, {"right_femur_imu": R["right_femur_imu"], "right_tibia": R["right_tibia"]}, tol=TIGHT
    )
    np.testing.assert_allclose(res_imu.q[:, :6], q_true[:, :6], atol=1e-8)
    np.testing.assert_array_equal(res_imu.q[:, 6:], 0.0)  # ankle unobserved: stays at q0


def _hinge_problem(n=40, seed=2):
    q_true = gait(n, seed)
    return frame_rotations(leg_model("free"), q_true, FRAMES)  # tibia has off-axis rotation


def test_hinge_knee_is_weighted_least_squares_optimum():
    m = leg_model("hinge")
    R = _hinge_problem()
    w = {"right_femur": 2.0, "right_tibia": 1.0, "right_foot": 0.5}
    res = solve_ik(m, R, w, tol=TIGHT)
    assert res.converged.all()
    assert res.task_errors[:, 1].max() > 0.01  # the hinge cannot follow the off-axis tibia
    default = solve_ik(m, R, w)  # the default tol bounds the distance to the optimum
    assert np.abs(default.q - res.q).max() < 1e-4
    for n in (0, 17, 39):
        tg = {f: R[f][n] for f in FRAMES}
        r, J = orientation_residuals(m, res.q[n], tg)
        W = np.repeat([w[f] for f in FRAMES], 3)
        assert np.abs(J.T @ (W * r)).max() < 1e-8  # stationary point of the weighted cost
        best = minimize(lambda q, tg=tg: cost(m, q, tg, w), res.q[n] + 0.05, method="BFGS")
        assert cost(m, res.q[n], tg, w) <= best.fun + 1e-10
        np.testing.assert_allclose(res.q[n], best.x, atol=1e-4)


def test_weights_hand_checkable_and_shift_compromise():
    # one revolute about z, two frames on it: optimum angle is the weighted mean of the targets
    m = pin.Model()
    j = m.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "z")
    for name in ("a", "b"):
        m.addFrame(pin.Frame(name, j, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME))
    a, b = np.array([0.2, -0.4]), np.array([0.8, 0.5])
    res = solve_ik(m, {"a": rot_z(a), "b": rot_z(b)}, {"a": 3.0, "b": 1.0})
    np.testing.assert_allclose(res.q[:, 0], (3 * a + b) / 4, atol=1e-10)
    # Tikhonov pull to q0 = 0: 1/2 (q - a)^2 + 1/2 lambda q^2  ->  q = a / (1 + lambda)
    res = solve_ik(m, {"a": rot_z(a)}, regularization=0.5, tol=TIGHT)
    np.testing.assert_allclose(res.q[:, 0], a / 1.5, atol=1e-10)
    # leg: a heavier femur weight pulls the compromise towards the femur target
    m = leg_model("hinge")
    R = _hinge_problem(20)
    errs = [
        solve_ik(m, R, {"right_femur": wf}, tol=TIGHT).task_errors.mean(axis=0)
        for wf in (0.1, 1.0, 10.0, 1e4)
    ]
    femur, tibia = np.array(errs)[:, 0], np.array(errs)[:, 1]
    assert np.all(np.diff(femur) < 0) and np.all(np.diff(tibia) > 0) and femur[-1] < 1e-4


def test_joint_limits_respected_and_optimal():
    lim = (0.0, 0.9)
    m = leg_model("hinge", knee_limits=[lim])
    R = _hinge_problem(40)  # knee flexion up to 1.15 rad
    iq = m.joints[m.getJointId("right_knee_0")].idx_q
    free = solve_ik(m, R, limits=False)
    assert free.q[:, iq].max() > 1.0
    res = solve_ik(m, R, tol=TIGHT)
    assert res.converged.all()
    assert np.all(res.q[:, iq] >= lim[0]) and np.all(res.q[:, iq] <= lim[1])
    n = int(np.argmax(free.q[:, iq]))
    assert res.q[n, iq] == lim[1]
    tg = {f: R[f][n] for f in FRAMES}
    w = dict.fromkeys(FRAMES, 1.0)
    bounds = [(None, None)] * m.nq
    bounds[iq] = lim
    x0 = np.clip(res.q[n] + 0.05, -10, 10)
    x0[iq] = 0.8
    best = minimize(lambda q: cost(m, q, tg, w), x0, method="L-BFGS-B", bounds=bounds)
    assert cost(m, res.q[n], tg, w) <= best.fun + 1e-9


def test_warm_start_continuity_no_wrap():
    m = leg_model("free")
    q_true = gait(400)
    q_true[:, 2] = np.linspace(0.0, 8.0, 400)  # hip rotation about y beyond 2 pi
    R = frame_rotations(m, q_true, FRAMES)
    res = solve_ik(m, R, tol=TIGHT)
    np.testing.assert_allclose(res.q, q_true, atol=1e-8)
    assert np.abs(np.diff(res.q, axis=0)).max() < 0.1
    pred = solve_ik(m, R, tol=TIGHT, extrapolate=True)  # constant-velocity warm start
    np.testing.assert_allclose(pred.q, q_true, atol=1e-8)


def test_nan_frames_skipped_and_partial_targets():
    m = leg_model("free")
    q_true = gait(60)
    R = {f: v.copy() for f, v in frame_rotations(m, q_true, FRAMES).items()}
    for f in FRAMES:
        R[f][10:13] = np.nan
    R["right_foot"][30:35] = np.nan
    res = solve_ik(m, R, tol=TIGHT)
    assert np.isnan(res.q[10:13]).all() and not res.converged[10:13].any()
    assert (res.iterations[10:13] == 0).all() and np.isnan(res.residual_rms[10:13]).all()
    ok = np.r_[0:10, 13:60]
    assert res.converged[ok].all()
    np.testing.assert_allclose(res.q[13:30], q_true[13:30], atol=1e-8)  # recovers after the gap
    np.testing.assert_allclose(res.q[30:35, :6], q_true[30:35, :6], atol=1e-8)
    np.testing.assert_array_equal(res.q[30:35, 6:], np.repeat(res.q[29:30, 6:], 5, 0))  # held
    assert np.isnan(res.task_errors[30:35, 2]).all() and res.residual_rms[30:35].max() < 1e-9


@pytest.mark.parametrize("root", ["freeflyer", "spherical"])
def test_floating_root_orientation_from_pelvis(root):
    m = leg_model("free", root=root)
    rng = np.random.default_rng(3)
    legs = gait(50)
    pelvis = exp3(0.3 * np.sin(np.linspace(0, 3, 50))[:, None] * normalize(rng.normal(size=3)))
    q_true = np.array([pin.neutral(m)] * 50)
    for n in range(50):
        quat = pin.Quaternion(pelvis[n]).coeffs()  # x y z w as pinocchio stores it
        q_true[n, m.nq - 12 : m.nq - 8] = quat
        q_true[n, m.nq - 8 :] = legs[n]
    if root == "freeflyer":
        q_true[:, :3] = [0.1, 0.9, -0.2]
    R = frame_rotations(m, q_true, ["pelvis", *FRAMES])
    q0 = pin.neutral(m)
    if root == "freeflyer":
        q0[:3] = [0.1, 0.9, -0.2]
    res = solve_ik(m, R, q0=q0, tol=TIGHT)
    assert res.converged.all() and res.task_errors.max() < 1e-9
    np.testing.assert_allclose(res.q[:, m.nq - 8 :], legs, atol=1e-8)
    if root == "freeflyer":
        np.testing.assert_array_equal(res.q[:, :3], np.tile(q0[:3], (50, 1)))  # unobservable


def test_root_rotation_expresses_targets_in_model():
    m = leg_model("free")
    q_true = gait(30)
    R = frame_rotations(m, q_true, FRAMES)
    pelvis = rot_y(0.7) @ rot_x(-0.2)  # world orientation of the model's fixed pelvis
    res = solve_ik(m, {f: pelvis @ v for f, v in R.items()}, root=pelvis, tol=TIGHT)
    np.testing.assert_allclose(res.q, q_true, atol=1e-8)


def test_human_urdf_right_leg():
    from pipeline.model.resources import human_urdf

    m = pin.buildModelFromUrdf(str(human_urdf()))
    leg = [
        m.joints[m.getJointId(n)].idx_q
        for n in m.names
        if n.startswith(("right_hip", "right_knee", "right_ankle"))
    ]
    rng = np.random.default_rng(4)
    lo, hi = m.lowerPositionLimit[leg], m.upperPositionLimit[leg]
    mid, half = (lo + hi) / 2, (hi - lo) / 2
    t = np.linspace(0, 1, 80)[:, None]
    q_true = np.tile(pin.neutral(m), (80, 1))
    q_true[:, leg] = mid + 0.6 * half * np.sin(2 * np.pi * t + rng.uniform(0, 6, len(leg)))
    names = ["right_upperleg", "right_lowerleg", "right_foot"]
    R = frame_rotations(m, q_true, names)
    q0 = pin.neutral(m)
    q0[leg] = mid
    res = solve_ik(m, R, q0=q0, tol=TIGHT)
    assert res.converged.all() and res.task_errors.max() < 1e-9
    np.testing.assert_allclose(res.q, q_true, atol=1e-7)
    # targets beyond the URDF limits: the solution stays in the box, pinned at the bounds
    q_far = q_true.copy()
    q_far[:, leg] = mid + 1.3 * half * np.sin(2 * np.pi * t + rng.uniform(0, 6, len(leg)))
    R_far = frame_rotations(m, q_far, names)
    res = solve_ik(m, R_far, q0=q0)
    assert np.all(res.q[:, leg] >= lo) and np.all(res.q[:, leg] <= hi)
    assert np.any(res.q[:, leg] == lo) and np.any(res.q[:, leg] == hi)
    # converged frames are within tol of a tight solve. The 2 others are flagged: one at hip_X =
    # 90 deg (the template's upper limit: Z-X-Y gimbal lock), one with an 18 deg residual, where
    # Gauss-Newton's linear rate is ~0.7 and 20 iterations do not suffice
    ref = solve_ik(m, R_far, q0=q0, tol=1e-12, max_iters=500)
    ok = res.converged
    assert ok.sum() >= 78 and np.abs(res.q[ok] - ref.q[ok]).max() < 1e-4


def test_input_errors_name_the_target():
    m = leg_model("free")
    R = frame_rotations(m, gait(5), FRAMES)
    with pytest.raises(InputError, match="right_femr"):
        solve_ik(m, {"right_femr": R["right_femur"]})
    with pytest.raises(InputError, match="right_tibia.*shape"):
        solve_ik(m, {"right_femur": R["right_femur"], "right_tibia": np.zeros((5, 3))})
    with pytest.raises(InputError, match="same number"):
        solve_ik(m, {"right_femur": R["right_femur"], "right_tibia": R["right_tibia"][:3]})
    with pytest.raises(InputError, match="right_foot.*rotation"):
        solve_ik(m, {"right_foot": 2 * R["right_foot"]})
    with pytest.raises(InputError, match="right_femur.*weight"):
        solve_ik(m, {OrientationTask("right_femur", -1.0): R["right_femur"]})
    with pytest.raises(InputError, match="q0"):
        solve_ik(m, R, q0=np.zeros(3))
    with pytest.raises(InputError, match="root"):
        solve_ik(m, R, root=np.eye(4))


def test_missing_foot_target_with_zero_damping_is_solved():
    """Regression: with ``damping=0`` a frame whose foot target is missing leaves the ankle DoFs
    without information; the normal matrix is singular and LAPACK's ``dposv`` fails (``info > 0``).
    That failure was ignored (converged False, a 72.6 deg residual on a reachable frame); the step
    is now the minimum-norm one in the observed subspace, the ankle held."""
    from pipeline.model import Skeleton, SubjectGeometry

    sk = Skeleton.build(SubjectGeometry.default(1.75, "m", "right"), knee="free", legs=("right",))
    rng = np.random.default_rng(3)
    frames = ["right_femur", "right_tibia", "right_foot"]
    lo, hi = sk.lower_limits, sk.upper_limits
    Q = np.array([lo + (hi - lo) * rng.uniform(0.3, 0.7, sk.nq) for _ in range(4)])
    targets = frame_rotations(sk.model, Q, frames)
    targets["right_foot"][2] = np.nan  # frame 2: no foot target
    res = solve_ik(sk.model, targets, damping=0.0)
    assert res.converged.all()
    assert np.degrees(np.nanmax(res.residual_rms)) < 1e-3
    ankle = [sk.q_index(j) for j in sk.leg_joints("right", "ankle")]
    np.testing.assert_allclose(res.q[2, ankle], res.q[1, ankle])  # held at the previous frame
