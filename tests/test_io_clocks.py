"""pipeline.io.clocks: one-sensor recordings on their own clocks put on one time base."""

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.clocks import align_clocks, device_time
from pipeline.io.recording import Recording


def _rec(t, w=1.0, header=None):
    gyr = np.stack([w * np.sin(t), np.cos(t), 0 * t], axis=1)
    return Recording.single("s", t, gyr=gyr, acc=np.tile([0, 0, 9.81], (t.size, 1)),
                            header=header)  # fmt: skip


def test_devices_a_few_ms_apart_are_aligned_by_time_stamp():
    t = np.arange(500) / 100.0
    rec = align_clocks({"femur_r_imu": _rec(t), "tibia_r_imu": _rec(t + 0.004)})
    assert rec.time[0] == 0.0 and rec.rate_hz == pytest.approx(100.0)
    # the common span starts at the later device: the femur is resampled 4 ms later
    np.testing.assert_allclose(rec.sensors["femur_r_imu"].gyr[:, 0], np.sin(rec.time + 0.004),
                               atol=2e-4)  # fmt: skip
    np.testing.assert_allclose(rec.sensors["tibia_r_imu"].gyr[:, 0], np.sin(rec.time + 0.004),
                               atol=1e-9)  # fmt: skip
    assert any("clocks aligned by time stamp" in n for n in rec.notes)


def test_a_clock_kept_in_the_header_and_one_that_wrapped():
    t = np.arange(300) / 100.0
    a = _rec(t, header={"clock_start_s": "100.0", "clock_wrap_s": "4294.967296"})
    b = _rec(t, header={"clock_start_s": repr(100.5 + 4294.967296), "clock_wrap_s": "4294.967296"})
    assert device_time(b, reference=100.0)[0] == pytest.approx(100.5)
    rec = align_clocks({"pelvis_imu": a, "femur_r_imu": b})
    assert rec.time[-1] == pytest.approx(2.49)
    np.testing.assert_allclose(rec.sensors["pelvis_imu"].gyr[:, 0], np.sin(rec.time + 0.5),
                               atol=1e-9)  # fmt: skip


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
        "d/tibia.txt: 3 dropped packet(s) (PacketCounter jumps)",)}  # fmt: skip
    assert "d/tibia.txt: 3 dropped packet(s) (PacketCounter jumps)" in rec.notes
