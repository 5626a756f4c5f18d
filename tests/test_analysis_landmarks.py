"""Landmark trajectories (Wang eq 15-17 by FK) and ISB joint angles (ZXY JCS)."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analysis.joint_angles import jcs_angles, joint_angles
from pipeline.analysis.landmarks import landmark_trajectories
from pipeline.errors import InputError
from pipeline.model import Skeleton, SubjectGeometry
from pipeline.rotations import matrix_from_euler_zxy, normalize, rot_x, rot_y, rot_z

ANGLES = ("flexion", "adduction", "rotation")


def subject(**over) -> SubjectGeometry:
    kw = dict(
        sex="m",
        height_m=1.78,
        femur_landmarks={"EFM": [0.003, -0.418, -0.051], "EFL": [-0.003, -0.425, 0.050]},
        tibia_landmarks={"MM": [-0.020, -0.392, -0.036], "LM": [0.018, -0.410, 0.035]},
        knee_axis_femur=normalize(np.array([0.05, -0.1, 1.0])),
        knee_axis_tibia=normalize(np.array([-0.04, 0.08, 1.0])),
    )
    kw.update(over)
    return SubjectGeometry(**kw)


@pytest.fixture(scope="module")
def free(tmp_path_factory):
    return Skeleton.build(subject(), knee="free")


@pytest.fixture(scope="module")
def hinge(tmp_path_factory):
    return Skeleton.build(subject(), knee="hinge")


def isb_configurations(sk: Skeleton, n: int, seed: int) -> tuple[np.ndarray, dict]:
    """Random q from ISB angles away from gimbal lock, and the angles used per joint."""
    rng = np.random.default_rng(seed)
    Q = np.zeros((n, sk.nq))
    truth = {}
    for side in sk.legs:
        for joint, lo, hi in (("hip", [-0.5, -0.5, -0.7], [1.5, 0.5, 0.7]),):
            ang = rng.uniform(lo, hi, (n, 3))
            for i, jn in enumerate(sk.leg_joints(side, joint)):
                Q[:, sk.q_index(jn)] = ang[:, i]
            truth[f"{side}_{joint}"] = ang
        knee = sk.leg_joints(side, "knee")
        ang = rng.uniform([0.0, -0.3, -0.5], [2.0, 0.3, 0.5], (n, 3))
        if len(knee) == 1:
            ang[:, 1:] = np.nan
        for i, jn in enumerate(knee):
            Q[:, sk.q_index(jn)] = ang[:, i]
        truth[f"{side}_knee"] = ang
        ankle = rng.uniform(-0.4, 0.4, (n, 2))
        for i, jn in enumerate(sk.leg_joints(side, "ankle")):
            Q[:, sk.q_index(jn)] = ankle[:, i]
        truth[f"{side}_ankle"] = ankle  # ankle_Z = dorsiflexion, ankle_X = inversion
    return Q, truth


def test_trajectories_equal_per_sample_forward_kinematics(free):
    Q, _ = isb_configurations(free, 40, seed=1)
    traj = landmark_trajectories(free, Q)
    assert set(traj) == set(free.landmark_frames) and len(traj) == 22
    for k in (0, 17, 39):
        free.forward(Q[k])
        for name, xyz in traj.items():
            np.testing.assert_allclose(xyz[k], free.frame_position(name), atol=1e-14)
    one = landmark_trajectories(free, Q[3], names=["right_MM"])
    assert one["right_MM"].shape == (1, 3)
    with pytest.raises(InputError):
        landmark_trajectories(free, np.zeros((5, free.nq + 1)))
    with pytest.raises(InputError):
        landmark_trajectories(free, Q, names=["right_toe"])


@pytest.mark.parametrize("side", ["right", "left"])
def test_trajectories_follow_wang_eq_15_17(free, side):
    """Vectorised eq 15-17 in NumPy from the segment rotations built from the ISB angles."""
    g = subject().for_side(side)
    lat = 1.0 if side == "right" else -1.0
    Q, truth = isb_configurations(free, 200, seed=2)
    h, k = truth[f"{side}_hip"], truth[f"{side}_knee"]
    e_F = matrix_from_euler_zxy(h * [1.0, lat, lat])
    e_T = e_F @ matrix_from_euler_zxy(k * [-1.0, lat, lat])
    traj = landmark_trajectories(free, Q)
    t_EFL = e_F @ g.femur_landmarks["EFL"]  # eq 15
    t_EFM = e_F @ g.femur_landmarks["EFM"]
    t_knee = 0.5 * (t_EFL + t_EFM)  # eq 16
    t_LM = e_T @ g.tibia_landmarks["LM"] + t_knee  # eq 17
    t_MM = e_T @ g.tibia_landmarks["MM"] + t_knee
    for name, t in (("EFL", t_EFL), ("EFM", t_EFM), ("KJC", t_knee), ("LM", t_LM), ("MM", t_MM)):
        assert np.abs(traj[f"{side}_{name}"] - g.hip - t).max() < 1e-9, name


def test_joint_angles_round_trip_zxy_chain(free):
    Q, truth = isb_configurations(free, 300, seed=3)
    ang = joint_angles(free, Q)
    assert len(ang) == 16
    for side in ("right", "left"):
        for joint in ("hip", "knee"):
            for i, a in enumerate(ANGLES):
                np.testing.assert_allclose(
                    ang[f"{side}_{joint}_{a}"], truth[f"{side}_{joint}"][:, i], atol=1e-12
                )
        # the 2-DoF ankle: its coordinates are the JCS dorsiflexion and inversion on both sides
        for i, a in enumerate(("flexion", "inversion")):
            np.testing.assert_allclose(
                ang[f"{side}_ankle_{a}"], truth[f"{side}_ankle"][:, i], atol=1e-12
            )


def test_joint_angles_hinge(hinge, tmp_path):
    Q, truth = isb_configurations(hinge, 50, seed=4)
    ang = joint_angles(hinge, Q)
    for side in ("right", "left"):
        for i, a in enumerate(ANGLES):
            np.testing.assert_allclose(
                ang[f"{side}_hip_{a}"], truth[f"{side}_hip"][:, i], atol=1e-12
            )
    # knee axes along z in both segments: the hinge is pure JCS flexion
    sk = Skeleton.build(
        subject(knee_axis_femur=[0, 0, 1.0], knee_axis_tibia=[0, 0, 1.0]), "hinge"
    )
    Q, truth = isb_configurations(sk, 50, seed=5)
    ang = joint_angles(sk, Q)
    for side in ("right", "left"):
        np.testing.assert_allclose(
            ang[f"{side}_knee_flexion"], truth[f"{side}_knee"][:, 0], atol=1e-12
        )
        np.testing.assert_allclose(ang[f"{side}_knee_adduction"], 0.0, atol=1e-12)
        np.testing.assert_allclose(ang[f"{side}_knee_rotation"], 0.0, atol=1e-12)


def test_jcs_angle_signs_by_hand():
    I = np.eye(3)
    # right hip: rotation about +z = flexion; about +x = adduction; about +y = internal rotation
    np.testing.assert_allclose(jcs_angles(I, rot_z(0.3), "hip", "right"), [0.3, 0, 0], atol=1e-15)
    np.testing.assert_allclose(jcs_angles(I, rot_x(0.2), "hip", "right"), [0, 0.2, 0], atol=1e-15)
    np.testing.assert_allclose(jcs_angles(I, rot_y(0.1), "hip", "right"), [0, 0, 0.1], atol=1e-15)
    # left leg (mirrored frames): the same rotations are abduction / external rotation
    np.testing.assert_allclose(jcs_angles(I, rot_x(0.2), "hip", "left"), [0, -0.2, 0], atol=1e-15)
    np.testing.assert_allclose(jcs_angles(I, rot_y(0.1), "hip", "left"), [0, 0, -0.1], atol=1e-15)
    # knee flexion: the tibia turns about -z relative to the femur
    np.testing.assert_allclose(jcs_angles(I, rot_z(-0.5), "knee", "left"), [0.5, 0, 0], atol=1e-15)
    # relative rotation only: a common world rotation cancels (stacked input)
    W = rot_x(0.7) @ rot_y(-0.4)
    R_d = W @ matrix_from_euler_zxy(np.array([0.4, 0.1, -0.2]))
    out = jcs_angles(np.stack([W, W]), np.stack([R_d, R_d]), "knee", "right")
    np.testing.assert_allclose(out, [[-0.4, 0.1, -0.2]] * 2, atol=1e-12)
    # ankle: the foot turning about +z (toes up) is dorsiflexion; about +x (lateral edge down,
    # sole facing medially) inversion, on both legs
    np.testing.assert_allclose(jcs_angles(I, rot_z(0.2), "ankle", "right"), [0.2, 0, 0],
                               atol=1e-15)
    np.testing.assert_allclose(jcs_angles(I, rot_x(0.1), "ankle", "right"), [0, 0.1, 0],
                               atol=1e-15)
    np.testing.assert_allclose(jcs_angles(I, rot_x(-0.1), "ankle", "left"), [0, 0.1, 0],
                               atol=1e-15)
    with pytest.raises(InputError):
        jcs_angles(I, I, "elbow", "right")


def test_3000_frames_all_landmarks(free):
    # speed is measured in scripts/bench_ik.py, not asserted here (shared, noisy machines);
    # here: every landmark of every frame equals the model's own forward kinematics, and the
    # distances that the skeleton fixes (hip-knee, knee-ankle) stay those of the geometry
    Q, _ = isb_configurations(free, 3000, seed=6)
    traj = landmark_trajectories(free, Q)
    assert set(traj) == set(free.landmark_frames)
    for k in (0, 1234, 2999):
        free.forward(Q[k])
        for name, xyz in traj.items():
            np.testing.assert_allclose(xyz[k], free.frame_position(name), atol=1e-12)
    free.forward(free.neutral())
    for side in ("right", "left"):
        for a, b in (("HJC", "KJC"), ("KJC", "AJC")):
            pa, pb = free.frame_position(f"{side}_{a}"), free.frame_position(f"{side}_{b}")
            d = np.linalg.norm(traj[f"{side}_{a}"] - traj[f"{side}_{b}"], axis=1)
            np.testing.assert_allclose(d, np.linalg.norm(pa - pb), atol=1e-12)


@pytest.mark.parametrize("side", ["right", "left"])
def test_wang_trajectories_equal_model_forward_kinematics(free, side):
    """The closed form used by `reproduce` (eq 15-17) equals FK of the free-knee model."""
    from pipeline.analysis.landmarks import wang_trajectories

    g = subject().for_side(side)
    lat = 1.0 if side == "right" else -1.0
    Q, truth = isb_configurations(free, 100, seed=7)
    e_F = matrix_from_euler_zxy(truth[f"{side}_hip"] * [1.0, lat, lat])
    e_T = e_F @ matrix_from_euler_zxy(truth[f"{side}_knee"] * [-1.0, lat, lat])
    closed = wang_trajectories(e_F, e_T, g.femur_landmarks, g.tibia_landmarks)
    fk = landmark_trajectories(free, Q)
    for name, t in closed.items():
        assert np.abs(fk[f"{side}_{name}"] - g.hip - t).max() < 1e-9, name
    with pytest.raises(InputError):
        wang_trajectories(e_F[:, :2], e_T, g.femur_landmarks, g.tibia_landmarks)
