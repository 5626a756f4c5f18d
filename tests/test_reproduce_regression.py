"""pipeline.reproduce.wang2023.regression: OLS, R², F-test and K-fold fitting of the Table I
equations (Wang §III.A), on synthetic subjects with known coefficients and, if present, on the
published data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from pipeline.errors import InputError
from pipeline.model.anthropometry import CSV_COLUMNS, GROUPS, load_table1, predict_landmarks
from pipeline.model.measures import Measures
from pipeline.reproduce.wang2023.regression import (
    SubjectSample,
    fit_results_to_rows,
    fit_table,
    kfold_indices,
    table_from_fits,
    write_fit_csv,
)

MIRRORS = [  # (equation, landmark a, landmark b, axis): a = -b by construction of the frames
    *[(eq, "EFM", "EFL", "z") for eq in ("h", "k")],
    *[(eq, "MM", "LM", ax) for eq in ("h", "h+a") for ax in ("x", "z")],
]

# ------------------------------------------------------------------------------------- fitting

TRUE = {  # (landmark, axis) -> equation and true coefficients (mm, mm/mm) used to generate data
    ("EFM", "y"): ("h", (150.0, -0.33, 0.0)),
    ("EFL", "y"): ("h", (140.0, -0.32, 0.0)),
    ("MM", "y"): ("h+sM", (5.0, -0.01, -0.97)),
    ("LM", "y"): ("h+sL", (-2.0, 0.005, -1.0)),
    ("MM", "x"): ("h+a", (20.0, 0.0, -0.1)),
    ("MM", "z"): ("h+a", (-5.0, 0.004, -0.45)),
}
NOISE_MM = 2.0


def make_samples(n: int, seed: int, noise_mm: float = NOISE_MM) -> list[SubjectSample]:
    rng = np.random.default_rng(seed)
    out = []
    for i in range(n):
        sex = "m" if i % 2 == 0 else "f"
        d = {
            "h": rng.uniform(1500, 1900),
            "s_L": rng.uniform(340, 460),
            "s_M": rng.uniform(330, 450),
            "k": rng.uniform(85, 115),
            "a": rng.uniform(55, 80),
        }
        val = {}
        for (lm, ax), (eq, b) in TRUE.items():
            second = {"h": 0.0, "h+sM": d["s_M"], "h+sL": d["s_L"], "h+a": d["a"]}[eq]
            val[(lm, ax)] = b[0] + b[1] * d["h"] + b[2] * second + rng.normal(0, noise_mm)
        efm = np.array([0.0, val[("EFM", "y")], -d["k"] / 2])  # exact: z = -k/2
        efl = np.array([0.0, val[("EFL", "y")], d["k"] / 2])
        mm = np.array([val[("MM", "x")], val[("MM", "y")], val[("MM", "z")]])
        lm = np.array([-mm[0], val[("LM", "y")], -mm[2]])  # ankle centre on the tibial y axis
        dims_m = [d[k] / 1e3 for k in ("h", "s_L", "s_M", "k", "a")]
        out.append(SubjectSample(i, sex, *dims_m, efm / 1e3, efl / 1e3, mm / 1e3, lm / 1e3))
    return out


def by_key(results):
    return {(r.sex, r.equation, r.landmark, r.axis): r for r in results}


SAMPLES = make_samples(240, seed=1)


@pytest.fixture(scope="module")
def fits():
    return by_key(fit_table(SAMPLES, k_folds=5, seed=0))


def design_mm(samples, equation):
    cols = {"h": "height_m", "h+sL": "shank_lateral_m", "h+sM": "shank_medial_m"}
    cols["h+a"] = "ankle_width_m"
    x = [np.ones(len(samples)), [s.height_m * 1e3 for s in samples]]
    if equation != "h":
        x.append([getattr(s, cols[equation]) * 1e3 for s in samples])
    return np.column_stack(x)


def test_fit_recovers_known_coefficients(fits):
    for group in GROUPS:
        members = [s for s in SAMPLES if group == "all" or s.sex == group]
        n = len(members)
        for (lm, ax), (eq, b) in TRUE.items():
            r = fits[(group, eq, lm, ax)]
            assert r.n == n and r.k_folds == 5
            # within 4 standard errors of the truth: SE = noise * sqrt(diag((X'X)^-1))
            x = design_mm(members, eq)
            se = NOISE_MM * np.sqrt(np.diag(np.linalg.inv(x.T @ x)))
            err = np.abs(np.array([r.b0, r.b1, r.b2])[: len(se)] - np.array(b)[: len(se)])
            assert np.all(err < 4 * se), (group, eq, lm, ax, err / se)
            assert abs(r.cv_sd_mm - NOISE_MM) < 0.2 * NOISE_MM  # held-out error SD = noise SD
            assert abs(r.cv_mean_mm) < 4 * NOISE_MM / np.sqrt(n)
            if (lm, ax) != ("MM", "x"):  # every other true relation is strong (MM z: R2 ~ 0.7,
                assert r.r2 > 0.6 and r.p < 1e-12  # 0.45 a has SD 3.2 mm against 2 mm noise)
        # MM x depends only weakly on a (0.1 mm/mm): its h-only fit explains almost nothing
        assert fits[(group, "h", "MM", "x")].r2 < 0.05
        # knee width: EFM z = -k/2 exactly -> R2 = 1, zero test error
        r = fits[(group, "k", "EFM", "z")]
        assert r.r2 == pytest.approx(1.0) and r.p == 0.0 and r.cv_sd_mm < 1e-9
        assert (r.b0, r.b1, r.b2) == pytest.approx((0.0, -0.5, 0.0), abs=1e-9)


def test_fit_r2_and_p_match_scipy_linregress(fits):
    samples = [s for s in SAMPLES if s.sex == "f"]
    h = np.array([s.height_m for s in samples]) * 1e3
    y = np.array([s.efm[1] for s in samples]) * 1e3
    ref = stats.linregress(h, y)
    r = fits[("f", "h", "EFM", "y")]
    assert r.r2 == pytest.approx(ref.rvalue**2, rel=1e-10)
    assert r.p == pytest.approx(ref.pvalue, rel=1e-6)
    assert r.coef_full_mm[:2] == pytest.approx((ref.intercept, ref.slope), rel=1e-10)
    assert np.mean(r.coef_folds_mm, axis=0) == pytest.approx((r.b0, r.b1, r.b2))


def test_fit_mirrored_targets_give_mirrored_results(fits):
    for group in GROUPS:
        for eq, a, b, ax in MIRRORS:
            ra, rb = fits[(group, eq, a, ax)], fits[(group, eq, b, ax)]
            assert (ra.b0, ra.b1, ra.b2) == pytest.approx((-rb.b0, -rb.b1, -rb.b2), abs=1e-9)
            assert ra.cv_sd_mm == pytest.approx(rb.cv_sd_mm, abs=1e-9)
            assert ra.cv_mean_mm == pytest.approx(-rb.cv_mean_mm, abs=1e-9)


def test_leave_one_out_equals_press_residuals():
    # with K = n, the held-out OLS error of sample i is e_i / (1 - H_ii) (PRESS identity)
    samples = make_samples(12, seed=3)
    (r,) = [
        r
        for r in fit_table(samples, k_folds=12, seed=5, groups=("all",))
        if (r.equation, r.landmark, r.axis) == ("h+sM", "MM", "y")
    ]
    x = np.column_stack([np.ones(12), [s.height_m * 1e3 for s in samples]])
    x = np.column_stack([x, [s.shank_medial_m * 1e3 for s in samples]])
    y = np.array([s.mm[1] * 1e3 for s in samples])
    hat = x @ np.linalg.solve(x.T @ x, x.T)
    press = (y - hat @ y) / (1 - np.diag(hat))
    assert r.cv_mean_mm == pytest.approx(press.mean(), abs=1e-9)
    assert r.cv_sd_mm == pytest.approx(press.std(ddof=1), rel=1e-9)


def test_kfold_is_a_deterministic_partition():
    folds = kfold_indices(11, 5, seed=7)
    assert sorted(np.concatenate(folds).tolist()) == list(range(11))
    assert sorted(len(f) for f in folds) == [2, 2, 2, 2, 3]
    again = kfold_indices(11, 5, seed=7)
    assert all(np.array_equal(a, b) for a, b in zip(folds, again, strict=True))
    samples = make_samples(30, seed=2)
    a, b = fit_table(samples, seed=4), fit_table(samples, seed=4)
    c = fit_table(samples, seed=5)
    assert fit_results_to_rows(a) == fit_results_to_rows(b)
    ka, kc = by_key(a), by_key(c)
    key = ("m", "h", "MM", "y")
    assert ka[key].cv_sd_mm != kc[key].cv_sd_mm  # other folds, other test errors
    assert ka[key].r2 == kc[key].r2 and ka[key].p == kc[key].p  # full-sample stats do not depend


def test_too_few_samples_and_bad_samples_raise():
    samples = make_samples(30, seed=2)
    few_f = [s for s in samples if s.sex == "m"] + [s for s in samples if s.sex == "f"][:3]
    with pytest.raises(InputError, match="group 'f' has 3 subjects.*at least 5"):
        fit_table(few_f, k_folds=5)
    assert len(fit_table(few_f, k_folds=5, groups=("m", "all"))) == 40
    with pytest.raises(InputError, match="k_folds"):
        fit_table(samples, k_folds=1)
    with pytest.raises(InputError, match="unique"):
        fit_table(samples + samples[:1])
    s = samples[0]
    with pytest.raises(InputError, match="subject 0: expected metres") as info:
        SubjectSample(0, "m", 1.7, 0.4, 0.4, 0.1, 0.07, s.efm * 1e3, s.efl, s.mm, s.lm)
    assert info.value.field == "efm"
    with pytest.raises(InputError, match="subject 9: 170 looks like centimetres"):
        SubjectSample(9, "m", 170, 0.4, 0.4, 0.1, 0.07, s.efm, s.efl, s.mm, s.lm)


def test_rows_csv_round_trip_and_prediction_from_fits(tmp_path, fits):
    results = list(fits.values())
    rows = fit_results_to_rows(results)
    assert len(rows) == 60 and all(tuple(r) == CSV_COLUMNS for r in rows)
    table = load_table1(write_fit_csv(results, tmp_path / "fit.csv"))
    assert len(table) == 60
    e = table.get("m", "h+sM", "MM", "y")
    assert e.b2 == pytest.approx(fits[("m", "h+sM", "MM", "y")].b2, rel=1e-5)
    # predicting with the fitted table reproduces the generating model at a new subject
    lp = predict_landmarks(Measures("m", 1.70, shank_medial_m=0.40), table_from_fits(results))
    truth = 5.0 - 0.01 * 1700 - 0.97 * 400  # mm, TRUE[("MM", "y")]
    assert lp.tibia["MM"][1] * 1e3 == pytest.approx(truth, abs=3.0)


# ------------------------------------------------------------------------------ published data

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "wang2023" / "raw"


@pytest.fixture(scope="module")
def table():
    return load_table1()


@pytest.fixture(scope="module")
def dataset_samples():
    if not DATA.is_dir():
        pytest.skip(f"published Wang 2023 dataset not found at {DATA}")
    from pipeline.reproduce.wang2023.dataset import load_subject, subject_paths
    from pipeline.reproduce.wang2023.omc import process_subject

    out = []
    for path in subject_paths(DATA):
        r = process_subject(load_subject(path).omc)
        d, f, t = r.dims, r.landmarks_femur, r.landmarks_tibia
        out.append(
            SubjectSample(
                r.subject_id,
                r.sex,
                d.h,
                d.s_L,
                d.s_M,
                d.k,
                d.a,
                f["EFM"],
                f["EFL"],
                t["MM"],
                t["LM"],
            )
        )
    return out


@pytest.mark.dataset
def test_reconstructed_rows_agree_with_a_refit_of_the_published_data(dataset_samples, table):
    assert len(dataset_samples) == 38
    fits = by_key(fit_table(dataset_samples, k_folds=5, seed=0))
    for e in table:
        if e.equation != "h+a":
            continue
        members = [s for s in dataset_samples if e.sex == "all" or s.sex == e.sex]
        inputs = [s.measures().inputs_mm() for s in members]
        fit = fits[(e.sex, e.equation, e.landmark, e.axis)].to_equation()
        table_pred = np.array([e.evaluate_mm(d) for d in inputs])
        rms = np.sqrt(np.mean((table_pred - [fit.evaluate_mm(d) for d in inputs]) ** 2))
        assert rms < 3.0, (e, rms)  # measured 0.7-1.8 mm: same quantity, (nearly) same data
        # the labels as printed ("ML X" for MM z, "MM Z" for LM x) would be 18-19 mm off
        printed = {("MM", "z"): ("LM", "x"), ("LM", "x"): ("MM", "z")}.get((e.landmark, e.axis))
        if printed:
            other = fits[(e.sex, e.equation, *printed)].to_equation()
            rms = np.sqrt(np.mean((table_pred - [other.evaluate_mm(d) for d in inputs]) ** 2))
            assert rms > 12.0, (e, rms)
