"""Scaled lower-limb model: geometry checks, URDF content, Pinocchio kinematics (Wang eq 15-17)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from _helpers import MIRROR, asymmetric_subject

from pipeline.errors import InputError
from pipeline.model import (
    Skeleton,
    SubjectGeometry,
    build_urdf,
    imu_frame_names,
    joint_names,
    landmark_frame_names,
    mirror_point,
)
from pipeline.rotations import (
    euler_zxy_from_matrix,
    exp3,
    matrix_from_euler_zxy,
)


@pytest.fixture(scope="module")
def models(tmp_path_factory):
    out = tmp_path_factory.mktemp("models")
    g = asymmetric_subject()
    return {
        k: Skeleton.from_urdf(build_urdf(g, out / f"{k}.urdf", knee=k)) for k in ("hinge", "free")
    }


def q_free(sk: Skeleton, side: str, hip: np.ndarray, knee: np.ndarray, q=None) -> np.ndarray:
    """q of the free-knee model from ISB angles [flexion, adduction, internal rotation]."""
    q = sk.neutral() if q is None else q
    for name, v in zip(("hip_Z", "hip_X", "hip_Y"), hip, strict=True):
        q[sk.q_index(f"{side}_{name}")] = v
    for name, v in zip(("knee_Z", "knee_X", "knee_Y"), knee, strict=True):
        q[sk.q_index(f"{side}_{name}")] = v
    return q


# ---- geometry -----------------------------------------------------------------------------------
def test_geometry_derived_dimensions_by_hand():
    g = asymmetric_subject()
    np.testing.assert_allclose(g.kjc_femur, [0.001, -0.379, -0.001])
    np.testing.assert_allclose(g.ajc_tibia, [-0.001, -0.365, 0.001])
    assert g.thigh_length == pytest.approx(np.sqrt(0.001**2 + 0.379**2 + 0.001**2))
    assert g.knee_width == pytest.approx(np.sqrt(0.010**2 + 0.014**2 + 0.092**2))
    assert g.ankle_width == pytest.approx(np.sqrt(0.022**2 + 0.018**2 + 0.064**2))
    # template hip offset (0.023, -0.1, +-0.082) at 1.80 m, scaled by height
    np.testing.assert_allclose(g.right_hip, np.array([0.023, -0.1, 0.082]) * 1.62 / 1.80)
    np.testing.assert_allclose(g.left_hip, np.array([0.023, -0.1, -0.082]) * 1.62 / 1.80)
    assert g.foot_length_m == pytest.approx(0.152 * 1.62)  # Drillis & Contini
    assert np.linalg.norm(g.knee_axis_femur) == pytest.approx(1.0)
    # foot landmarks by hand: L = 0.24624 m, breadth 0.0891 m, ankle height 0.06318 m; the heel
    # 23.6 % of L behind the ankle centre, MT1 / MT5 at 72.5 / 63.5 %, sole on the floor
    L, b, h = 0.152 * 1.62, 0.055 * 1.62, 0.039 * 1.62
    foot = g.foot_landmarks
    np.testing.assert_allclose(foot["HEE"], [-0.236 * L, -h, 0.0])
    np.testing.assert_allclose(foot["TOE"], [0.764 * L, -h, 0.0])
    np.testing.assert_allclose(foot["MT1"], [(0.725 - 0.236) * L, -h, -b / 2])  # medial
    np.testing.assert_allclose(foot["MT5"], [(0.635 - 0.236) * L, -h, b / 2])  # lateral
    left = g.mirrored().foot_landmarks
    assert left["MT5"][2] == pytest.approx(-b / 2) and left["MT1"][2] == pytest.approx(b / 2)
    with pytest.raises(InputError, match="foot length"):
        replace(g, foot_length_m=0.5)


def test_mirrored_flips_landmark_z_and_keeps_axes_rightward():
    g = asymmetric_subject()
    m = g.mirrored()
    assert m.side == "left" and m.mirrored().side == "right"
    np.testing.assert_allclose(m.femur_landmarks["EFL"], [-0.004, -0.386, -0.045])
    np.testing.assert_allclose(m.tibia_landmarks["MM"], [-0.012, -0.356, 0.031])
    a = g.knee_axis_femur
    np.testing.assert_allclose(m.knee_axis_femur, [-a[0], -a[1], a[2]])
    assert m.knee_axis_femur[2] > 0 and m.thigh_length == pytest.approx(g.thigh_length)
    np.testing.assert_allclose(m.mirrored().tibia_landmarks["LM"], g.tibia_landmarks["LM"])


@pytest.mark.parametrize(
    "over, field",
    [
        (dict(height_m=162.0), "height"),
        (dict(sex="x"), "sex"),
        (  # millimetres instead of metres
            dict(femur_landmarks={"EFM": [0, -372.0, -47.0], "EFL": [0, -386.0, 45.0]}),
            "thigh",
        ),
        (  # medial / lateral swapped for a right leg
            dict(femur_landmarks={"EFM": [0, -0.372, 0.047], "EFL": [0, -0.386, -0.045]}),
            "landmarks",
        ),
        (dict(femur_landmarks={"EFM": [0, -0.372, -0.047]}), "femur"),
        (dict(tibia_landmarks={"MM": [0, -0.36, -0.2], "LM": [0, -0.36, 0.2]}), "ankle_width"),
        (dict(tibia_landmarks={"MM": [0.05, -0.36, -0.03], "LM": [0.05, -0.36, 0.03]}), "tibia"),
        (dict(knee_axis_femur=[0.0, 0.0, -1.0]), "knee_axis_femur"),
        (dict(knee_axis_tibia=[0.0, 0.0, 0.0]), "knee_axis_tibia"),
        (dict(right_hip=[0.02, -0.09, -0.08]), "right_hip"),
        (dict(side="middle"), "side"),
    ],
)
def test_implausible_geometry_rejected(over, field):
    with pytest.raises(InputError) as e:
        asymmetric_subject(**over)
    assert e.value.field == field


def test_builder_rejects_bad_options(tmp_path):
    g = asymmetric_subject()
    with pytest.raises(InputError):
        build_urdf(g, tmp_path / "a.urdf", knee="ball")
    with pytest.raises(InputError):
        build_urdf(g, tmp_path / "a.urdf", legs=("middle",))
    with pytest.raises(InputError):
        build_urdf(g, tmp_path / "a.urdf", imu_placements={"right_femur_imu": np.ones((4, 4))})
    with pytest.raises(InputError):
        build_urdf(g, tmp_path / "a.urdf", imu_placements={"head_imu": np.eye(4)})
    with pytest.raises(InputError, match="ankle"):
        Skeleton.build(g, ankle="ball")


# ---- URDF content -------------------------------------------------------------------------------
@pytest.mark.parametrize("knee", ["hinge", "free"])
def test_urdf_loads_with_expected_joints_and_frames(models, knee):
    sk = models[knee]
    assert sorted(sk.joint_names) == sorted(joint_names(knee))
    assert sk.nq == (12 if knee == "hinge" else 16) and sk.knee == knee
    assert sk.legs == ("right", "left")
    for name in [*sk.segment_frames.values(), *landmark_frame_names(), *imu_frame_names()]:
        assert sk.model.frames[sk.frame_id(name)].name == name
    assert set(sk.segment_frames) == {
        "pelvis",
        *(f"{s}_{x}" for s in ("right", "left") for x in ("femur", "tibia", "foot")),
    }
    assert sk.leg_joints("right", "hip") == ["right_hip_Z", "right_hip_X", "right_hip_Y"]
    with pytest.raises(InputError):
        sk.frame_id("right_patella")


def test_masses_scale_with_height_cubed_or_body_mass(tmp_path):
    def total_mass(g):
        sk = Skeleton.from_urdf(build_urdf(g, tmp_path / "x.urdf"), root="freeflyer")
        return pin.computeTotalMass(sk.model)

    template = 10.65 + 2 * (9.22 + 3.6 + 0.9)  # human.urdf pelvis + legs at 1.80 m / 75 kg
    assert total_mass(asymmetric_subject()) == pytest.approx(template * (1.62 / 1.80) ** 3)
    assert total_mass(asymmetric_subject(body_mass_kg=60.0)) == pytest.approx(
        template * 60.0 / 75.0
    )


def test_imu_frames_default_sites_and_custom_placement(tmp_path):
    g = asymmetric_subject()
    R = exp3(np.array([0.1, -0.2, 0.3]))
    p = np.array([0.01, -0.2, -0.05])
    path = build_urdf(g, tmp_path / "i.urdf", imu_placements={"left_tibia_imu": (R, p)})
    sk = Skeleton.from_urdf(path)
    T = sk.relative_pose("left_tibia_imu", "left_tibia", sk.neutral())
    np.testing.assert_allclose(T[:3, :3], R, atol=1e-12)
    np.testing.assert_allclose(T[:3, 3], p, atol=1e-12)
    for side, lat in (("right", 1.0), ("left", -1.0)):
        fem = sk.relative_pose(f"{side}_femur_imu", f"{side}_femur")
        np.testing.assert_allclose(fem[:3, :3], np.eye(3), atol=1e-12)
        assert lat * fem[2, 3] > 0.05  # lateral thigh
        assert -0.7 * g.thigh_length < fem[1, 3] < -0.3 * g.thigh_length
        foot = sk.relative_pose(f"{side}_foot_imu", f"{side}_foot")
        assert foot[0, 3] > 0.03  # dorsum, anterior of the ankle
    tib = sk.relative_pose("right_tibia_imu", "right_tibia")
    assert tib[0, 3] > 0 and tib[2, 3] < 0  # anterior-medial (medial = -z on the right)


# ---- kinematics ---------------------------------------------------------------------------------
@pytest.mark.parametrize("knee", ["hinge", "free"])
def test_landmark_frames_at_geometry_positions(models, knee):
    sk, g = models[knee], asymmetric_subject()
    rng = np.random.default_rng(1)
    for side in ("right", "left"):
        gs = g.for_side(side)
        pts = {
            "femur": {**gs.femur_landmarks, "HJC": np.zeros(3), "KJC": gs.kjc_femur},
            "tibia": {**gs.tibia_landmarks, "AJC": gs.ajc_tibia},
        }
        for q in (sk.neutral(), rng.uniform(-1.0, 1.0, sk.nq)):
            sk.forward(q)
            for seg, d in pts.items():
                for lm, pos in d.items():
                    T = sk.relative_pose(f"{side}_{lm}", f"{side}_{seg}")
                    np.testing.assert_allclose(T[:3, 3], pos, atol=1e-12)
        # q = 0, pelvis = world: the femur frame is the pelvis frame moved to the hip centre
        sk.forward(sk.neutral())
        for lm, pos in gs.femur_landmarks.items():
            np.testing.assert_allclose(sk.frame_position(f"{side}_{lm}"), gs.hip + pos, atol=1e-12)
        np.testing.assert_allclose(sk.frame_rotation(f"{side}_femur"), np.eye(3), atol=1e-12)
        np.testing.assert_allclose(sk.frame_position(f"{side}_tibia"), gs.hip + gs.kjc_femur)
        np.testing.assert_allclose(
            sk.frame_position(f"{side}_foot"), sk.frame_position(f"{side}_AJC")
        )


@pytest.mark.parametrize("knee", ["hinge", "free"])
def test_segment_dimensions_by_fk_equal_geometry(models, knee):
    sk, g = models[knee], asymmetric_subject()
    q = np.random.default_rng(2).uniform(-1.2, 1.2, sk.nq)
    sk.forward(q)
    for side in ("right", "left"):

        def pos(n, side=side):
            return sk.frame_position(f"{side}_{n}")

        assert np.linalg.norm(pos("HJC") - pos("KJC")) == pytest.approx(g.thigh_length, abs=1e-12)
        assert np.linalg.norm(pos("KJC") - pos("AJC")) == pytest.approx(g.shank_length, abs=1e-12)
        assert np.linalg.norm(pos("EFM") - pos("EFL")) == pytest.approx(g.knee_width, abs=1e-12)
        assert np.linalg.norm(pos("MM") - pos("LM")) == pytest.approx(g.ankle_width, abs=1e-12)
        np.testing.assert_allclose(pos("KJC"), 0.5 * (pos("EFM") + pos("EFL")), atol=1e-12)


@pytest.mark.parametrize("side", ["right", "left"])
def test_free_knee_reproduces_wang_eq_15_17(models, side):
    """FK of EFL/EFM/LM/MM equals eq 15-17 computed by hand from e_F and e_T (ZXY angles)."""
    sk, g = models["free"], asymmetric_subject().for_side(side)
    lat = 1.0 if side == "right" else -1.0
    rng = np.random.default_rng(3)
    for _ in range(20):
        e_F = matrix_from_euler_zxy(rng.uniform([-0.5, -0.6, -0.8], [1.5, 0.6, 0.8]))
        e_T = e_F @ matrix_from_euler_zxy(rng.uniform([-1.5, -0.4, -0.6], [0.0, 0.4, 0.6]))
        hip = euler_zxy_from_matrix(e_F) * [1.0, lat, lat]  # ISB angles -> q (mirrored axes)
        rel = euler_zxy_from_matrix(e_F.T @ e_T)
        knee = rel * [-1.0, lat, lat]
        q = q_free(sk, side, hip, knee, rng.uniform(-1, 1, sk.nq))  # other leg anywhere
        sk.forward(q)
        h = sk.frame_position(f"{side}_HJC")
        np.testing.assert_allclose(h, g.hip, atol=1e-12)  # pelvis fixed: hip fixed
        t = {n: e_F @ g.femur_landmarks[n] for n in ("EFL", "EFM")}  # eq 15
        t_knee = 0.5 * (t["EFL"] + t["EFM"])  # eq 16
        t.update({n: e_T @ g.tibia_landmarks[n] + t_knee for n in ("LM", "MM")})  # eq 17
        for n, v in t.items():
            assert np.abs(sk.frame_position(f"{side}_{n}") - h - v).max() < 1e-9
        np.testing.assert_allclose(sk.frame_position(f"{side}_KJC") - h, t_knee, atol=1e-12)
        np.testing.assert_allclose(sk.frame_rotation(f"{side}_femur"), e_F, atol=1e-12)
        np.testing.assert_allclose(sk.frame_rotation(f"{side}_tibia"), e_T, atol=1e-12)


@pytest.mark.parametrize("side", ["right", "left"])
def test_hinge_keeps_knee_axis_fixed_in_both_segments(models, side):
    sk, g = models["hinge"], asymmetric_subject().for_side(side)
    rng = np.random.default_rng(4)
    j = sk.q_index(f"{side}_knee")
    for _ in range(10):
        q = rng.uniform(-1.5, 1.5, sk.nq)
        sk.forward(q)
        R_F, R_T = sk.frame_rotation(f"{side}_femur"), sk.frame_rotation(f"{side}_tibia")
        np.testing.assert_allclose(R_F @ g.knee_axis_femur, R_T @ g.knee_axis_tibia, atol=1e-12)
        np.testing.assert_allclose(
            sk.frame_position(f"{side}_tibia"), sk.frame_position(f"{side}_KJC"), atol=1e-12
        )
        # flexing by d turns the tibia about the rightward AoR by -d
        q2 = q.copy()
        q2[j] += 0.3
        sk.forward(q2)
        R_T2 = sk.frame_rotation(f"{side}_tibia")
        axis_world = R_F @ g.knee_axis_femur
        np.testing.assert_allclose(R_T2 @ R_T.T, exp3(-0.3 * axis_world), atol=1e-12)
        # flexion moves the ankle posteriorly in the femoral frame
        sk.forward(sk.neutral())
        a0 = sk.relative_pose(f"{side}_AJC", f"{side}_femur")[0, 3]
        q3 = sk.neutral()
        q3[j] = 0.5
        sk.forward(q3)
        assert sk.relative_pose(f"{side}_AJC", f"{side}_femur")[0, 3] < a0 - 0.1


@pytest.mark.parametrize("knee", ["hinge", "free"])
def test_left_leg_mirrors_right_leg(models, knee):
    """Same q on both legs -> left landmarks are the sagittal mirror images of the right ones."""
    sk = models[knee]
    rng = np.random.default_rng(5)
    for _ in range(5):
        q = sk.neutral()
        for jn in sk.leg_joints("right", "hip") + sk.leg_joints("right", "knee"):
            v = rng.uniform(-0.5, 0.5) + (0.6 if "knee" in jn and jn[-1] != "X" else 0.0)
            q[sk.q_index(jn)] = v
            q[sk.q_index(jn.replace("right", "left"))] = v
        for side in ("right", "left"):
            for a in ("ankle_Z", "ankle_X"):
                q[sk.q_index(f"{side}_{a}")] = 0.2
        sk.forward(q)
        for lm in ("HJC", "KJC", "AJC", "EFM", "EFL", "MM", "LM"):
            np.testing.assert_allclose(
                sk.frame_position(f"left_{lm}"),
                mirror_point(sk.frame_position(f"right_{lm}")),
                atol=1e-12,
            )
        for seg in ("femur", "tibia", "foot"):  # rotations: M R M
            R_r, R_l = sk.frame_rotation(f"right_{seg}"), sk.frame_rotation(f"left_{seg}")
            np.testing.assert_allclose(R_l, MIRROR @ R_r @ MIRROR, atol=1e-12)


def test_isb_signs_of_hip_joints(models):
    """Positive hip_Z/X/Y = flexion, adduction, internal rotation on both legs (by hand)."""
    sk = models["free"]
    for side, lat in (("right", 1.0), ("left", -1.0)):
        sk.forward(sk.neutral())
        k0 = sk.frame_position(f"{side}_KJC")
        for joint, check in (
            ("hip_Z", lambda d: d[0] > 0.1),  # flexion: knee forward
            ("hip_X", lambda d, lat=lat: -lat * d[2] > 0.1),  # adduction: knee medially
        ):
            q = sk.neutral()
            q[sk.q_index(f"{side}_{joint}")] = 0.4
            sk.forward(q)
            assert check(sk.frame_position(f"{side}_KJC") - k0), (side, joint)
        q = sk.neutral()
        q[sk.q_index(f"{side}_hip_Y")] = 0.4
        sk.forward(q)
        x_axis = sk.frame_rotation(f"{side}_femur")[:, 0]  # anterior axis turns medially
        assert -lat * x_axis[2] > 0.3


def test_freeflyer_root_moves_everything(tmp_path):
    path = build_urdf(asymmetric_subject(), tmp_path / "ff.urdf", knee="free", legs=("right",))
    sk = Skeleton.from_urdf(path, root="freeflyer")
    assert sk.nq == 7 + 8 and sk.legs == ("right",) and sk.q_slice("root_joint") == slice(0, 7)
    q = sk.neutral()
    q[:3] = [1.0, 2.0, 3.0]
    R = exp3(np.array([0.0, 0.0, 0.5]))
    q[3:7] = pin.Quaternion(R).coeffs()  # x, y, z, w
    sk.forward(q)
    g = asymmetric_subject()
    np.testing.assert_allclose(
        sk.frame_position("right_EFM"), [1, 2, 3] + R @ (g.right_hip + g.femur_landmarks["EFM"])
    )
    assert Skeleton.from_urdf(path, root="spherical").nq == 4 + 8
    with pytest.raises(InputError):
        Skeleton.from_urdf(path, root="hovering")
    with pytest.raises(InputError):
        sk.forward(np.zeros(3))


def test_pinocchio_check_failure_is_an_input_error(monkeypatch):
    """The builder's self-check raised RuntimeError; the package's contract is InputError."""
    from pipeline.errors import InputError
    from pipeline.model import builder

    monkeypatch.setattr(builder, "joint_names", lambda *args: ["no_such_joint"])
    with pytest.raises(InputError, match="expected"):
        builder.urdf_text(builder.SubjectGeometry.default(1.75, "m", "right"), legs=("right",))


def test_the_model_is_built_in_memory(tmp_path, monkeypatch):
    """Skeleton.build once made a temporary folder with mkdtemp and never deleted it."""
    import tempfile

    monkeypatch.setenv("TMPDIR", str(tmp_path))
    tempfile.tempdir = None  # re-read TMPDIR
    try:
        sk = Skeleton.build(SubjectGeometry.default(1.75, "m", "right"), knee="hinge")
        assert sk.source is None and "<robot" in sk.urdf
        assert list(tmp_path.iterdir()) == []  # nothing written, nothing left behind
    finally:
        tempfile.tempdir = None


@pytest.mark.parametrize("side", ["right", "left"])
def test_a_free_ankle_adds_the_jcs_third_rotation(side):
    """The simulator's free ankle (Z-X-Y, as the JCS): its third joint is the ankle's third JCS
    angle (the foot's internal rotation relative to the tibia), the same sign on either leg; the
    other two angles and every frame above the ankle as the model's ankle puts them."""
    from pipeline.analysis.joint_angles import jcs_angles

    g = asymmetric_subject()
    free, universal = Skeleton.build(g, ankle="free"), Skeleton.build(g)
    assert free.ankle == "free" and universal.ankle == "universal"
    assert sorted(free.joint_names) == sorted(joint_names("free", ankle="free"))
    assert free.leg_joints(side, "ankle") == [f"{side}_ankle_{a}" for a in "ZXY"]
    angles = {"ankle_Z": 0.3, "ankle_X": 0.1, "ankle_Y": -0.2, "knee_Z": 0.4, "hip_Y": 0.1}
    q_free, q_universal = free.neutral(), universal.neutral()
    for name, v in angles.items():
        q_free[free.q_index(f"{side}_{name}")] = v
        if name != "ankle_Y":
            q_universal[universal.q_index(f"{side}_{name}")] = v
    free.forward(q_free)
    universal.forward(q_universal)

    def rotation(sk, frame):
        return sk.data.oMf[sk.frame_id(f"{side}_{frame}")].rotation

    got = jcs_angles(rotation(free, "tibia"), rotation(free, "foot"), "ankle", side)
    np.testing.assert_allclose(got, [0.3, 0.1, -0.2], atol=1e-12)
    for frame in ("tibia", "AJC", "MM", "tibia_imu"):
        np.testing.assert_allclose(rotation(free, frame), rotation(universal, frame), atol=1e-12)
