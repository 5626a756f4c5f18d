"""pipeline.io.clocks: one-sensor recordings on their own clocks put on one time base."""

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.clocks import align_clocks, device_time
from pipeline.io.recording import Recording


def _rec(t, w=1.0, header=None):
    gyr = np.stack([w * np.sin(t), np.cos(t), 0 * t], axis=1)
    return Recording.single("s", t, gyr=gyr, acc=np.tile([0, 0, 9.81], (t.size, 1)),
                            header=header)


def test_devices_a_few_ms_apart_are_aligned_by_time_stamp():
    t = np.arange(500) / 100.0
    rec = align_clocks({"femur_r_imu": _rec(t), "tibia_r_imu": _rec(t + 0.004)})
    assert rec.time[0] == 0.0 and rec.rate_hz == pytest.approx(100.0)
    # both devices saw sin(device time); the grid's phase is the later one's (the earlier's
    # 4 ms before it, less than a period, are not a sample of the grid): the femur resampled
    np.testing.assert_allclose(rec.sensors["femur_r_imu"].gyr[:-1, 0],
                               np.sin(rec.time[:-1] + 0.004), atol=2e-4)  # its last: held
    np.testing.assert_allclose(rec.sensors["tibia_r_imu"].gyr[:, 0], np.sin(rec.time + 0.004),
                               atol=1e-9)
    assert np.isfinite(rec.sensors["tibia_r_imu"].gyr).all()
    assert any("clocks aligned by time stamp" in n for n in rec.notes)
    assert not any("missing there" in n for n in rec.notes)


def test_a_clock_kept_in_the_header_and_one_that_wrapped():
    """The grid spans both devices; each is missing (NaN, never bridged) where it has no
    samples: the second starts 0.5 s late, the first ends 0.5 s early."""
    t = np.arange(300) / 100.0
    a = _rec(t, header={"clock_start_s": "100.0", "clock_wrap_s": "4294.967296"})
    b = _rec(t, header={"clock_start_s": repr(100.5 + 4294.967296), "clock_wrap_s": "4294.967296"})
    assert device_time(b, reference=100.0)[0] == pytest.approx(100.5)
    rec = align_clocks({"pelvis_imu": a, "femur_r_imu": b})
    assert rec.time[-1] == pytest.approx(3.49)
    pelvis, femur = rec.sensors["pelvis_imu"].gyr[:, 0], rec.sensors["femur_r_imu"].gyr[:, 0]
    np.testing.assert_allclose(pelvis[:300], np.sin(rec.time[:300]), atol=1e-9)
    np.testing.assert_allclose(femur[50:], np.sin(rec.time[50:] - 0.5), atol=1e-9)
    assert np.isnan(pelvis[300:]).all() and np.isnan(femur[:50]).all()
    assert "pelvis_imu ends 0.50 s early: missing there, not bridged" in rec.notes
    assert "femur_r_imu starts 0.50 s late: missing there, not bridged" in rec.notes


def test_a_sensors_own_clock_jump_is_missing_not_interpolated():
    """Rows missing from one sensor's file (its stamps jump 0.5 s): NaN there, noted."""
    t = np.arange(500) / 100.0
    holed = np.r_[t[:200], t[250:]]
    rec = align_clocks({"femur_r_imu": _rec(t), "tibia_r_imu": _rec(holed)})
    tibia = rec.sensors["tibia_r_imu"].gyr[:, 0]
    assert np.isnan(tibia[200:250]).all() and np.isfinite(np.delete(tibia, range(200, 250))).all()
    assert any(n.startswith("tibia_r_imu has no samples between t = 1.99 and 2.50 s")
               for n in rec.notes)


def test_different_rates_and_no_overlap_are_refused():
    with pytest.raises(InputError, match="rate"):
        align_clocks({"a": _rec(np.arange(300) / 100.0), "b": _rec(np.arange(300) / 120.0)})
    with pytest.raises(InputError, match="do not overlap"):
        align_clocks({"a": _rec(np.arange(300) / 100.0), "b": _rec(10 + np.arange(300) / 100.0)})


def test_each_sensor_keeps_its_own_files_notes():
    """The merged recording says which sensor a reader's repair concerns (the sensor table)."""
    t = np.arange(500) / 100.0
    noted = _rec(t).with_notes("d/tibia.txt: 3 dropped packet(s) (PacketCounter jumps)")
    rec = align_clocks({"femur_r_imu": _rec(t), "tibia_r_imu": noted})
    assert rec.sensor_notes == {"tibia_r_imu": (
        "d/tibia.txt: 3 dropped packet(s) (PacketCounter jumps)",)}
    assert "d/tibia.txt: 3 dropped packet(s) (PacketCounter jumps)" in rec.notes
