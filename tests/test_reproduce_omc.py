"""OMC processing: sphere fit, segment frames, landmarks, body dimensions, frame independence."""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.reproduce.wang2023.dataset import OmcTrial, load_subject, subject_paths
from pipeline.reproduce.wang2023.omc import (
    femoral_frames,
    fit_concentric_spheres,
    fit_sphere,
    landmarks_in_frames,
    process_subject,
    tibial_frames,
)
from pipeline.rotations import angle_between, exp3, normalize, rot_x, rot_y, rot_z

DEG = np.pi / 180
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "wang2023"


def _random_rotation(rng):
    return exp3(normalize(rng.normal(size=3)) * rng.uniform(0.3, 3.0))


# --------------------------------------------------------------------------------------------
# sphere fits


def _cap(rng, centre, radius, n, half_angle_deg):
    """Points on a spherical cap around -y (a thigh hanging from the hip, flexing)."""
    a = rng.uniform(-half_angle_deg, half_angle_deg, n) * DEG  # flexion
    b = rng.uniform(-8, 8, n) * DEG  # a little abduction
    d = np.stack([np.sin(a) * np.cos(b), -np.cos(a) * np.cos(b), np.sin(b)], axis=1)
    return centre + radius * d


def test_sphere_fit_exact_points():
    rng = np.random.default_rng(0)
    c = np.array([0.3, 0.9, -1.2])
    p = _cap(rng, c, 0.42, 500, 40)
    for steps in (0, 5):
        fit = fit_sphere(p, refine_steps=steps)
        np.testing.assert_allclose(fit.centre, c, atol=1e-9)
        assert fit.radius == pytest.approx(0.42, abs=1e-9)
        assert fit.rms < 1e-9
    assert fit_sphere(p).method == "algebraic"
    assert fit_sphere(p, refine_steps=3).method == "geometric"


def test_sphere_fit_noisy_partial_cap():
    rng = np.random.default_rng(1)
    c = np.array([-0.5, 1.1, 0.2])
    p = _cap(rng, c, 0.40, 4000, 45) + rng.normal(scale=0.002, size=(4000, 3))
    alg = fit_sphere(p)
    geo = fit_sphere(p, refine_steps=10)
    # 2 mm noise on a 90-deg cap: centre within a few mm, rms close to the noise
    assert np.linalg.norm(alg.centre - c) < 0.01
    assert np.linalg.norm(geo.centre - c) < 0.01
    assert abs(geo.radius - 0.40) < 0.01
    assert 0.0015 < geo.rms < 0.0040
    assert geo.rms <= alg.rms + 1e-12  # geometric refinement minimises this residual


def test_concentric_spheres_two_radii():
    rng = np.random.default_rng(2)
    c = np.array([0.1, 0.2, 0.3])
    p1 = c + 0.40 * normalize(rng.normal(size=(300, 3)))
    p2 = c + 0.37 * normalize(rng.normal(size=(300, 3)))
    fit = fit_concentric_spheres([p1, p2], refine_steps=3)
    np.testing.assert_allclose(fit.centre, c, atol=1e-9)
    np.testing.assert_allclose(fit.radii, [0.40, 0.37], atol=1e-9)


def test_sphere_fit_ignores_nan_and_refuses_too_few():
    rng = np.random.default_rng(3)
    c = np.zeros(3)
    p = _cap(rng, c, 0.4, 100, 40)
    p[::7] = np.nan
    np.testing.assert_allclose(fit_sphere(p).centre, c, atol=1e-9)
    with pytest.raises(InputError, match="too few"):
        fit_sphere(p[:3])


# --------------------------------------------------------------------------------------------
# frames by hand


def test_femoral_frame_by_hand():
    hjc = np.array([1.0, 2.0, 3.0])
    efm = hjc + np.array([[0.0, -0.4, -0.05]])
    efl = hjc + np.array([[0.0, -0.4, 0.05]])
    R, o = femoral_frames(hjc, efm, efl)
    np.testing.assert_allclose(R[0], np.eye(3), atol=1e-12)
    np.testing.assert_allclose(o[0], hjc)
    # rotated leg: the frame rotates with it
    Q = rot_z(0.7) @ rot_x(-0.2)
    R2, _ = femoral_frames(hjc, hjc + (efm - hjc) @ Q.T, hjc + (efl - hjc) @ Q.T)
    np.testing.assert_allclose(R2[0], Q, atol=1e-12)


def test_tibial_frame_by_hand():
    efm, efl = np.array([[0, 0, -0.05]]), np.array([[0, 0, 0.05]])
    mm, lm = np.array([[0.01, -0.38, -0.03]]), np.array([[-0.01, -0.38, 0.03]])
    axis = normalize(np.array([[0.1, 0.2, 1.0]]))  # projected perpendicular to y
    R, o = tibial_frames(efm, efl, mm, lm, axis)
    np.testing.assert_allclose(R[0][:, 1], [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(R[0][:, 2], normalize(np.array([0.1, 0, 1.0])), atol=1e-12)
    np.testing.assert_allclose(R[0].T @ R[0], np.eye(3), atol=1e-12)
    assert np.linalg.det(R[0]) == pytest.approx(1.0)
    np.testing.assert_allclose(o[0], 0.0, atol=1e-12)
    loc = landmarks_in_frames(np.repeat(mm, 3, 0), np.repeat(R, 3, 0), np.repeat(o, 3, 0))
    np.testing.assert_allclose(R[0] @ loc, mm[0], atol=1e-12)


# --------------------------------------------------------------------------------------------
# synthetic subject with known geometry


def _synthetic_subject(rng, n=3000):
    """Supine hip flexion of a right leg with a knee hinge; all true values returned."""
    t = np.arange(n) / 100.0
    cyc = 0.5 * (1 - np.cos(2 * np.pi * t / 6.0))
    hip, knee = 70 * DEG * cyc**1.2, 90 * DEG * cyc
    abd = 2 * DEG * np.sin(2 * np.pi * t / 9.0)
    lab = _random_rotation(rng)
    hjc = np.array([0.4, -0.2, 1.1])
    F = lab @ rot_z(hip) @ rot_x(abd)  # femoral anatomical frames
    p_efm, p_efl = np.array([0.0, -0.41, -0.047]), np.array([0.0, -0.41, 0.047])
    kjc_f = 0.5 * (p_efm + p_efl)
    a_F = normalize(np.array([-0.12, 0.05, 1.0]))
    # tibia at zero knee flexion, in femoral coordinates relative to the KJC
    m_mm, m_lm = np.array([0.012, -0.385, -0.030]), np.array([-0.012, -0.395, 0.031])
    E = exp3(-knee[:, None] * a_F)  # knee flexion: rotation about the left-pointing axis
    mm = hjc + np.einsum("nij,j->ni", F, kjc_f) + np.einsum("nij,j->ni", F @ E, m_mm)
    lm = hjc + np.einsum("nij,j->ni", F, kjc_f) + np.einsum("nij,j->ni", F @ E, m_lm)
    efm = hjc + F @ p_efm
    efl = hjc + F @ p_efl
    # true tibial frame at zero flexion (femoral coordinates) and the truths in it
    y0 = normalize(-(m_mm + m_lm) / 2)
    z0 = normalize(a_F - (a_F @ y0) * y0)
    T0 = np.stack([np.cross(y0, z0), y0, z0], axis=1)
    cl_t = T0 @ rot_y(0.4) @ rot_x(0.3)  # tibia cluster, a constant offset from the frame
    cl_f = rot_z(-0.5)
    trial = OmcTrial(
        subject_id=99,
        sex="f",
        height_m=1.65,
        rate_hz=100.0,
        time=t,
        landmarks={"EFM": efm, "EFL": efl, "MM": mm, "LM": lm},
        femur_cluster_R=F @ cl_f,
        femur_cluster_pos=hjc + F @ np.array([0.05, -0.2, 0.05]),
        tibia_cluster_R=F @ E @ cl_t,
        tibia_cluster_pos=hjc + F @ kjc_f + np.einsum("nij,j->ni", F @ E, [0.05, -0.15, 0.0]),
        clusters_swapped=False,
        notes=(),
        source=None,
    )
    truth = {
        "hjc": hjc,
        "F": F,
        "a_F": a_F,
        "a_T": T0.T @ a_F,
        "EFM": p_efm,
        "EFL": p_efl,
        "MM": T0.T @ m_mm,
        "LM": T0.T @ m_lm,
        "s_L": np.linalg.norm(p_efl - (kjc_f + m_lm)),
        "s_M": np.linalg.norm(p_efm - (kjc_f + m_mm)),
        "k": 0.094,
        "a": np.linalg.norm(m_mm - m_lm),
    }
    return trial, truth


def test_process_synthetic_subject_recovers_truth():
    trial, tr = _synthetic_subject(np.random.default_rng(4))
    r = process_subject(trial)
    np.testing.assert_allclose(r.hjc, tr["hjc"], atol=1e-9)
    assert r.hip_fit_rms_m < 1e-9
    np.testing.assert_allclose(r.femur_R, tr["F"], atol=1e-9)
    assert angle_between(r.knee_aor.femur_axis, tr["a_F"]) < 1e-9
    assert angle_between(r.knee_aor.tibia_axis, tr["a_T"]) < 1e-9
    for name in ("EFM", "EFL"):
        np.testing.assert_allclose(r.landmarks_femur[name], tr[name], atol=1e-9)
    for name in ("MM", "LM"):
        np.testing.assert_allclose(r.landmarks_tibia[name], tr[name], atol=1e-9)
    d = r.dims
    assert d.h == 1.65
    assert d.k == pytest.approx(tr["k"], abs=1e-9) and d.a == pytest.approx(tr["a"], abs=1e-9)
    # straight-knee shank lengths: the most extended frames are within a fraction of a degree
    assert d.s_L == pytest.approx(tr["s_L"], abs=2e-4)
    assert d.s_M == pytest.approx(tr["s_M"], abs=2e-4)
    assert r.valid.all() and r.n_frames == 3000


def test_missing_samples_are_excluded():
    trial, tr = _synthetic_subject(np.random.default_rng(5))
    lm = dict(trial.landmarks)
    efm = lm["EFM"].copy()
    efm[400:600] = np.nan
    lm["EFM"] = efm
    tib = trial.tibia_cluster_R.copy()
    tib[1500:1550] = np.nan
    mm = lm["MM"].copy()
    mm[1500:1550] = np.nan
    lm["MM"] = mm
    r = process_subject(replace(trial, landmarks=lm, tibia_cluster_R=tib))
    assert not r.valid[400:600].any() and not r.valid[1500:1550].any()
    assert r.valid.sum() == 3000 - 250
    assert np.isnan(r.femur_R[450]).all() and np.isnan(r.tibia_origin[1520]).all()
    np.testing.assert_allclose(r.hjc, tr["hjc"], atol=1e-9)
    assert angle_between(r.knee_aor.femur_axis, tr["a_F"]) < 1e-9
    np.testing.assert_allclose(r.landmarks_tibia["LM"], tr["LM"], atol=1e-9)


def _rigid(trial: OmcTrial, Q: np.ndarray, t: np.ndarray) -> OmcTrial:
    move = lambda p: p @ Q.T + t  # noqa: E731
    return replace(
        trial,
        landmarks={k: move(v) for k, v in trial.landmarks.items()},
        femur_cluster_R=Q @ trial.femur_cluster_R,
        tibia_cluster_R=Q @ trial.tibia_cluster_R,
        femur_cluster_pos=move(trial.femur_cluster_pos),
        tibia_cluster_pos=move(trial.tibia_cluster_pos),
    )


def _assert_same_in_segment_frames(a, b, Q, t, atol):
    np.testing.assert_allclose(b.hjc, Q @ a.hjc + t, atol=atol)
    assert b.hip_fit_rms_m == pytest.approx(a.hip_fit_rms_m, abs=atol)
    np.testing.assert_array_equal(a.valid, b.valid)
    ok = a.valid
    np.testing.assert_allclose(b.femur_R[ok], Q @ a.femur_R[ok], atol=atol)
    np.testing.assert_allclose(b.tibia_R[ok], Q @ a.tibia_R[ok], atol=atol)
    assert np.array_equal(a.knee_aor.pairs, b.knee_aor.pairs)
    np.testing.assert_allclose(b.knee_aor.femur_axis, a.knee_aor.femur_axis, atol=atol)
    np.testing.assert_allclose(b.knee_aor.tibia_axis, a.knee_aor.tibia_axis, atol=atol)
    assert b.knee_aor.sd_angle_femur == pytest.approx(a.knee_aor.sd_angle_femur, abs=atol)
    for side in ("landmarks_femur", "landmarks_tibia"):
        for k, v in getattr(a, side).items():
            np.testing.assert_allclose(getattr(b, side)[k], v, atol=atol)
    for f in ("h", "s_L", "s_M", "k", "a"):
        assert getattr(b.dims, f) == pytest.approx(getattr(a.dims, f), abs=atol)


def test_outputs_do_not_depend_on_lab_axes_synthetic():
    rng = np.random.default_rng(6)
    trial, _ = _synthetic_subject(rng)
    Q, t = _random_rotation(rng), rng.normal(size=3)
    a, b = process_subject(trial), process_subject(_rigid(trial, Q, t))
    _assert_same_in_segment_frames(a, b, Q, t, atol=1e-8)


# --------------------------------------------------------------------------------------------
# real data


@pytest.fixture(scope="module")
def real_results():
    if not DATA.is_dir():
        pytest.skip(f"dataset not found at {DATA}")
    t0 = time.perf_counter()
    out = {}
    for p in subject_paths(DATA):
        omc = load_subject(p).omc
        out[omc.subject_id] = (omc, process_subject(omc))
    return out, time.perf_counter() - t0


@pytest.mark.dataset
def test_real_data_all_subjects(real_results):
    res, elapsed = real_results
    assert len(res) == 38
    for sid, (_omc, r) in res.items():
        assert r.hip_fit_rms_m < 0.008, sid  # 1-6 mm measured
        assert 0.30 < r.hip_fit.radius < 0.50, sid
        assert r.knee_aor.femur_axis[2] > 0.85, sid  # 0.88-1.00 measured
        assert r.knee_aor.tibia_axis[2] > 0.95, sid
        assert r.knee_aor.n_pairs > 50 and r.knee_aor.sd_angle_femur < 10 * DEG, sid
        d = r.dims
        assert 0.07 < d.k < 0.13 and 0.045 < d.a < 0.09, sid
        assert 0.30 < d.s_L < 0.50 and 0.30 < d.s_M < 0.50, sid
        # EFM medial (-z), EFL lateral (+z); malleoli likewise; both below their origin
        assert r.landmarks_femur["EFM"][2] < 0 < r.landmarks_femur["EFL"][2], sid
        assert r.landmarks_tibia["MM"][2] < 0 < r.landmarks_tibia["LM"][2], sid
        assert r.landmarks_tibia["MM"][1] < -0.25 and r.landmarks_femur["EFM"][1] < -0.3, sid


@pytest.mark.dataset
def test_real_data_other_lab_axes_in_same_range(real_results):
    res, _ = real_results
    odd = {17, 18, 19, 28, 29, 30}

    def features(r):
        return np.concatenate(
            [
                r.knee_aor.femur_axis,
                r.knee_aor.tibia_axis,
                r.landmarks_femur["EFM"],
                r.landmarks_tibia["MM"],
                r.landmarks_tibia["LM"],
            ]
        )

    others = np.stack([features(r) for sid, (_, r) in res.items() if sid not in odd])
    mu, sd = others.mean(axis=0), others.std(axis=0, ddof=1)
    for sid in odd:
        z = (features(res[sid][1]) - mu) / np.maximum(sd, 1e-6)
        assert np.all(np.abs(z) < 3.0), (sid, np.round(z, 2))


@pytest.mark.dataset
def test_real_subject_frame_independent(real_results):
    res, _ = real_results
    rng = np.random.default_rng(7)
    for sid in (2, 28):  # 2 has missing tibia samples; 28 other lab axes
        omc, r = res[sid]
        Q, t = _random_rotation(rng), rng.normal(size=3)
        _assert_same_in_segment_frames(r, process_subject(_rigid(omc, Q, t)), Q, t, atol=1e-7)
