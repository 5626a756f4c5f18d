"""C3D reader (pipeline.io.c3d): the dataset's Xsens/optical files and generated ones."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.c3d import read_c3d

XSENS = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "wang2023" / "xsens"


def _needs(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"dataset file missing: {path}")
    return path


def _dist(m, a, b):
    return np.linalg.norm(m.marker(a) - m.marker(b), axis=1)


def _write_c3d(path: Path, points_xyz: np.ndarray, labels, *, unit="mm", rate=100.0):
    """points_xyz: (N, M, 3) in ``unit``."""
    ezc3d = pytest.importorskip("ezc3d")
    c = ezc3d.c3d()
    c["parameters"]["POINT"]["RATE"]["value"] = [rate]
    c["parameters"]["POINT"]["LABELS"]["value"] = tuple(labels)
    pts = np.ones((4, points_xyz.shape[1], points_xyz.shape[0]))
    pts[:3] = np.transpose(points_xyz, (2, 1, 0))
    c["data"]["points"] = pts
    if unit is not None:
        c.add_parameter("POINT", "UNITS", unit)
    c.write(str(path))
    return path


# ---------------------------------------------------------------- dataset files


@pytest.mark.dataset
def test_xsens_mvn_export_units_rate_and_segment_lengths():
    m = read_c3d(_needs(XSENS / "Subject1" / "HipF1" / "xsensHipF1.c3d"))
    assert m.units_in_file == "mm" and m.rate_hz == 240.0
    assert m.points.shape == (7727, 64, 3) and len(m.labels) == 64
    assert np.isfinite(m.points).all()
    np.testing.assert_allclose(m.time[:3], [0, 1 / 240, 2 / 240])
    assert m.analog == {}
    knee = _dist(m, "pRightKneeMedEpicondyle", "pRightKneeLatEpicondyle")
    ankle = _dist(m, "pRightMedMalleolus", "pRightLatMalleolus")
    thigh = _dist(m, "pRightGreaterTrochanter", "pRightKneeLatEpicondyle")
    # metres, plausible adult dimensions, and rigid (MVN's model has fixed segment lengths)
    assert 0.06 < knee.mean() < 0.14 and 0.04 < ankle.mean() < 0.10
    assert 0.30 < thigh.mean() < 0.55
    assert max(knee.std(), ankle.std(), thigh.std()) < 1e-3


@pytest.mark.dataset
def test_optical_file_labels_missing_samples_and_lengths():
    m = read_c3d(_needs(XSENS / "Subject1" / "HipF1" / "OMCHipF1.c3d"))
    assert set(m.labels) == {"REFM", "REFL", "RMM", "RLM"} and m.rate_hz == 100.0
    assert m.points.shape == (3000, 4, 3)
    assert np.isnan(m.points).any() and any("missing marker samples" in n for n in m.notes)
    knee = np.nanmedian(_dist(m, "REFM", "REFL"))
    shank = np.nanmedian(_dist(m, "REFL", "RLM"))
    assert 0.06 < knee < 0.14 and 0.30 < shank < 0.50


@pytest.mark.dataset
@pytest.mark.parametrize("height_cm", [150, 170, 190])
def test_static_pose_height_matches_file_name(height_cm):
    """The MVN static files are named by body height: the head top stands at that height."""
    files = sorted((XSENS / "XsensStatic_c3d").glob(f"Test_static_{height_cm}_*.c3d"))
    if not files:
        pytest.skip(f"no static file for {height_cm} cm under {XSENS}")
    m = read_c3d(files[0])
    head_z = m.marker("pTopOfHead")[:, 2]
    assert head_z.mean() == pytest.approx(height_cm / 100.0, abs=0.005)
    assert np.nanmin(m.points[..., 2]) == pytest.approx(0.0, abs=0.01)  # feet on the floor


# ---------------------------------------------------------------- generated files


@pytest.mark.parametrize(("unit", "scale"), [("mm", 1e-3), ("cm", 1e-2), ("m", 1.0)])
def test_units_converted_to_metres(tmp_path, unit, scale):
    rng = np.random.default_rng(4)
    pts_m = rng.uniform(-0.5, 0.5, (20, 2, 3)) + [0, 0, 1]
    p = _write_c3d(tmp_path / "a.c3d", pts_m / scale, ["EFM", "EFL"], unit=unit)
    m = read_c3d(p)
    assert m.units_in_file == unit and m.labels == ("EFM", "EFL")
    np.testing.assert_allclose(m.points, pts_m, rtol=1e-6, atol=1e-6)  # c3d stores float32
    np.testing.assert_allclose(m.marker("EFL"), pts_m[:, 1], rtol=1e-6, atol=1e-6)


def test_millimetres_labelled_as_metres_refused(tmp_path):
    pts_mm = np.full((10, 2, 3), 900.0)
    pts_mm[:, 1] += 400.0
    pts_mm[:, 0, 0] += np.linspace(0, 3000, 10)
    p = _write_c3d(tmp_path / "a.c3d", pts_mm, ["a", "b"], unit="m")
    with pytest.raises(
        InputError, match="field POINT: positions span .* millimetres given as metres"
    ):
        read_c3d(p)


def test_unknown_unit_and_unknown_marker_refused(tmp_path):
    pts = np.ones((5, 1, 3))
    with pytest.raises(InputError, match="field POINT:UNITS: unknown unit 'in'"):
        read_c3d(_write_c3d(tmp_path / "a.c3d", pts, ["a"], unit="in"))
    m = read_c3d(_write_c3d(tmp_path / "b.c3d", pts, ["a"]))
    with pytest.raises(InputError, match="no marker 'RMM'; available: a"):
        m.marker("RMM")


def test_empty_missing_and_garbage_files_refused(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        read_c3d(tmp_path / "none.c3d")
    (tmp_path / "e.c3d").write_bytes(b"")
    with pytest.raises(InputError, match="file is empty"):
        read_c3d(tmp_path / "e.c3d")
    (tmp_path / "g.c3d").write_bytes(b"this is not a c3d file at all" * 20)
    with pytest.raises(InputError, match="not a readable C3D file"):
        read_c3d(tmp_path / "g.c3d")


def test_truncated_c3d_refused(tmp_path):
    rng = np.random.default_rng(5)
    p = _write_c3d(tmp_path / "a.c3d", rng.uniform(0, 1000, (200, 3, 3)), ["a", "b", "c"])
    data = p.read_bytes()
    p.write_bytes(data[: len(data) // 2])
    with pytest.raises(InputError, match=r"header declares 200 frames but the data hold only \d+"):
        read_c3d(p)
