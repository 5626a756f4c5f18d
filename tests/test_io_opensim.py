"""OpenSim .sto orientation files and .mot tables (pipeline.io.opensim)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from pipeline.errors import InputError
from pipeline.io import mot, opensim
from pipeline.io.checks import make_quaternions_continuous
from pipeline.io.recording import Recording
from pipeline.rotations import exp3, log3, matrix_from_quat, quat_from_matrix

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opensim"
NAMES = ["pelvis_imu", "femur_r_imu", "tibia_r_imu"]


def _needs(path: Path) -> Path:
    if not path.exists():
        pytest.skip(f"dataset file missing: {path}")
    return path


def _truth(n: int = 100, rate: float = 100.0) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    t = 2.0 + np.arange(n) / rate
    sensors = {}
    for k, name in enumerate(NAMES):
        axis = np.array([1.0, k, 2.0 - k]) / np.linalg.norm([1.0, k, 2.0 - k])
        sensors[name] = _continuous(
            exp3(np.array([0.1 * k, 0.5, -0.2])) @ exp3((1 + k) * t[:, None] * axis)
        )
    return t, sensors


def _continuous(R: np.ndarray) -> np.ndarray:
    return make_quaternions_continuous(quat_from_matrix(R))[0]


def _write_sto(path: Path, t, sensors, *, rate="100.000000", extra_header="", fmt="{:.15g}"):
    lines = [f"DataRate={rate}", "DataType=Quaternion", "version=3", extra_header, "endheader"]
    lines = [ln for ln in lines if ln]
    lines.append("\t".join(["time", *sensors]))
    for i in range(len(t)):
        cells = [fmt.format(t[i])]
        cells += [",".join(fmt.format(v) for v in q[i]) for q in sensors.values()]
        lines.append("\t".join(cells))
    path.write_text("\n".join(lines) + "\n")
    return path


def _rot_err(q1, q2):
    """Angle (rad) of the rotation between q1 and q2 (log map: accurate near zero)."""
    R = np.swapaxes(matrix_from_quat(q1), -1, -2) @ matrix_from_quat(q2)
    return np.linalg.norm(log3(R), axis=-1)


# ---------------------------------------------------------------- real files


@pytest.mark.dataset
def test_real_quaternions_4_ik():
    path = _needs(DATA / "quaternions_4_ik.sto")
    tr = opensim.read_orientations_sto(path)
    assert tr.n_samples == 1401 and len(tr.sensors) == 8
    assert tr.rate_hz == 100.0 and tr.time[0] == 417.0 and tr.time[-1] == pytest.approx(431.0)
    assert set(tr.sensors) == set(opensim.SENSOR_TO_SEGMENT)
    # first row parsed by hand from the text
    line = path.read_text().splitlines()[7].split("\t")
    assert float(line[0]) == 417.0
    q_file = np.array([float(v) for v in line[1].split(",")])
    np.testing.assert_allclose(tr.sensors["torso_imu"].quat[0], q_file / np.linalg.norm(q_file))
    for q in tr.orientations().values():
        np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0, atol=1e-12)
        assert np.all(np.sum(q[1:] * q[:-1], axis=1) > 0)  # continuous
    segs = opensim.map_sensors(tr, required=["pelvis", "right_femur", "left_foot", "torso"])
    assert set(segs) == set(opensim.SENSOR_TO_SEGMENT.values())


@pytest.mark.dataset
def test_real_xsens_walking_and_opensense_rotation():
    path = _needs(DATA / "xsens_walking_orientations.sto")
    tr = opensim.read_orientations_sto(path)
    assert tr.n_samples == 2432 and tr.rate_hz == 100.0 and len(tr.sensors) == 8
    R = opensim.sensor_to_opensim_matrix([-np.pi / 2, 0, 0])
    np.testing.assert_allclose(R @ [0, 0, 1], [0, 1, 0], atol=1e-15)  # Xsens z-up -> OpenSim y-up
    rot = opensim.rotate_world(tr, R)
    for name in tr.sensors:
        np.testing.assert_allclose(
            matrix_from_quat(rot.sensors[name].quat),
            R @ matrix_from_quat(tr.sensors[name].quat),
            atol=1e-12,
        )
    # relative orientation pelvis -> femur does not depend on the world frame
    rel = lambda t: (  # noqa: E731
        np.swapaxes(matrix_from_quat(t.sensors["pelvis_imu"].quat), 1, 2)
        @ matrix_from_quat(t.sensors["femur_r_imu"].quat)
    )
    np.testing.assert_allclose(rel(rot), rel(tr), atol=1e-12)
    assert "world frame rotated by a fixed rotation of 90 deg" in rot.notes[-1]


def test_sensor_to_opensim_matrix_is_space_fixed_xyz():
    a = [0.3, -1.1, 2.0]
    expected = Rotation.from_euler("xyz", a).as_matrix()  # scipy lowercase = extrinsic
    np.testing.assert_allclose(opensim.sensor_to_opensim_matrix(a), expected, atol=1e-14)


# ---------------------------------------------------------------- round trips


def test_sto_write_read_round_trip(tmp_path):
    t, sensors = _truth()
    tr = Recording.from_orientations(t, 100.0, sensors)
    p = opensim.write_orientations_sto(tmp_path / "o.sto", tr)
    back = opensim.read_orientations_sto(p)
    np.testing.assert_array_equal(back.time, t)
    for n in NAMES:
        np.testing.assert_allclose(back.sensors[n].quat, sensors[n], atol=1e-15)
    assert back.notes == () and list(back.sensors) == NAMES


def test_mot_round_trip_and_header(tmp_path):
    t = np.arange(50) / 100.0
    cols = {
        "hip_flexion_r": np.sin(t),
        "knee_angle_r": -0.5 * t,
        "pelvis_tx": 0.1 + t,  # a translation: metres, never converted
    }
    p = mot.write_mot(tmp_path / "ik.mot", t, cols, in_degrees=True)
    lines = p.read_text().splitlines()
    assert lines[:6] == [
        "Coordinates",
        "version=1",
        "nRows=50",
        "nColumns=4",
        "inDegrees=yes",
        "endheader",
    ]
    assert lines[6].split("\t") == ["time", "hip_flexion_r", "knee_angle_r", "pelvis_tx"]
    row = [float(v) for v in lines[17].split("\t")]
    assert row[2] == pytest.approx(np.degrees(-0.5 * t[10])) and row[3] == pytest.approx(
        0.1 + t[10]
    )
    back = mot.read_mot(p)
    assert back.in_degrees and back.name == "Coordinates"
    for k, v in cols.items():
        np.testing.assert_allclose(back.columns[k], v, rtol=1e-15, atol=1e-15)
    p2 = mot.write_mot(tmp_path / "rad.mot", t, cols, in_degrees=False)
    assert "inDegrees=no" in p2.read_text()
    np.testing.assert_array_equal(
        mot.read_mot(p2).columns["knee_angle_r"], cols["knee_angle_r"]
    )


# ---------------------------------------------------------------- sensor mapping


def test_map_sensors_missing_names_file_sensor_and_columns(tmp_path):
    t, sensors = _truth(10)
    p = _write_sto(tmp_path / "o.sto", t, sensors)
    tr = opensim.read_orientations_sto(p)
    segs = opensim.map_sensors(tr, required=["pelvis", "right_femur"])
    assert set(segs) == {"pelvis", "right_femur", "right_tibia"}
    np.testing.assert_array_equal(segs["right_tibia"], tr.sensors["tibia_r_imu"].quat)
    with pytest.raises(InputError) as e:
        opensim.map_sensors(tr, required=["pelvis", "left_tibia", "left_foot"])
    msg = str(e.value)
    assert str(p) in msg
    assert "tibia_l_imu (for left_tibia), calcn_l_imu (for left_foot)" in msg
    assert "available columns: pelvis_imu, femur_r_imu, tibia_r_imu" in msg


# ---------------------------------------------------------------- bad inputs


def test_empty_and_headerless_files_refused(tmp_path):
    (tmp_path / "e.sto").write_text("")
    with pytest.raises(InputError, match="file is empty"):
        opensim.read_orientations_sto(tmp_path / "e.sto")
    (tmp_path / "h.sto").write_text("time\ta\n0\t1,0,0,0\n")
    with pytest.raises(InputError, match="no 'endheader' line"):
        opensim.read_orientations_sto(tmp_path / "h.sto")
    (tmp_path / "n.sto").write_text("DataRate=100\nendheader\ntime\tpelvis_imu\n")
    with pytest.raises(InputError, match="no data rows"):
        opensim.read_orientations_sto(tmp_path / "n.sto")


def test_truncated_mid_row_refused(tmp_path):
    t, sensors = _truth(20)
    p = _write_sto(tmp_path / "o.sto", t, sensors)
    text = p.read_text()
    cut = text[: len(text) - 40]  # inside the last quaternion cell of the last row
    p.write_text(cut)
    with pytest.raises(InputError, match=r"row 19 \(line 25\) has \d+ fields, expected 13"):
        opensim.read_orientations_sto(p)


def test_cell_with_three_components_refused(tmp_path):
    t, sensors = _truth(10)
    p = _write_sto(tmp_path / "o.sto", t, sensors)
    lines = p.read_text().splitlines()
    cells = lines[8].split("\t")
    cells[2] = ",".join(cells[2].split(",")[:3])
    lines[8] = "\t".join(cells)
    p.write_text("\n".join(lines))
    with pytest.raises(InputError, match=r"row 3 \(line 9\) has 12 fields, expected 13.*'w,x,y,z'"):
        opensim.read_orientations_sto(p)


def test_wrong_datatype_refused(tmp_path):
    p = tmp_path / "d.sto"
    p.write_text("DataRate=100\nDataType=double\nendheader\ntime\tknee\n0\t1\n0.01\t2\n")
    with pytest.raises(InputError, match="DataType=double: expected Quaternion.*read_mot"):
        opensim.read_orientations_sto(p)


@pytest.mark.parametrize(
    ("edit", "msg"),
    [
        ("repeat", r"repeated time stamp 2\.04 s at row 5 \(line 11\)"),
        ("swap", r"not sorted: 2\.05 s at row 6 \(line 12\) comes after 2\.06 s"),
    ],
)
def test_bad_time_stamps_refused(tmp_path, edit, msg):
    t, sensors = _truth(20)
    t = t.copy()
    if edit == "repeat":
        t[5] = t[4]
    else:
        t[5], t[6] = t[6], t[5]
    p = _write_sto(tmp_path / "o.sto", t, sensors)
    with pytest.raises(InputError, match=msg):
        opensim.read_orientations_sto(p)


def test_rate_disagreeing_with_datarate_refused(tmp_path):
    t, sensors = _truth(20)
    p = _write_sto(tmp_path / "o.sto", t, sensors, rate="50.000000")
    with pytest.raises(InputError, match=r"declared rate 50 Hz but the time stamps give 100 Hz"):
        opensim.read_orientations_sto(p)


def test_short_nan_gap_slerped_and_reported(tmp_path):
    t, sensors = _truth(100)
    holed = {k: v.copy() for k, v in sensors.items()}
    holed["femur_r_imu"][40:45] = np.nan
    p = _write_sto(tmp_path / "o.sto", t, holed)
    tr = opensim.read_orientations_sto(p)
    assert _rot_err(tr.sensors["femur_r_imu"].quat, sensors["femur_r_imu"]).max() < 1e-9
    assert any(
        "field femur_r_imu: filled 5 missing sample(s) from t=2.4 s to t=2.44 s (slerp)" in n
        for n in tr.notes
    )


def test_long_nan_gap_left_missing(tmp_path):
    t, sensors = _truth(100)
    sensors["tibia_r_imu"][30:60] = np.nan
    rec = opensim.read_orientations_sto(_write_sto(tmp_path / "o.sto", t, sensors))
    tibia = rec.sensors["tibia_r_imu"].quat
    assert np.isnan(tibia[30:60]).all() and np.isfinite(tibia[60:]).all()
    assert np.isfinite(rec.sensors["pelvis_imu"].quat).all()
    assert any("field tibia_r_imu: missing 30 sample(s) (0.3 s)" in n for n in rec.notes)


def test_non_unit_zero_and_slightly_off_quaternions(tmp_path):
    t, sensors = _truth(20)
    s = {k: v.copy() for k, v in sensors.items()}
    s["pelvis_imu"][3] *= 2.0
    with pytest.raises(InputError, match=r"pelvis_imu: not unit quaternions \(norm 2 at row 3"):
        opensim.read_orientations_sto(_write_sto(tmp_path / "a.sto", t, s))
    s = {k: v.copy() for k, v in sensors.items()}
    s["pelvis_imu"][3] = 0.0
    with pytest.raises(InputError, match=r"zero quaternion at row 3 \(line 9\)"):
        opensim.read_orientations_sto(_write_sto(tmp_path / "b.sto", t, s))
    s = {k: v.copy() for k, v in sensors.items()}
    s["pelvis_imu"] *= 1.02
    tr = opensim.read_orientations_sto(_write_sto(tmp_path / "c.sto", t, s))
    np.testing.assert_allclose(tr.sensors["pelvis_imu"].quat, sensors["pelvis_imu"], atol=1e-14)
    assert any("normalised 20 quaternion(s)" in n for n in tr.notes)


def test_opensim_loads_our_files(tmp_path):
    """Runs where the ``opensim`` package is installed (verified with OpenSim 4.6).

    OpenSim is loaded in a child process: its bundled CasADi clashes with the PyPI casadi that
    this test process has already loaded (undefined symbol on import).
    """
    import importlib.util
    import json
    import subprocess
    import sys

    if importlib.util.find_spec("opensim") is None:
        pytest.skip("could not import 'opensim': No module named 'opensim'")
    t = np.arange(30) / 100.0
    p = mot.write_mot(tmp_path / "ik.mot", t, {"knee_angle_r": -0.5 * t, "pelvis_tx": t})
    tt, sensors = _truth(20)
    ps = opensim.write_orientations_sto(
        tmp_path / "o.sto", Recording.from_orientations(tt, 100.0, sensors)
    )
    script = f"""
import json, opensim as osim
table = osim.TimeSeriesTable({str(p)!r})
qt = osim.TimeSeriesTableQuaternion({str(ps)!r})
e = qt.getRowAtIndex(5).getElt(0, 0)
print(json.dumps(dict(
    rows=table.getNumRows(), labels=list(table.getColumnLabels()),
    knee10=table.getDependentColumn("knee_angle_r")[10],
    in_degrees=bool(osim.Storage({str(p)!r}).isInDegrees()),
    quat=[e.get(i) for i in range(4)])))
"""
    # OpenSim writes opensim.log into the working directory
    run = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True,
                         text=True, check=True)
    out = json.loads(run.stdout.strip().splitlines()[-1])
    assert out["rows"] == 30 and out["labels"] == ["knee_angle_r", "pelvis_tx"]
    assert out["knee10"] == pytest.approx(np.degrees(-0.05))
    assert out["in_degrees"]
    np.testing.assert_allclose(out["quat"], sensors[NAMES[0]][5], atol=1e-15)
