"""Xsens MT Manager .txt exports (pipeline.io.xsens) on files generated with known truth.

The generated files follow the layout of OpenSim's Xsens test files (``// key: value`` comments,
``PacketCounter`` zero-padded, empty cells for unused columns, ``Mat[r][c]`` listed column by
column, six decimals).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io import xsens
from pipeline.io.checks import make_quaternions_continuous
from pipeline.rotations import euler_zyx_from_matrix, exp3, log3, matrix_from_quat, quat_from_matrix

RATE = 100.0
G = np.array([0.0, 0.0, 9.81])


def _motion(n: int = 200, w=(0.8, -0.4, 1.2)):
    """Constant body angular velocity ``w`` (rad/s): R(t) = R0 exp(t [w]x)."""
    t = np.arange(n) / RATE
    R = exp3(np.array([0.2, -0.3, 2.0])) @ exp3(t[:, None] * np.asarray(w))
    acc = np.einsum("nji,j->ni", R, G)  # specific force at rest-like: R^T g
    gyr = np.tile(w, (n, 1))
    return t, R, acc, gyr


#: The earth's field in MT Manager's z-up world (a.u.: north, dipping down).
FIELD = np.array([0.45, 0.0, -0.89])


def _write(
    path: Path,
    R,
    acc,
    gyr,
    *,
    orientation="matrix",
    counter=None,
    rate_comment="// Update Rate: 100.0Hz",
    stf=None,
    delim="\t",
    drop=(),
):
    n = len(R)
    counter = np.arange(3583, 3583 + n) if counter is None else np.asarray(counter)
    head = ["PacketCounter", "SampleTimeFine", "Year", "Acc_X", "Acc_Y", "Acc_Z"]
    head += ["Gyr_X", "Gyr_Y", "Gyr_Z", "Mag_X", "Mag_Y", "Mag_Z"]
    if orientation == "matrix":
        head += [f"Mat[{r}][{c}]" for c in (1, 2, 3) for r in (1, 2, 3)]
    elif orientation == "quaternion":
        head += ["Quat_q0", "Quat_q1", "Quat_q2", "Quat_q3"]
    elif orientation == "euler":
        head += ["Roll", "Pitch", "Yaw"]
    lines = ["// Start Time: Unknown"]
    if rate_comment:
        lines.append(rate_comment)
    lines += ["// Filter Profile: human (46.1)", "// Firmware Version: 4.0.2", delim.join(head)]
    for i in range(n):
        if i in drop:
            continue
        cells = [f"{int(counter[i]) % 65536:05d}", "" if stf is None else f"{int(stf[i])}", ""]
        mag = R[i].T @ FIELD  # the earth's field turning with the sensor
        cells += [f"{v:.6f}" for v in (*acc[i], *gyr[i], *mag)]
        if orientation == "matrix":
            cells += [f"{R[i][r, c]:.6f}" for c in range(3) for r in range(3)]
        elif orientation == "quaternion":
            cells += [f"{v:.6f}" for v in quat_from_matrix(R[i])]
        elif orientation == "euler":
            yaw, pitch, roll = np.degrees(euler_zyx_from_matrix(R[i]))
            cells += [f"{v:.6f}" for v in (roll, pitch, yaw)]
        lines.append(delim.join(cells))
    path.write_text("\n".join(lines) + "\n")
    return path


def _err(q, R):
    return np.linalg.norm(log3(np.swapaxes(matrix_from_quat(q), -1, -2) @ R), axis=-1)


@pytest.mark.parametrize("orientation", ["matrix", "quaternion", "euler"])
def test_orientation_formats_agree_with_truth(tmp_path, orientation):
    t, R, acc, gyr = _motion()
    p = _write(
        tmp_path / f"MT_012005D6_009-001_00B421AF_{orientation}.txt",
        R,
        acc,
        gyr,
        orientation=orientation,
    )
    rec = xsens.read_xsens_txt(p)
    assert rec.header["orientation_from"] == orientation
    assert rec.rate_hz == 100.0 and rec.header["Update Rate"] == "100.0Hz"
    np.testing.assert_allclose(rec.time, t, atol=1e-12)
    assert _err(rec.quat, R).max() < 2e-5  # six printed decimals
    np.testing.assert_allclose(rec.acc, acc, atol=1e-6)
    np.testing.assert_allclose(rec.gyr, gyr, atol=1e-6)
    np.testing.assert_allclose(rec.mag, np.einsum("nji,j->ni", R, FIELD), atol=1e-6)
    # gravity check: the accelerometer at rest is R^T g
    np.testing.assert_allclose(
        np.einsum("nji,j->ni", matrix_from_quat(rec.quat), G), rec.acc, atol=2e-4
    )
    assert rec.name == orientation  # last '_' field of the file name


def test_sensor_id_from_file_name(tmp_path):
    t, R, acc, gyr = _motion(20)
    rec = xsens.read_xsens_txt(_write(tmp_path / "MT_012005D6_009-001_00B421AF.txt", R, acc, gyr))
    assert rec.name == "00B421AF"


def test_packet_counter_wraps(tmp_path):
    t, R, acc, gyr = _motion(100)
    rec = xsens.read_xsens_txt(
        _write(tmp_path / "w.txt", R, acc, gyr, counter=np.arange(65500, 65600))
    )
    np.testing.assert_allclose(rec.time, t, atol=1e-12)
    assert not any("dropped" in n for n in rec.notes)


def test_dropped_packets_filled_and_reported(tmp_path):
    t, R, acc, gyr = _motion(100)
    rec = xsens.read_xsens_txt(_write(tmp_path / "d.txt", R, acc, gyr, drop=(40, 41, 42)))
    assert rec.time.size == 100
    assert any("3 dropped packet(s)" in n for n in rec.notes)
    assert any(
        "filled 3 missing sample(s) from t=0.4 s to t=0.42 s (slerp)" in n for n in rec.notes
    )
    assert _err(rec.quat, R).max() < 2e-5  # constant-rate rotation: slerp is exact
    np.testing.assert_allclose(rec.gyr, gyr, atol=1e-6)


def test_long_packet_loss_left_missing_and_noted(tmp_path):
    t, R, acc, gyr = _motion(100)
    rec = xsens.read_xsens_txt(_write(tmp_path / "d.txt", R, acc, gyr, drop=tuple(range(30, 60))))
    assert rec.time.size == 100
    assert np.isnan(rec.quat[30:60]).all() and np.isnan(rec.gyr[30:60]).all()
    assert np.isfinite(rec.quat[:30]).all() and np.isfinite(rec.quat[60:]).all()
    assert any("missing 30 sample(s) (0.3 s) from t=0.3 s to t=0.59 s" in n and "not bridged" in n
               for n in rec.notes)


def test_repeated_packet_counter_refused(tmp_path):
    t, R, acc, gyr = _motion(20)
    c = np.arange(20)
    c[7] = c[6]
    with pytest.raises(InputError, match=r"packet counter repeated: 6 at row 7 \(line 13\)"):
        xsens.read_xsens_txt(_write(tmp_path / "r.txt", R, acc, gyr, counter=c))


def test_sample_time_fine_gives_time_and_is_checked_against_rate(tmp_path):
    t, R, acc, gyr = _motion(50)
    stf = 123456 + np.arange(50) * 100  # 10 kHz ticks, 100 Hz
    rec = xsens.read_xsens_txt(_write(tmp_path / "s.txt", R, acc, gyr, stf=stf))
    np.testing.assert_allclose(rec.time, t, atol=1e-12)
    rec2 = xsens.read_xsens_txt(
        _write(tmp_path / "s1.txt", R, acc, gyr, stf=123456 + np.arange(50) * 100, drop=(20, 21))
    )
    assert rec2.time.size == 50
    assert any("2 dropped sample(s) (SampleTimeFine jumps)" in n for n in rec2.notes)
    assert _err(rec2.quat, R).max() < 2e-5
    stf_50 = 123456 + np.arange(50) * 200  # 50 Hz stamps, file says 100 Hz
    with pytest.raises(InputError, match=r"declared rate 100 Hz but the time stamps give 50 Hz"):
        xsens.read_xsens_txt(_write(tmp_path / "s2.txt", R, acc, gyr, stf=stf_50))


def test_missing_rate_refused_unless_given(tmp_path):
    t, R, acc, gyr = _motion(20)
    p = _write(tmp_path / "n.txt", R, acc, gyr, rate_comment=None)
    with pytest.raises(InputError, match="no sampling rate.*pass rate_hz"):
        xsens.read_xsens_txt(p)
    rec = xsens.read_xsens_txt(p, rate_hz=50.0)
    np.testing.assert_allclose(rec.time, np.arange(20) / 50.0)
    q = _write(tmp_path / "m.txt", R, acc, gyr)
    with pytest.raises(InputError, match="rate_hz=50 but the file says Update Rate 100 Hz"):
        xsens.read_xsens_txt(q, rate_hz=50.0)


def test_a_raw_export_without_orientation_columns_is_read_as_raw_signals(tmp_path):
    t, R, acc, gyr = _motion(20)
    p = _write(tmp_path / "o.txt", R, acc, gyr, orientation="none")
    rec = xsens.read_xsens_txt(p)
    s = rec.sensor
    assert s.quat is None and rec.header["orientation_from"] == "none"
    np.testing.assert_allclose(s.gyr, gyr, atol=1e-6)
    np.testing.assert_allclose(s.acc, acc, atol=1e-6)
    # neither orientations nor the raw signals: refused, naming what was expected
    lines = p.read_text().splitlines()
    header = lines[4].split("\t")
    keep = [k for k, h in enumerate(header) if not h.startswith(("Acc", "Gyr"))]
    (tmp_path / "n.txt").write_text("\n".join(lines[:4] + ["\t".join(
        [ln.split("\t")[k] for k in keep]) for ln in lines[4:]]) + "\n")
    with pytest.raises(InputError, match=r"no orientation columns .* no raw Acc_X.*found Packet"):
        xsens.read_xsens_txt(tmp_path / "n.txt")


def test_a_folder_of_raw_xsens_exports_runs_through_the_filter_and_ik(tmp_path):
    """The Xsens MT raw path end to end: simulated gait (misplaced sensors, noise, gyro bias)
    written as MT Manager .txt exports with Acc/Gyr/Mag only, read by the ``pipeline ik`` loader
    with an id map, filtered by VQF 9-D: knee flexion of the truth within 2 deg RMS, hip flexion
    within 3 (the simulated subject stands leaning 2-6 deg; the lean the joint centres give is
    1.2 deg short on this 10 s trial: hip measured 2.5 and 1.7 deg, 3.3 and 3.7 upright)."""
    from pipeline.analysis.joint_angles import joint_angles
    from pipeline.commands.ik import load_orientations
    from pipeline.model.measures import Measures
    from pipeline.process import process_recording
    from pipeline.simulate.model import simulate_trial

    trial = simulate_trial(motion="gait", duration_s=10.0, seed=2, standing_s=2.0)
    ours = {"pelvis_imu": "pelvis_imu", "right_femur_imu": "femur_r_imu",
            "right_tibia_imu": "tibia_r_imu", "right_foot_imu": "calcn_r_imu",
            "left_femur_imu": "femur_l_imu", "left_tibia_imu": "tibia_l_imu",
            "left_foot_imu": "calcn_l_imu"}
    sensor_map = {}
    for k, (frame, name) in enumerate(ours.items()):
        sid = f"00B4{k:04X}"
        sensor_map[name] = sid
        s = trial.imus[frame].recording.sensor
        head = ["PacketCounter", "SampleTimeFine", "Acc_X", "Acc_Y", "Acc_Z", "Gyr_X", "Gyr_Y",
                "Gyr_Z", "Mag_X", "Mag_Y", "Mag_Z"]
        rows = ["// Update Rate: 100.0Hz", "\t".join(head)]
        for i in range(len(trial.time)):
            cells = [f"{i:05d}", f"{1000 + 100 * i}"]
            cells += [f"{v:.6f}" for v in (*s.acc[i], *s.gyr[i], *(s.mag[i] / 50.0))]
            rows.append("\t".join(cells))
        (tmp_path / f"MT_012005D6_009-001_{sid}.txt").write_text("\n".join(rows) + "\n")
    rec = load_orientations(tmp_path, sensor_map)
    assert all(rec.sensors[n].quat is None and rec.sensors[n].mag is not None
               for n in ours.values())
    run = process_recording(rec, Measures("m", 1.75))
    assert any("by VQF, 9-D" in n for n in run.notes)
    truth = joint_angles(trial.skeleton, trial.q)
    for key, bound in (("right_knee_flexion", 2.0), ("left_knee_flexion", 2.0),
                       ("right_hip_flexion", 3.0), ("left_hip_flexion", 3.0)):
        e = np.degrees(run.joint_angles[key][200:] - truth[key][200:])
        assert np.sqrt(np.mean(e**2)) < bound, (key, np.sqrt(np.mean(e**2)))


def test_truncated_and_empty_files_refused(tmp_path):
    t, R, acc, gyr = _motion(20)
    p = _write(tmp_path / "t.txt", R, acc, gyr)
    p.write_text(p.read_text()[:-30])
    with pytest.raises(InputError, match=r"row 19 \(line 25\) has \d+ fields.*truncated"):
        xsens.read_xsens_txt(p)
    (tmp_path / "e.txt").write_text("// Update Rate: 100.0Hz\n")
    with pytest.raises(InputError, match="no header line"):
        xsens.read_xsens_txt(tmp_path / "e.txt")


def test_gyro_in_degrees_refused(tmp_path):
    t, R, acc, gyr = _motion(50, w=(2.0, -1.0, 1.5))
    p = _write(tmp_path / "g.txt", R, acc, np.degrees(gyr))
    with pytest.raises(InputError, match="field Gyr: angular velocity.*looks like deg/s"):
        xsens.read_xsens_txt(p)


@pytest.mark.parametrize("delim", [",", ";"])
def test_comma_and_semicolon_delimited_exports(tmp_path, delim):
    """MT Manager's export settings offer tab, comma and semicolon; each is read, and the world
    is the vendor's (z up: pipeline ik turns it without --sensor-to-model)."""
    t, R, acc, gyr = _motion(30)
    rec = xsens.read_xsens_txt(_write(tmp_path / "c.txt", R, acc, gyr, delim=delim))
    assert _err(rec.quat, R).max() < 2e-5
    assert rec.header["world"] == "xsens"


def test_trailing_delimiters_as_mt_manager_writes_them(tmp_path):
    """Some MT Manager versions end the header and every row with the delimiter."""
    t, R, acc, gyr = _motion(30)
    path = _write(tmp_path / "t.txt", R, acc, gyr, delim=";")
    lines = path.read_text().splitlines()
    path.write_text("\n".join(ln if ln.startswith("//") else ln + ";" for ln in lines) + "\n")
    rec = xsens.read_xsens_txt(path)
    assert _err(rec.quat, R).max() < 2e-5


def test_trial_from_several_sensors(tmp_path):
    from pipeline.io.formats import read_recording

    t, R, acc, gyr = _motion(60)
    t2, R2, acc2, gyr2 = _motion(60, w=(0.1, 0.2, -0.3))
    _write(tmp_path / "MT_012005D6_009-001_00B421AF.txt", R, acc, gyr)
    _write(tmp_path / "MT_012005D6_009-001_00B42263.txt", R2, acc2, gyr2)
    trial = read_recording(tmp_path, {"pelvis_imu": "00B421AF", "femur_r_imu": "00B42263"})
    assert set(trial.sensor_names) == {"pelvis_imu", "femur_r_imu"} and trial.rate_hz == 100.0
    np.testing.assert_allclose(trial.time, t, atol=1e-12)
    assert _err(trial.sensors["femur_r_imu"].quat, R2).max() < 2e-5
    q = make_quaternions_continuous(trial.sensors["pelvis_imu"].quat)[0]
    np.testing.assert_array_equal(q, trial.sensors["pelvis_imu"].quat)  # already continuous
    with pytest.raises(InputError, match="no sensor of the recording matches '00B4XXXX'"):
        read_recording(tmp_path, {"tibia_r_imu": "00B4XXXX"})
    with pytest.raises(InputError, match=r"no sensor name for \['MT_012005D6_009-001_00B42263"):
        read_recording(tmp_path, {"pelvis_imu": "00B421AF"})


def test_a_sensor_that_stops_early_or_starts_late_is_missing_there(tmp_path):
    """Files of one station share the packet counter: the trial spans every sensor's samples;
    a file that stops early or starts late leaves its sensor missing there (NaN, never bridged),
    and a note says so (not a refusal, not a crop)."""
    from pipeline.io.formats import read_recording

    t, R, acc, gyr = _motion(60)
    _write(tmp_path / "a_1.txt", R, acc, gyr)
    _write(tmp_path / "a_2.txt", R[:40], acc[:40], gyr[:40])
    trial = read_recording(tmp_path, {"pelvis_imu": "a_1", "femur_r_imu": "a_2"})
    assert trial.n_samples == 60
    np.testing.assert_allclose(trial.time, t, atol=1e-9)
    femur = trial.sensors["femur_r_imu"].quat
    assert np.isnan(femur[40:]).all() and _err(femur[:40], R[:40]).max() < 2e-5
    assert "femur_r_imu ends 0.20 s early: missing there, not bridged" in trial.notes
    later = np.arange(3583 + 20, 3583 + 60)  # the second sensor's first packet 20 samples later
    _write(tmp_path / "a_2.txt", R[20:], acc[20:], gyr[20:], counter=later)
    trial = read_recording(tmp_path, {"pelvis_imu": "a_1", "femur_r_imu": "a_2"})
    assert trial.n_samples == 60
    assert _err(trial.sensors["pelvis_imu"].quat, R).max() < 2e-5
    femur = trial.sensors["femur_r_imu"].quat
    assert np.isnan(femur[:20]).all() and _err(femur[20:], R[20:]).max() < 2e-5
    assert "femur_r_imu starts 0.20 s late: missing there, not bridged" in trial.notes


def test_empty_orientation_columns_are_read_as_raw_signals(tmp_path):
    """An export whose Quat_ columns are there but empty (the raw signals complete): read as
    raw signals, said in the notes (refused before: 'no finite values at all')."""
    t, R, acc, gyr = _motion(50)
    p = _write(tmp_path / "q.txt", R, acc, gyr, orientation="quaternion")
    lines = p.read_text().splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("PacketCounter"))
    cols = lines[head].split("\t")
    quat = [k for k, c in enumerate(cols) if c.startswith("Quat_")]
    assert len(quat) == 4
    for i in range(head + 1, len(lines)):
        cells = lines[i].split("\t")
        for k in quat:
            cells[k] = ""
        lines[i] = "\t".join(cells)
    p.write_text("\n".join(lines) + "\n")
    rec = xsens.read_xsens_txt(p)
    assert rec.sensor.quat is None
    np.testing.assert_allclose(rec.gyr, gyr, atol=1e-6)
    assert any("the orientation columns are empty: read as raw signals" in n for n in rec.notes)
