"""pipeline.model.anthropometry: Table I transcription, eq 14 prediction, input validation.

Fitting (OLS, K-fold) is tested in test_regression.py."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.model.anthropometry import (
    CSV_COLUMNS,
    EQUATION_TARGETS,
    GROUPS,
    load_table1,
    predict_landmarks,
)
from pipeline.model.measures import Measures

MIRRORS = [  # (equation, landmark a, landmark b, axis): a = -b by construction of the frames
    *[(eq, "EFM", "EFL", "z") for eq in ("h", "k")],
    *[(eq, "MM", "LM", ax) for eq in ("h", "h+a") for ax in ("x", "z")],
]


# ----------------------------------------------------------------------------- the shipped table


@pytest.fixture(scope="module")
def table():
    return load_table1()


def test_table_has_every_row_with_finite_numbers(table):
    targets = [(eq, lm, ax) for eq, tg in EQUATION_TARGETS.items() for lm, ax in tg]
    expected = {(g, *t) for g in GROUPS for t in targets}
    got = [(e.sex, e.equation, e.landmark, e.axis) for e in table]
    assert len(got) == len(expected) == 60 and set(got) == expected
    for e in table:
        values = [e.b0, e.b1, e.b2, e.r2, e.p, e.cv_mean_mm, e.cv_sd_mm]
        assert np.all(np.isfinite(values)) and 0 <= e.r2 <= 1 and 0 <= e.p <= 1 and e.cv_sd_mm >= 0
        if len(e.inputs) == 1:
            assert e.b2 == 0.0
    # the 7 rows documented in models/wang2023_table1.md, and nothing else
    recon = {(e.sex, e.equation, e.landmark, e.axis) for e in table if e.source == "reconstructed"}
    assert recon == {("m", "h+a", "MM", "z"), ("m", "h+a", "LM", "x"), ("f", "h+a", "MM", "z")} | {
        ("f", "h+a", "LM", "x"),
        ("all", "h+a", "MM", "z"),
        ("all", "h+a", "LM", "x"),
        ("all", "h+a", "LM", "z"),
    }
    assert {e.source for e in table} == {"table", "reconstructed"}


@pytest.mark.parametrize("group", GROUPS)
def test_table_mirrored_pairs_are_consistent(table, group):
    for eq, a, b, ax in MIRRORS:
        ea, eb = table.get(group, eq, a, ax), table.get(group, eq, b, ax)
        assert (ea.b0, ea.b1, ea.b2) == (-eb.b0, -eb.b1, -eb.b2), (group, eq, ax)
        assert (ea.r2, ea.p, ea.cv_sd_mm) == (eb.r2, eb.p, eb.cv_sd_mm)
        assert ea.cv_mean_mm == -eb.cv_mean_mm


def test_table_spot_values_as_printed(table):
    # copied by eye from Table I of the paper
    e = table.get("m", "h", "EFM", "y")
    printed = (-11.949, -0.232, 0.24, 0.042, 0, 23.3)
    assert (e.b0, e.b1, e.r2, e.p, e.cv_mean_mm, e.cv_sd_mm) == printed
    e = table.get("f", "h+sL", "LM", "y")
    assert (e.b0, e.b1, e.b2, e.r2, e.cv_sd_mm) == (-35.334, 0.024, -1.007, 0.995, 1.9)
    e = table.get("all", "h+sM", "MM", "y")
    assert (e.b0, e.b1, e.b2, e.r2, e.cv_sd_mm) == (1.254, -0.005, -0.977, 0.996, 2.0)
    # the row whose b2 and R2 were garbled ("-0/2/ 0/1/") in the extracted text
    e = table.get("all", "h+a", "LM", "x")
    assert (e.b0, e.b1, e.b2, e.r2, e.p) == (29.259, -0.014, -0.257, 0.217, 0.029)


def test_bad_table_files_raise_input_error(tmp_path):
    bad = tmp_path / "t.csv"
    bad.write_text("sex,equation,landmark,axis,b0\nm,h,EFM,y,1\n")
    with pytest.raises(InputError, match="missing"):
        load_table1(bad)
    header = ",".join(CSV_COLUMNS)
    bad.write_text(f"# comment\n{header}\nm,h,EFM,y,abc,0,0,0,0,0,1\n")
    with pytest.raises(InputError, match="data row 1"):
        load_table1(bad)
    bad.write_text(f"{header}\nm,k,MM,y,1,0,0,0,0,0,1\n")  # no k equation for MM y in Table I
    with pytest.raises(InputError, match="no MM y"):
        load_table1(bad)


# ------------------------------------------------------------------------------------ prediction


def test_prediction_by_hand_male_174(table):
    lp = predict_landmarks(Measures("m", 1.74), table)
    # Table I, male, p = b0 + b1 h with h = 1740 mm:
    # EFM y = -11.949 - 0.232*1740 = -11.949 - 403.680 = -415.629 mm
    # EFM z = -51.859 + 0.001*1740 = -50.119 mm;  EFL z = +50.119 mm
    # EFL y =  -3.102 - 0.238*1740 =  -3.102 - 414.120 = -417.222 mm
    # MM  x = -65.268 + 0.045*1740 = -65.268 +  78.300 =   13.032 mm;  LM x = -13.032 mm
    # MM  y = 156.409 - 0.312*1740 = 156.409 - 542.880 = -386.471 mm
    # LM  y = 125.652 - 0.300*1740 = 125.652 - 522.000 = -396.348 mm
    # MM  z = -37.062 + 0.004*1740 = -37.062 +   6.960 =  -30.102 mm;  LM z = +30.102 mm
    by_hand_mm = {
        "EFM": [0, -415.629, -50.119],
        "EFL": [0, -417.222, 50.119],
        "MM": [13.032, -386.471, -30.102],
        "LM": [-13.032, -396.348, 30.102],
    }
    for name, p in {**lp.femur, **lp.tibia}.items():
        np.testing.assert_allclose(p, np.array(by_hand_mm[name]) * 1e-3, atol=1e-12, err_msg=name)
    assert lp.equations[("EFM", "x")] is None
    assert lp.equations[("EFM", "y")] is table.get("m", "h", "EFM", "y")
    # knee centre on the femoral y axis, ankle centre on the tibial y axis
    np.testing.assert_allclose(lp.knee_centre, [0, -0.4164255, 0], atol=1e-12)
    np.testing.assert_allclose(lp.ankle_centre, [0, -0.3914095, 0], atol=1e-12)
    # knee width = |EFM - EFL| = sqrt(1.593^2 + 100.238^2) = sqrt(10050.194) = 100.2507 mm
    assert lp.knee_width == pytest.approx(0.1002507, abs=1e-7)
    left = lp.for_left_leg()
    assert left.tibia["MM"][2] == pytest.approx(0.030102)
    assert left.tibia["MM"][0] == lp.tibia["MM"][0]


def test_prediction_uses_other_inputs_by_hand(table):
    lp = predict_landmarks(Measures("f", 1.62, knee_width_m=0.095, shank_medial_m=0.37), table)
    # female k equation: EFM z = -0.152 - 0.498*95 = -0.152 - 47.310 = -47.462 mm
    assert lp.femur["EFM"][2] == pytest.approx(-0.047462, abs=1e-12)
    # female h+sM: MM y = 35.417 - 0.026*1620 - 0.980*370 = 35.417 - 42.12 - 362.6 = -369.303 mm
    assert lp.tibia["MM"][1] == pytest.approx(-0.369303, abs=1e-12)
    # sex_specific=False -> 'all' rows: EFM y = 152.541 - 0.327*1620 = 152.541 - 529.74 = -377.199
    lp_all = predict_landmarks(Measures("f", 1.62), table, sex_specific=False)
    assert lp_all.femur["EFM"][1] == pytest.approx(-0.377199, abs=1e-12)
    assert lp_all.equations[("EFM", "y")].sex == "all"


def test_smallest_sd_selection(table):
    used = predict_landmarks(Measures("m", 1.74, shank_medial_m=0.40), table).equations
    assert used[("MM", "y")].equation == "h+sM"  # SD 1.8 < 15.0 (h)
    assert used[("LM", "y")].equation == "h+sM"  # SD 8.7 < 17.3 (h); no s_L given
    both = Measures("m", 1.74, shank_lateral_m=0.41, shank_medial_m=0.40)
    used = predict_landmarks(both, table).equations
    assert used[("MM", "y")].equation == "h+sM" and used[("LM", "y")].equation == "h+sL"  # 1.8, 2.1
    used = predict_landmarks(Measures("m", 1.74, shank_lateral_m=0.41), table).equations
    assert used[("MM", "y")].equation == "h+sL"  # 7.9 < 15.0
    # male MM x: h+a and h tie at 7.1 mm -> the simpler h; MM z: h+a 3.8 < h 4.4
    used = predict_landmarks(Measures("m", 1.74, ankle_width_m=0.07), table).equations
    assert used[("MM", "x")].equation == "h" and used[("MM", "z")].equation == "h+a"


def test_joint_centres_stay_on_segment_axes_for_every_input_set(table):
    optional = {"shank_lateral_m": 0.41, "shank_medial_m": 0.40, "knee_width_m": 0.1}
    optional["ankle_width_m"] = 0.068
    for sex, specific in itertools.product("mf", (True, False)):
        for r in range(len(optional) + 1):
            for keys in itertools.combinations(optional, r):
                m = Measures(sex, 1.70, **{k: optional[k] for k in keys})
                lp = predict_landmarks(m, table, sex_specific=specific)
                np.testing.assert_allclose(lp.knee_centre[[0, 2]], 0, atol=1e-12)
                np.testing.assert_allclose(lp.ankle_centre[[0, 2]], 0, atol=1e-12)
                assert 0.3 < lp.thigh_length < 0.5 and 0.3 < lp.shank_length < 0.5


# ---------------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    ("kwargs", "field", "pattern"),
    [
        ({"height_m": 162}, "height_m", r"looks like centimetres; give metres, e\.g\. 1\.62"),
        ({"height_m": 1745}, "height_m", r"looks like millimetres; give metres, e\.g\. 1\.745"),
        ({"height_m": 0.9}, "height_m", r"expected metres in \[1, 2\.5\]"),
        ({"height_m": float("nan")}, "height_m", "positive length"),
        ({"height_m": "1.7"}, "height_m", "expected a length"),
        ({"knee_width_m": 10}, "knee_width_m", r"centimetres; give metres, e\.g\. 0\.1"),
        ({"knee_width_m": 95}, "knee_width_m", r"millimetres; give metres, e\.g\. 0\.095"),
        ({"ankle_width_m": 0.0}, "ankle_width_m", "positive"),
        ({"shank_lateral_m": -0.4}, "shank_lateral_m", "positive"),
        ({"shank_medial_m": 40}, "shank_medial_m", "centimetres"),
        ({"shank_medial_m": 2.0}, "shank_medial_m", "expected metres"),
        ({"sex": "x"}, "sex", "'m' or 'f'"),
    ],
)
def test_implausible_measures_raise_with_hints(kwargs, field, pattern):
    args = {"sex": "m", "height_m": 1.74, **kwargs}
    with pytest.raises(InputError, match=pattern) as info:
        Measures(**args)
    assert info.value.field == field


def test_measures_normalise_sex_and_report_inputs_in_mm():
    m = Measures("Female", 1.6, knee_width_m=0.09)
    assert m.sex == "f" and m.inputs_mm() == pytest.approx({"h": 1600.0, "k": 90.0})
