from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pipeline.cli import main
from pipeline.errors import InputError
from pipeline.model import Skeleton
from pipeline.model.anthropometry import load_table1
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures, population_knee_axis, scale_model

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "wang2023"


def test_population_knee_axis_is_unit_and_points_right():
    for sex in ("m", "f", "all"):
        a = population_knee_axis(sex)
        assert np.linalg.norm(a.femur_axis) == pytest.approx(1.0)
        assert a.femur_axis[2] > 0.9 and a.tibia_axis[2] > 0.99
    with pytest.raises(InputError, match="sex"):
        population_knee_axis("x")


def test_geometry_uses_table1_by_hand():
    # male, 1.74 m, height only: EFM y = -11.949 - 0.232 * 1740 = -415.629 mm (Table I, m, h)
    geometry, landmarks = geometry_from_measures(Measures("m", 1.74))
    assert geometry.femur_landmarks["EFM"][1] == pytest.approx(-0.415629, abs=1e-9)
    # knee width k given: EFL z = 0.052 + 0.499 * 100 mm = 49.952 mm (Table I, m, k)
    geometry, _ = geometry_from_measures(Measures("m", 1.74, knee_width_m=0.100))
    assert geometry.femur_landmarks["EFL"][2] == pytest.approx(0.049952, abs=1e-9)
    np.testing.assert_allclose(geometry.knee_axis_femur, population_knee_axis("m").femur_axis)


def test_scale_model_writes_a_loadable_urdf_with_regression_dimensions(tmp_path):
    m = Measures("f", 1.62, knee_width_m=0.095)
    path = scale_model(m, tmp_path / "s.urdf", knee="hinge")
    model = pin.buildModelFromUrdf(str(path))
    assert model.existFrame("right_EFM") and model.existFrame("left_LM")
    sk = Skeleton.from_urdf(path)
    sk.forward(sk.neutral())
    # at q = 0 the femoral frame is aligned with the pelvis (world), so the z separation of the
    # epicondyles is Table I (f, k): EFL z - EFM z = 2 * (0.152 + 0.498 * 95) mm = 94.924 mm
    dz = sk.frame_position("right_EFL")[2] - sk.frame_position("right_EFM")[2]
    assert dz == pytest.approx(0.094924, abs=1e-9)


def test_scale_cli_refuses_implausible_height_without_writing(tmp_path, capsys):
    out = tmp_path / "x.urdf"
    code = main(["scale", "--sex", "f", "--height-m", "162", "--out", str(out)])
    assert code == 2
    err = capsys.readouterr().err
    assert "height_m" in err and "centimetres" in err and "Traceback" not in err
    assert not out.exists()
    assert main(["scale", "--sex", "f", "--height-m", "1.62", "--knee-width-m", "-0.1",
                 "--out", str(out)]) == 2
    assert not out.exists()


def test_scale_cli_writes_model(tmp_path, capsys):
    out = tmp_path / "m.urdf"
    assert main(["scale", "--sex", "m", "--height-m", "1.80", "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    # the file is the model of those measures: same dimensions as the library's geometry, and the
    # CLI's default knee is the library's default
    from pipeline.model.conventions import DEFAULT_KNEE

    sk = Skeleton.from_urdf(out)
    geometry, _ = geometry_from_measures(Measures("m", 1.80))
    assert sk.knee == DEFAULT_KNEE
    sk.forward(sk.neutral())
    thigh = np.linalg.norm(sk.frame_position("right_HJC") - sk.frame_position("right_KJC"))
    shank = np.linalg.norm(sk.frame_position("right_KJC") - sk.frame_position("right_AJC"))
    assert thigh == pytest.approx(geometry.thigh_length, abs=1e-9)
    assert shank == pytest.approx(geometry.shank_length, abs=1e-9)
    assert 0.35 < thigh < 0.5 and 0.35 < shank < 0.5  # a 1.80 m adult


@pytest.mark.dataset
def test_shipped_population_aor_matches_the_dataset():
    if not DATA.exists():
        pytest.skip("../shared/data/wang2023 not present")
    from pipeline.reproduce.wang2023.optical import run_omc_stage

    stage = run_omc_stage(DATA, progress=False)
    for sex in ("m", "f", "all"):
        shipped, computed = population_knee_axis(sex), stage.population[sex]
        np.testing.assert_allclose(shipped.femur_axis, computed.femur_axis, atol=2e-6)
        np.testing.assert_allclose(shipped.tibia_axis, computed.tibia_axis, atol=2e-6)
    assert len(load_table1()) == 60


def test_scale_cli_hinge_about_a_given_knee_axis(tmp_path):
    from pipeline.model.skeleton import knee_axis

    out = tmp_path / "h.urdf"
    args = ["scale", "--sex", "m", "--height-m", "1.80", "--knee", "hinge", "--out", str(out)]
    args += ["--knee-axis-femur", "-0.1", "-0.1", "1", "--knee-axis-tibia", "0", "0.05", "1"]
    assert main(args) == 0
    a_F, a_T = knee_axis(pin.buildModelFromUrdf(str(out)), "right")
    np.testing.assert_allclose(a_F, np.array([-0.1, -0.1, 1]) / np.sqrt(1.02), atol=1e-9)
    np.testing.assert_allclose(a_T, np.array([0, 0.05, 1]) / np.sqrt(1.0025), atol=1e-9)


def test_a_measured_pelvis_width_places_the_hip_centres():
    """Bell et al. 1989: each hip centre 14 % of the inter-ASIS distance medial of its ASIS, so
    the two 0.72 of it apart; their other coordinates stay the template's; without the width the
    template's hips scaled with height (0.157 m apart at 1.72 m)."""
    measured, _ = geometry_from_measures(Measures("m", 1.72, pelvis_width_m=0.242))
    default, _ = geometry_from_measures(Measures("m", 1.72))
    assert measured.right_hip[2] - measured.left_hip[2] == pytest.approx(0.72 * 0.242)
    np.testing.assert_allclose(measured.right_hip[:2], default.right_hip[:2])
    np.testing.assert_allclose(measured.left_hip, measured.right_hip * [1, 1, -1])
    assert default.right_hip[2] - default.left_hip[2] == pytest.approx(0.157, abs=5e-4)
    with pytest.raises(InputError, match="looks like centimetres"):
        Measures("m", 1.72, pelvis_width_m=24.2)


@pytest.mark.parametrize("sex", ["m", "f"])
def test_every_accepted_height_scales_with_the_bodys_proportions(sex):
    """Heights 1.0-2.5 m (all accepted) give a model: beyond the regression's heights (Wang's
    subjects' and 0.1 m) the landmarks at the nearest bound scaled by the heights' ratio, so the
    segments keep that bound's proportions; within them the equations themselves (before, a
    1.2 m woman was refused for a thigh of 12 % of her height)."""
    from pipeline.model.scaling import REGRESSION_HEIGHTS_M

    low, high = REGRESSION_HEIGHTS_M[sex]
    share = {}
    for h in (1.0, 1.2, low, 1.7, high, 2.2, 2.5):
        g, _ = geometry_from_measures(Measures(sex, h))
        share[h] = (g.thigh_length / h, g.shank_length / h)
    for h, bound in ((1.0, low), (1.2, low), (2.2, high), (2.5, high)):
        np.testing.assert_allclose(share[h], share[bound], rtol=1e-12)
    from pipeline.model.anthropometry import predict_landmarks

    within = geometry_from_measures(Measures(sex, 1.7))[1].femur["EFM"]
    np.testing.assert_array_equal(within, predict_landmarks(Measures(sex, 1.7)).femur["EFM"])
    assert share[1.2][0] != pytest.approx(share[1.7][0])  # the proportions do vary within
