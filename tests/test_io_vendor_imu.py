"""pipeline.io.vendor_imu: Movella DOT .csv exports and x-IMU3 device folders, in SI units."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.vendor_imu import G, read_movella_dot_csv, read_ximu3_folder
from pipeline.rotations import exp3, quat_from_matrix

XIMU3 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ximu3_lower_body"


def _dot_file(path, n=240, rate=120.0, start_us=4_294_000_000, metadata=True):
    """A Movella DOT export exactly as the app writes it: metadata lines, the header, rows with
    SampleTimeFine in microseconds (here wrapping past 2^32), deg/s, m/s^2, a.u., Status."""
    t = np.arange(n) / rate
    gyr = np.stack([np.sin(t), 0.5 * np.cos(2 * t), 0.1 * t], axis=1)  # rad/s
    acc = np.tile([0.2, 0.1, 9.79], (n, 1))
    quats = quat_from_matrix(exp3(np.stack([0.1 * t, 0.2 * np.sin(t), 0 * t], axis=1)))
    ticks = (start_us + np.round(t * 1e6)).astype(np.int64) % 2**32
    lines = ["DOT Serial,D422CD0045A1", "Firmware,2.6.0", ""] if metadata else []
    lines.append("PacketCounter,SampleTimeFine,Quat_W,Quat_X,Quat_Y,Quat_Z,Acc_X,Acc_Y,Acc_Z,"
                 "Gyr_X,Gyr_Y,Gyr_Z,Mag_X,Mag_Y,Mag_Z,Status")
    for k in range(n):
        cells = [*quats[k], *acc[k], *np.degrees(gyr[k])]
        lines.append(",".join([str(k), str(ticks[k]), *(repr(float(c)) for c in cells),
                               "0.31", "-0.12", "0.94", "0"]))
    path.write_text("\n".join(lines) + "\n")
    return t, gyr, acc, quats


def test_movella_dot_export_in_si_units(tmp_path):
    t, gyr, acc, quats = _dot_file(tmp_path / "D422CD0045A1_20240101.csv")
    rec = read_movella_dot_csv(tmp_path / "D422CD0045A1_20240101.csv")
    s = rec.sensor
    np.testing.assert_allclose(rec.time, t, atol=1e-6)  # microseconds, unwrapped past 2^32
    np.testing.assert_allclose(s.gyr, gyr, atol=1e-9)  # deg/s in the file
    np.testing.assert_allclose(s.acc, acc)
    np.testing.assert_allclose(s.quat, quats, atol=1e-12)
    assert s.mag.shape == (240, 3) and rec.rate_hz == pytest.approx(120.0, rel=1e-4)  # us ticks


def test_movella_dot_app_export_with_its_trailing_commas(tmp_path):
    """The DOT app's quirk, kept byte for byte: every line ends with a comma (the header
    ``...,Status,``), a row's cells are separated by ", " (``0, 3629233986, ..., 0, ``), CRLF."""
    t, gyr, acc, quats = _dot_file(tmp_path / "plain.csv")
    lines = (tmp_path / "plain.csv").read_text().splitlines()
    k = next(i for i, ln in enumerate(lines) if ln.startswith("PacketCounter"))
    app = lines[:k] + [lines[k] + ","] + [", ".join(ln.split(",")) + ", " for ln in lines[k + 1:]]
    path = tmp_path / "app.csv"
    path.write_bytes(("\r\n".join(app) + "\r\n").encode())
    assert path.read_bytes().splitlines()[k + 1].endswith(b", 0, ")
    rec = read_movella_dot_csv(path)
    np.testing.assert_allclose(rec.time, t, atol=1e-6)
    np.testing.assert_allclose(rec.sensor.gyr, gyr, atol=1e-9)
    np.testing.assert_allclose(rec.sensor.quat, quats, atol=1e-12)
    assert rec.header["world"] == "movella-dot"  # pipeline ik turns its z-up world itself


def test_movella_dot_sdk_export_with_euler_angles_and_extra_columns(tmp_path):
    """The SDK's column set: Euler angles (deg; R = Rz(yaw) Ry(pitch) Rx(roll)) instead of the
    quaternion, free acceleration and UTC columns (noted as not used)."""
    from pipeline.rotations import matrix_from_euler_zyx

    n, rate = 120, 60.0
    t = np.arange(n) / rate
    eul = np.stack([0.3 * np.sin(t), 0.2 * t, 0.5 + 0 * t], axis=1)  # roll, pitch, yaw (rad)
    lines = ["PacketCounter,SampleTimeFine,UTC_Nano,Euler_X,Euler_Y,Euler_Z,FreeAcc_X,FreeAcc_Y,"
             "FreeAcc_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z,Status"]
    for k in range(n):
        cells = [k, int(1000 + t[k] * 1e6), 5, *np.degrees(eul[k]), 0, 0, 0, 0.1, 0.2, 9.8, 1.0,
                 2.0, 3.0, 0]
        lines.append(",".join(str(c) for c in cells))
    path = tmp_path / "sdk.csv"
    path.write_text("\n".join(lines) + "\n")
    rec = read_movella_dot_csv(path)
    R = matrix_from_euler_zyx(eul[:, ::-1])
    np.testing.assert_allclose(np.abs(np.sum(rec.sensor.quat * quat_from_matrix(R), axis=1)), 1.0,
                               atol=1e-9)
    assert any("not used" in n and "FreeAcc_X" in n and "UTC_Nano" in n for n in rec.notes)


def test_movella_dot_refuses_a_column_it_does_not_know(tmp_path):
    _dot_file(tmp_path / "a.csv", metadata=False)
    text = (tmp_path / "a.csv").read_text().splitlines()
    text[0] = text[0].replace("Status", "Temperature")
    (tmp_path / "b.csv").write_text("\n".join(text) + "\n")
    with pytest.raises(InputError, match=r"b.csv.*\['Temperature'\] are not Movella DOT"):
        read_movella_dot_csv(tmp_path / "b.csv")


def test_movella_dot_refuses_a_file_without_its_header(tmp_path):
    p = tmp_path / "x.csv"
    p.write_text("time,a\n0,1\n")
    with pytest.raises(InputError, match="PacketCounter"):
        read_movella_dot_csv(p)


def test_ximu3_folder_of_the_real_recording():
    if not XIMU3.exists():
        pytest.skip("../shared/data/ximu3_lower_body not present")
    rec = read_ximu3_folder(XIMU3 / "pelvis 64F0EDBF (UDP)")
    s = rec.sensor
    n = rec.time.size
    assert n == 900 and 49 < rec.rate_hz < 51
    # still for the first second: gravity in m/s^2 (the file's g times 9.80665), gyro < 3 deg/s
    still = slice(0, 40)
    assert np.linalg.norm(s.acc[still], axis=1).mean() == pytest.approx(G, rel=0.02)
    assert np.degrees(np.linalg.norm(s.gyr[still], axis=1)).max() < 3.0
    assert s.quat.shape == (n, 4) and s.mag.shape == (n, 3)  # magnetometer onto 50 Hz
    # the device's own fusion agrees with its accelerometer at rest (z up)
    from pipeline.rotations import matrix_from_quat

    up = matrix_from_quat(s.quat[:40])[:, 2, :]  # world z in the sensor frame
    a = s.acc[:40] / np.linalg.norm(s.acc[:40], axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(np.sum(up * a, axis=1), -1, 1))).max() < 3.0


def test_a_dot_export_saved_with_decimal_commas_reads_alike(tmp_path):
    """The same export saved in a decimal-comma locale (';' between cells, ',' in numbers; the
    issue: refused as 'has 14 fields, expected 1', not naming the cause): read alike, noted."""
    t, gyr, acc, quats = _dot_file(tmp_path / "a.csv")
    lines = (tmp_path / "a.csv").read_text().splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("PacketCounter"))
    comma = lines[:start] + [line.replace(",", ";").replace(".", ",") for line in lines[start:]]
    (tmp_path / "b.csv").write_text("\n".join(comma) + "\n")
    a, b = read_movella_dot_csv(tmp_path / "a.csv"), read_movella_dot_csv(tmp_path / "b.csv")
    for k in ("quat", "gyr", "acc", "mag"):
        np.testing.assert_array_equal(getattr(b.sensor, k), getattr(a.sensor, k))
    assert any("decimal commas" in n for n in b.notes)
