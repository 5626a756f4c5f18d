"""pipeline.live.store: the frames spooled to disk and read back as they went in; the live
orientations kept only while a calibration may need them."""

import numpy as np

from pipeline.io.recording import SensorSignals
from pipeline.live.aligner import Block
from pipeline.live.store import CaptureStore, ColumnSpool


def _block(t, with_mag=True):
    m = len(t)
    a = SensorSignals(gyr=np.tile(t[:, None], (1, 3)), acc=np.ones((m, 3)),
                      mag=np.full((m, 3), 2.0) if with_mag else None)
    b = SensorSignals(quat=np.tile([1.0, 0.0, 0.0, 0.0], (m, 1)))
    return Block(t, {"femur_r_imu": a, "pelvis_imu": b})


def test_frames_come_back_as_they_went_in_and_a_missing_signal_is_nan():
    store = CaptureStore(["femur_r_imu", "pelvis_imu"])
    R = {"own": {"pelvis_imu": np.tile(np.eye(3), (3, 1, 1))}}
    store.add(_block(np.arange(3) / 100.0), R)
    store.add(_block(np.arange(3, 5) / 100.0, with_mag=False), {})  # the magnetometer gone
    rec = store.recording(100.0, {"world": "xsens"})
    np.testing.assert_array_equal(rec.time, np.arange(5) / 100.0)
    np.testing.assert_array_equal(rec.sensors["femur_r_imu"].gyr[:, 0], rec.time)
    assert np.isnan(rec.sensors["femur_r_imu"].mag[3:]).all() and rec.header == {"world": "xsens"}
    assert store.live_rotations()["own"]["pelvis_imu"].shape == (3, 3, 3)
    store.forget_orientations()
    store.add(_block(np.array([0.05])), R)
    assert store.live_rotations() == {} and store.n == 6
    store.close()


def test_named_columns_a_block_lacks_are_nan():
    spool = ColumnSpool(["a", "b"])
    spool.append({"a": np.array([1.0, 2.0])}, 2)
    spool.append({}, 1)
    out = spool.read()
    np.testing.assert_array_equal(out["a"][:2], [1.0, 2.0])
    assert np.isnan(out["b"]).all() and np.isnan(out["a"][2])


def test_the_last_rows_read_back_alone():
    from pipeline.live.store import Spool

    spool = Spool(2)
    spool.append(np.arange(20.0).reshape(10, 2))
    assert np.array_equal(spool.read(3), np.arange(14.0, 20.0).reshape(3, 2))
    assert np.array_equal(spool.read(50), np.arange(20.0).reshape(10, 2))  # fewer than asked
    spool.append(np.array([[20.0, 21.0]]))  # still appends at the end after a partial read
    assert spool.read(1).tolist() == [[20.0, 21.0]] and spool.n == 11
    spool.close()
