"""Wang 2023 reader: synthetic fields with known truth, error messages, the real data."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.io

from pipeline.errors import InputError
from pipeline.reproduce.wang2023.dataset import (
    IMC_OMC_INDEX_OFFSET,
    TIBIA_HAND_CORRECTION_DEG,
    hand_correction,
    imc_from_fields,
    load_subject,
    omc_from_fields,
    subject_paths,
)
from pipeline.rotations import euler_zyx_from_matrix, exp3, matrix_from_euler_zyx, normalize

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "wang2023"
DEG = np.pi / 180


def _fields(rng, n=200, swap=False):
    """omcData-like fields (mm, rad): landmarks rigid in their clusters."""
    rv_f = normalize(rng.normal(size=3)) * np.linspace(0.2, 1.2, n)[:, None]
    rv_t = normalize(rng.normal(size=3)) * np.linspace(0.5, 1.9, n)[:, None]
    R_f, R_t = exp3(rv_f), exp3(rv_t)
    pos_f = rng.normal(size=(n, 3)) * 50 + 500
    pos_t = rng.normal(size=(n, 3)) * 50 - 300
    local = {
        "EFM": [10, -150, -40],
        "EFL": [10, -150, 45],
        "MM": [5, -200, -30],
        "LM": [0, -205, 30],
    }
    f = {
        "SubjectID": np.array([[7.0]]),
        "Gender": np.array(["f"]),
        "Height": np.array([[1620.0]]),
        "RFemoralClusterEul": euler_zyx_from_matrix(R_f),
        "RTibiaClusterEul": euler_zyx_from_matrix(R_t),
        "RFemoralClusterPos": pos_f,
        "RTibiaClusterPos": pos_t,
    }
    for name, p in local.items():
        R, pos = (R_f, pos_f) if name in ("EFM", "EFL") else (R_t, pos_t)
        f["R" + name] = np.einsum("nij,j->ni", R, p) + pos
    if swap:  # the file's labels exchanged: 'femur' slot carries the tibia cluster
        for a, b in (
            ("RFemoralClusterEul", "RTibiaClusterEul"),
            ("RFemoralClusterPos", "RTibiaClusterPos"),
        ):
            f[a], f[b] = f[b], f[a]
    return f, R_f, R_t, pos_f, pos_t


def test_omc_fields_units_and_rotations():
    f, R_f, R_t, pos_f, pos_t = _fields(np.random.default_rng(0))
    omc = omc_from_fields(f, "x.mat")
    assert (omc.subject_id, omc.sex, omc.height_m, omc.rate_hz) == (7, "f", 1.62, 100.0)
    np.testing.assert_allclose(omc.time[:3], [0, 0.01, 0.02])
    np.testing.assert_allclose(omc.landmarks["EFM"], f["REFM"] / 1000)
    np.testing.assert_allclose(omc.femur_cluster_R, R_f, atol=1e-12)
    np.testing.assert_allclose(omc.tibia_cluster_pos, pos_t / 1000)
    assert not omc.clusters_swapped and omc.notes == ()


def test_euler_convention_matches_matlab_eul2rotm():
    # eul2rotm([a b c]) = Rz(a) Ry(b) Rx(c); for a pure z angle the first column is (cos, sin, 0)
    R = matrix_from_euler_zyx(np.array([30 * DEG, 0, 0]))
    np.testing.assert_allclose(R[:, 0], [np.cos(30 * DEG), np.sin(30 * DEG), 0], atol=1e-12)


def test_swapped_clusters_detected_from_data():
    f, R_f, R_t, pos_f, pos_t = _fields(np.random.default_rng(1), swap=True)
    omc = omc_from_fields(f)
    assert omc.clusters_swapped
    np.testing.assert_allclose(omc.tibia_cluster_R, R_t, atol=1e-12)
    np.testing.assert_allclose(omc.femur_cluster_pos, pos_f / 1000)
    assert any("swapped" in n for n in omc.notes)


def test_nan_samples_kept_missing():
    f, *_ = _fields(np.random.default_rng(2))
    for k in ("REFM", "REFL", "RFemoralClusterEul", "RFemoralClusterPos"):
        f[k][10:15] = np.nan
    omc = omc_from_fields(f)
    assert np.isnan(omc.landmarks["EFM"][10:15]).all()
    assert np.isnan(omc.femur_cluster_R[12]).all()
    assert np.isfinite(omc.femur_cluster_R[20]).all()
    assert not omc.clusters_swapped
    assert any("EFM: 5 missing" in n for n in omc.notes)


@pytest.mark.parametrize(
    "field, value, match",
    [
        ("REFM", np.zeros((200, 2)), r"field REFM: expected shape \(N, 3\), found \(200, 2\)"),
        ("RMM", np.zeros((150, 3)), r"field RMM: expected shape \(200, 3\), found \(150, 3\)"),
        ("Height", np.array([[1.62]]), "field Height: expected a body height in mm"),
        ("Gender", np.array(["x"]), "field Gender: expected 'm' or 'f'"),
        ("SubjectID", np.zeros((0, 0)), r"field SubjectID: expected a 1x1 value"),
    ],
)
def test_omc_field_errors(field, value, match):
    f, *_ = _fields(np.random.default_rng(3))
    f[field] = value
    with pytest.raises(InputError, match=match) as e:
        omc_from_fields(f, "s.mat")
    assert "\n" not in str(e.value) and e.value.field == field


def test_missing_field_named():
    f, *_ = _fields(np.random.default_rng(3))
    del f["RTibiaClusterEul"]
    with pytest.raises(InputError, match="RTibiaClusterEul"):
        omc_from_fields(f)


def _imc_fields(rng, n=50, bad_cell=False):
    cells = np.empty((n, 1), dtype=object)
    R = exp3(rng.normal(size=(n, 3)))
    for i in range(n):
        cells[i, 0] = R[i]
    tib = np.empty((n, 1), dtype=object)
    for i in range(n):
        tib[i, 0] = R[i].T
    if bad_cell:
        tib[3, 0] = np.eye(2)
    q = rng.normal(size=(n, 4))
    return {"RFemoralRotm": cells, "RTibiaRotm": tib, "RFemoralQuat": q, "RKneeQuat": q}, R


def test_imc_fields_and_hand_correction():
    f, R = _imc_fields(np.random.default_rng(4))
    imc = imc_from_fields(f, 1)
    np.testing.assert_allclose(imc.femur_R, R)
    np.testing.assert_allclose(imc.tibia_R, np.swapaxes(R, 1, 2))
    # subject 1: C = eul2rotm([-10, 0, 0] deg) = Rz(-10 deg), by hand
    c, s = np.cos(-10 * DEG), np.sin(-10 * DEG)
    np.testing.assert_allclose(imc.hand_correction, [[c, -s, 0], [s, c, 0], [0, 0, 1]], atol=1e-12)
    np.testing.assert_allclose(imc.tibia_R_uncorrected @ imc.hand_correction, imc.tibia_R)
    np.testing.assert_allclose(hand_correction(4), np.eye(3))  # none applied
    assert len(TIBIA_HAND_CORRECTION_DEG) == 9 and IMC_OMC_INDEX_OFFSET[14] == -169
    with pytest.raises(InputError, match=r"field RTibiaRotm: .*cell of shape \(2, 2\)"):
        imc_from_fields(_imc_fields(np.random.default_rng(5), bad_cell=True)[0], 3)


def test_file_errors(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        load_subject(tmp_path / "rawData99.mat")
    txt = tmp_path / "rawData01.mat"
    txt.write_text("not a mat file\n")
    with pytest.raises(InputError, match="not a readable MATLAB .mat file") as e:
        load_subject(txt)
    assert "\n" not in str(e.value)
    other = tmp_path / "other.mat"
    scipy.io.savemat(other, {"x": np.zeros(3)})
    with pytest.raises(InputError, match="expected an omcData object"):
        load_subject(other)


def test_subject_paths_sorted_numerically(tmp_path):
    for i in (10, 2, 1):
        (tmp_path / f"rawData{i:02d}.mat").write_bytes(b"")
    (tmp_path / "notes.mat").write_bytes(b"")
    assert [p.name for p in subject_paths(tmp_path)] == [
        "rawData01.mat",
        "rawData02.mat",
        "rawData10.mat",
    ]
    with pytest.raises(InputError, match="no rawDataNN.mat"):
        subject_paths(tmp_path / "..")


# --------------------------------------------------------------------------------------------
# real data


@pytest.fixture(scope="module")
def subjects():
    if not DATA.is_dir():
        pytest.skip(f"dataset not found at {DATA}")
    return [load_subject(p) for p in subject_paths(DATA)]


@pytest.mark.dataset
def test_real_dataset_contents(subjects):
    assert [s.omc.subject_id for s in subjects] == list(range(1, 39))
    with_imc = [s.omc.subject_id for s in subjects if s.imc is not None]
    assert with_imc == [1, 2, 3, 6, 7, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19]
    assert sum(s.omc.sex == "m" for s in subjects) == 20
    assert [s.omc.subject_id for s in subjects if s.omc.clusters_swapped] == [1]
    assert subjects[20].omc.n_frames == 2651
    missing_tibia = np.isnan(subjects[1].omc.tibia_cluster_R).any(axis=(1, 2)).sum()
    assert missing_tibia == 594
    missing_femur = {
        s.omc.subject_id: int(np.isnan(s.omc.landmarks["EFM"]).any(axis=1).sum()) for s in subjects
    }
    expected = {3: 12, 8: 182, 11: 89, 13: 28, 16: 158, 33: 234}  # README
    assert {k: v for k, v in missing_femur.items() if v} == expected
    for s in subjects:
        assert 1.5 < s.omc.height_m < 1.9
        # malleoli rigid in the (possibly un-swapped) tibia cluster
        o = s.omc
        loc = np.einsum("nji,nj->ni", o.tibia_cluster_R, o.landmarks["MM"] - o.tibia_cluster_pos)
        assert np.nanmax(np.nanstd(loc, axis=0)) < 1e-6, o.subject_id
        if s.imc is not None:
            assert s.imc.n_frames == 2999
            RtR = np.swapaxes(s.imc.femur_R, 1, 2) @ s.imc.femur_R
            np.testing.assert_allclose(RtR, np.broadcast_to(np.eye(3), RtR.shape), atol=1e-6)
            np.testing.assert_allclose(s.imc.femur_R[0][:, 1], [0, 0, 1], atol=1e-9)  # F(1)'F(1)r


@pytest.mark.dataset
def test_real_require_imc(subjects):
    with pytest.raises(InputError, match="inertial data requested"):
        load_subject(subjects[3].path, require_imc=True)  # subject 4: OMC only
    assert load_subject(subjects[0].path, require_imc=True).imc is not None
