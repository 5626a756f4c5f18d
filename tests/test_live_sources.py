"""pipeline.live.sources: a recording replayed as live streams, and Lab Streaming Layer streams
read (pylsl's outlets and inlets in one process): names mapped, channels checked, time stamps."""

import threading
import time

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.recording import Recording, SensorSignals
from pipeline.live.sources import ReplaySource, stream_name_map


def _rec(n=300, rate=100.0):
    t = np.arange(n) / rate
    gyr = np.stack([np.sin(t), np.cos(t), t], axis=1)
    sensors = {name: SensorSignals(gyr=gyr + k, acc=np.tile([0.0, 0.0, 9.81], (n, 1)))
               for k, name in enumerate(("pelvis_imu", "femur_r_imu"))}
    return Recording(t, rate, sensors)


def test_a_replay_as_fast_as_read_gives_every_sample_once_without_the_missing_ones():
    rec = _rec()
    gyr = rec.sensors["femur_r_imu"].gyr.copy()
    gyr[100:110] = np.nan  # a gap in the recording: those samples are not sent
    rec = rec.with_sensors({**rec.sensors, "femur_r_imu": rec.sensors["femur_r_imu"].replace(
        gyr=gyr)})
    source, got = ReplaySource(rec, np.inf), {"pelvis_imu": [], "femur_r_imu": []}
    while (chunks := source.read()) is not None:
        for c in chunks:
            got[c.sensor].append(c.time)
    np.testing.assert_array_equal(np.concatenate(got["pelvis_imu"]), rec.time)
    femur = np.concatenate(got["femur_r_imu"])
    assert len(femur) == 290 and not np.isin(rec.time[100:110], femur).any()


def test_a_replay_in_real_time_paces_by_the_clock():
    now = [0.0]
    source = ReplaySource(_rec(), 2.0, clock=lambda: now[0],
                          sleep=lambda s: now.__setitem__(0, now[0] + s))
    assert source.read()[0].time.tolist() == [0.0]  # the first sample at once
    now[0] = 0.5  # half a second later, at twice real time: one second of recording
    assert source.read()[0].time[-1] == pytest.approx(1.0)
    assert source.read() == [] and now[0] > 0.5  # nothing due: it waited


def test_stream_names_are_mapped_like_a_recordings_sensors():
    names = ["Right Upper Leg 64F61C2E", "pelvis", "DOT-3"]
    out = stream_name_map(names, {"calcn_l_imu": "DOT-3", "femur_r_imu": "64F61C2E"})
    assert out == {"DOT-3": "calcn_l_imu", "Right Upper Leg 64F61C2E": "femur_r_imu",
                   "pelvis": "pelvis_imu"}
    with pytest.raises(InputError, match="no LSL streams match 'X9'"):
        stream_name_map(names, {"tibia_r_imu": "X9"})


def test_lsl_outlets_to_inlets_in_one_process():
    """A recording served as LSL outlets (``serve_outlets``) and read back by ``LslSource``: the
    streams found by name, their channels by label, the samples in order on LSL's clock; a
    stream with other channels refused naming it."""
    pylsl = pytest.importorskip("pylsl")
    from pipeline.live.sources import LslSource, serve_outlets

    rec, done = _rec(n=2000), threading.Event()  # 20 s served; stopped once read
    server = threading.Thread(target=serve_outlets, args=(rec,),
                              kwargs={"prefix": "test-a/", "stop": done.is_set}, daemon=True)
    server.start()
    try:
        source = LslSource(resolve_s=5.0, prefix="test-a/")
        assert sorted(source.names) == ["femur_r_imu", "pelvis_imu"] and source.rate_hz == 100.0
        got, t0 = [], time.monotonic()
        while time.monotonic() - t0 < 3.0 and sum(len(c.time) for c in got) < 100:
            got += [c for c in source.read() if c.sensor == "femur_r_imu"]
        stamps = np.concatenate([c.time for c in got])
        gyr = np.concatenate([c.signals["gyr"] for c in got])
        assert len(stamps) >= 50 and np.all(np.diff(stamps) > 0)
        k = np.argmin(np.abs(rec.sensors["femur_r_imu"].gyr[:, 2] - gyr[0, 2]))
        np.testing.assert_allclose(gyr[:10], rec.sensors["femur_r_imu"].gyr[k:k + 10], atol=1e-5)
        source.close()
    finally:
        done.set()
        server.join(timeout=5)
    info = pylsl.StreamInfo("test-b/tibia_r_imu", "IMU", 4, 100.0, "float32", "test-b")
    channels = info.desc().append_child("channels")
    for label in ("gyr_x", "gyr_y", "gyr_z", "temperature"):
        channels.append_child("channel").append_child_value("label", label)
    outlet = pylsl.StreamOutlet(info)
    with pytest.raises(InputError, match="stream 'tibia_r_imu'.*temperature"):
        LslSource(resolve_s=5.0, prefix="test-b/")
    del outlet
