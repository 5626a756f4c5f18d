"""pipeline.io.imu_folder: a folder of raw IMU files on one clock, named as our sensors."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.imu_csv import write_imu_csv
from pipeline.io.imu_folder import read_imu_folder
from pipeline.io.recording import Recording

XIMU3 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ximu3_lower_body"


def _write(folder, name, t, w=1.0):
    gyr = np.stack([w * np.sin(t), np.cos(t), 0 * t], axis=1)
    acc = np.tile([0.0, 0.0, 9.81], (t.size, 1))
    write_imu_csv(folder / f"{name}.csv", Recording.single(name, t, gyr=gyr, acc=acc))
    return gyr


def test_devices_a_few_ms_apart_are_aligned_by_time_stamp(tmp_path):
    t = np.arange(500) / 100.0
    _write(tmp_path, "femur_r_imu", t)
    _write(tmp_path, "right_tibia_imu", t + 0.004)  # pipeline simulate's name; 4 ms later
    (tmp_path / "notes.txt.csv").write_text("not,an,imu\n")
    rec = read_imu_folder(tmp_path)
    assert set(rec.sensor_names) == {"femur_r_imu", "tibia_r_imu"}
    assert rec.time[0] == 0.0 and rec.rate_hz == pytest.approx(100.0)
    # the common span starts at the later device: the femur is resampled 4 ms later
    shifted = np.sin(rec.time + 0.004)
    np.testing.assert_allclose(rec.sensors["femur_r_imu"].gyr[:, 0], shifted, atol=2e-4)
    np.testing.assert_allclose(rec.sensors["tibia_r_imu"].gyr[:, 0], np.sin(rec.time + 0.004),
                               atol=1e-9)  # fmt: skip
    assert any("clocks aligned by time stamp" in n for n in rec.notes)


def test_sensor_map_by_device_id_and_refusals(tmp_path):
    t = np.arange(300) / 100.0
    _write(tmp_path, "dev_00B421AF", t)
    _write(tmp_path, "dev_00B4227B", t)
    rec = read_imu_folder(tmp_path, {"pelvis_imu": "00B421AF", "femur_r_imu": "4227B"})
    assert set(rec.sensor_names) == {"pelvis_imu", "femur_r_imu"}
    with pytest.raises(InputError, match="no file for tibia_r_imu"):
        read_imu_folder(tmp_path, {"tibia_r_imu": "FFFF"})
    with pytest.raises(InputError, match="no IMU recording with a sensor name"):
        read_imu_folder(tmp_path)
    _write(tmp_path / ".." / tmp_path.name, "femur_r_imu", t[:150] + 10.0)  # no overlap in time
    with pytest.raises(InputError, match="do not overlap"):
        read_imu_folder(tmp_path, {"pelvis_imu": "00B421AF"})


def test_different_rates_are_refused(tmp_path):
    _write(tmp_path, "femur_r_imu", np.arange(300) / 100.0)
    _write(tmp_path, "tibia_r_imu", np.arange(300) / 120.0)
    with pytest.raises(InputError, match="rate"):
        read_imu_folder(tmp_path)


def test_the_real_ximu3_folder_is_seven_sensors_on_one_clock():
    if not XIMU3.exists():
        pytest.skip("../shared/data/ximu3_lower_body not present")
    rec = read_imu_folder(XIMU3)
    assert set(rec.sensor_names) == {"pelvis_imu", "femur_r_imu", "tibia_r_imu", "calcn_r_imu",
                                     "femur_l_imu", "tibia_l_imu", "calcn_l_imu"}  # fmt: skip
    assert 18.0 < rec.time[-1] < 18.7 and np.allclose(np.diff(rec.time), 1 / rec.rate_hz)
    for s in rec.sensors.values():
        assert s.gyr.shape == s.acc.shape == s.mag.shape == (rec.time.size, 3)
        assert np.allclose(np.linalg.norm(s.quat, axis=1), 1.0)
