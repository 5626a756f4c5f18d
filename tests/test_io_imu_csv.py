"""Raw IMU CSV (pipeline.io.imu_csv): round trips and every refusal on purpose."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import imu_recording

from pipeline.errors import InputError
from pipeline.io.checks import make_quaternions_continuous
from pipeline.io.imu_csv import read_imu_csv, write_imu_csv
from pipeline.io.recording import Recording
from pipeline.rotations import exp3, quat_from_matrix

HEADER = "time,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z"


def _rec(n: int = 300, rate: float = 100.0, quat: bool = True) -> Recording:
    t = np.arange(n) / rate
    w = np.column_stack([2.0 * np.sin(2 * np.pi * t), 0.5 * np.cos(t), 0.2 + 0 * t])  # rad/s
    a = np.column_stack([0.5 * np.sin(t), 9.81 + 0.3 * np.cos(5 * t), -0.2 + 0 * t])  # m/s^2
    q = None
    if quat:
        q = make_quaternions_continuous(quat_from_matrix(exp3(t[:, None] * [0.3, -0.6, 1.0])))[0]
    return imu_recording(time=t, gyr=w, acc=a, quat=q)


def _csv(path, rows, header=HEADER):
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


def _lines(rec: Recording):
    cols = [rec.time[:, None], rec.gyr, rec.acc] + ([rec.quat] if rec.quat is not None else [])
    return [",".join(f"{v:.12g}" for v in row) for row in np.hstack(cols)]


@pytest.mark.parametrize("quat", [True, False])
def test_round_trip(tmp_path, quat):
    rec = _rec(quat=quat)
    p = write_imu_csv(tmp_path / "imu.csv", rec)
    head = p.read_text().splitlines()[0]
    assert head == HEADER + (",quat_w,quat_x,quat_y,quat_z" if quat else "")
    back = read_imu_csv(p, rate_hz=100.0)
    np.testing.assert_array_equal(back.time, rec.time)
    np.testing.assert_array_equal(back.gyr, rec.gyr)
    np.testing.assert_array_equal(back.acc, rec.acc)
    if quat:
        np.testing.assert_allclose(back.quat, rec.quat, atol=1e-15)
    else:
        assert back.quat is None
    assert back.notes == () and back.rate_hz == pytest.approx(100.0)
    assert back.source == p


def test_columns_in_any_order_and_extra_column_noted(tmp_path):
    rec = _rec(50, quat=False)
    rows = [
        ",".join(f"{v:.12g}" for v in (*rec.acc[i], rec.time[i], *rec.gyr[i], 20.5))
        for i in range(50)
    ]
    p = _csv(tmp_path / "a.csv", rows, header="acc_x,acc_y,acc_z,time,gyr_x,gyr_y,gyr_z,temp")
    back = read_imu_csv(p)
    np.testing.assert_allclose(back.acc, rec.acc, rtol=1e-11)
    np.testing.assert_allclose(back.gyr, rec.gyr, rtol=1e-11, atol=1e-12)
    assert any("ignored column(s) temp" in n for n in back.notes)


def test_empty_file_and_header_only(tmp_path):
    (tmp_path / "e.csv").write_text("")
    with pytest.raises(InputError, match="file is empty"):
        read_imu_csv(tmp_path / "e.csv")
    (tmp_path / "h.csv").write_text(HEADER + "\n")
    with pytest.raises(InputError, match="no data rows"):
        read_imu_csv(tmp_path / "h.csv")


def test_truncated_mid_row(tmp_path):
    p = write_imu_csv(tmp_path / "a.csv", _rec(40))
    text = p.read_text()
    p.write_text(text[: len(text) - 60])
    with pytest.raises(InputError, match=r"row 39 \(line 41\) has \d+ fields, expected 11 \(file"):
        read_imu_csv(p)


def test_missing_columns_listed(tmp_path):
    p = _csv(
        tmp_path / "a.csv", ["0,1,2,3,4", "0.01,1,2,3,4"], header="time,gyr_x,gyr_y,acc_x,acc_y"
    )
    with pytest.raises(
        InputError, match="field header: missing column\\(s\\) gyr_z, acc_z; expected"
    ):
        read_imu_csv(p)
    p2 = _csv(tmp_path / "b.csv", ["0,1,1,1,0,0,9.8,1,0"], header=HEADER + ",quat_w,quat_x")
    with pytest.raises(InputError, match="incomplete quaternion"):
        read_imu_csv(p2)


def test_not_a_number_names_row_and_column(tmp_path):
    rec = _rec(10, quat=False)
    rows = _lines(rec)
    rows[4] = rows[4].replace(rows[4].split(",")[5], "abc", 1)
    with pytest.raises(InputError, match=r"field acc_y: 'abc' at row 4 \(line 6\) is not a number"):
        read_imu_csv(_csv(tmp_path / "a.csv", rows))


def test_unsorted_and_repeated_time(tmp_path):
    rec = _rec(20, quat=False)
    rows = _lines(rec)
    rows[7], rows[8] = rows[8], rows[7]
    with pytest.raises(InputError, match=r"time stamps not sorted: 0\.07 s at row 8 \(line 10\)"):
        read_imu_csv(_csv(tmp_path / "a.csv", rows))
    rows = _lines(rec)
    rows[3] = rows[2]
    with pytest.raises(InputError, match=r"repeated time stamp 0\.02 s at row 3 \(line 5\)"):
        read_imu_csv(_csv(tmp_path / "b.csv", rows))


def test_rate_checked_when_declared(tmp_path):
    p = write_imu_csv(tmp_path / "a.csv", _rec(50))
    with pytest.raises(InputError, match="declared rate 200 Hz but the time stamps give 100 Hz"):
        read_imu_csv(p, rate_hz=200.0)


def test_short_gap_interpolated_and_reported_long_left_missing(tmp_path):
    rec = _rec(300)
    gyr = rec.gyr.copy()
    gyr[100:104] = np.nan
    quat = rec.quat.copy()
    quat[200:205] = np.nan
    holed = imu_recording(time=rec.time, gyr=gyr, acc=rec.acc, quat=quat)
    back = read_imu_csv(write_imu_csv(tmp_path / "a.csv", holed))
    # linear interpolation of a smooth signal over 40 ms: close to the truth, not equal
    assert np.abs(back.gyr[100:104] - rec.gyr[100:104]).max() < 0.05
    np.testing.assert_allclose(back.quat, rec.quat, atol=1e-12)  # constant-rate: slerp exact
    assert any(
        "field gyr: filled 4 missing sample(s) from t=1 s to t=1.03 s" in n for n in back.notes
    )
    assert any("field quat: filled 5 missing sample(s)" in n and "slerp" in n for n in back.notes)
    acc = rec.acc.copy()
    acc[10:40] = np.nan
    p = write_imu_csv(tmp_path / "b.csv", imu_recording(time=rec.time, gyr=rec.gyr, acc=acc))
    long = read_imu_csv(p)  # a dropout: never bridged, noted, the rest read
    assert np.isnan(long.acc[10:40]).all() and np.isfinite(long.acc[40:]).all()
    assert any("field acc: missing 30 sample(s) (0.3 s)" in n and "not bridged" in n
               for n in long.notes)
    back2 = read_imu_csv(p, max_gap_s=0.5)
    assert np.isfinite(back2.acc).all()


def test_non_unit_and_zero_quaternions(tmp_path):
    rec = _rec(30)
    q = rec.quat.copy()
    q[5] *= 1.5
    p = write_imu_csv(tmp_path / "a.csv", imu_recording(rec.time, rec.gyr, rec.acc, q))
    with pytest.raises(
        InputError, match=r"field quat: not unit quaternions \(norm 1\.5 at row 5 \(line 7\)"
    ):
        read_imu_csv(p)
    q = rec.quat.copy()
    q[6] = 0
    p = write_imu_csv(tmp_path / "b.csv", imu_recording(rec.time, rec.gyr, rec.acc, q))
    with pytest.raises(InputError, match=r"zero quaternion at row 6"):
        read_imu_csv(p)


def test_gyro_in_deg_per_s_and_acc_in_g_refused(tmp_path):
    rec = _rec(200, quat=False)
    p = write_imu_csv(tmp_path / "a.csv", imu_recording(rec.time, np.degrees(rec.gyr), rec.acc))
    with pytest.raises(InputError, match="field gyr: .*looks like deg/s.*multiply deg/s by pi/180"):
        read_imu_csv(p)
    p = write_imu_csv(tmp_path / "b.csv", imu_recording(rec.time, rec.gyr, rec.acc / 9.81))
    with pytest.raises(InputError, match=r"field acc: median \|a\| is 0\.99\d, close to 1.*in g"):
        read_imu_csv(p)


def test_write_is_atomic_on_bad_input(tmp_path):
    p = tmp_path / "a.csv"
    p.write_text("keep")
    bad = imu_recording(time=np.arange(5.0), gyr=np.zeros((4, 3)), acc=np.zeros((5, 3)))
    with pytest.raises(ValueError, match="4 rows, time has 5"):
        write_imu_csv(p, bad)
    assert p.read_text() == "keep"
    assert [x.name for x in tmp_path.iterdir()] == ["a.csv"]


def test_time_in_milliseconds_refused(tmp_path):
    rec = _rec()
    p = write_imu_csv(tmp_path / "ms.csv", imu_recording(1000 * rec.time, rec.gyr, rec.acc))
    with pytest.raises(InputError, match="milliseconds"):
        read_imu_csv(p)
