"""pipeline.process.still: the still windows where a calibration pose can be read, anywhere in
the recording, on raw signals and on orientations alone; on the real walk's standing start and
end."""

import numpy as np
import pytest
from _helpers import s02_cut

from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.still import MIN_WINDOW_S, resting, still_windows
from pipeline.rotations import exp3, quat_from_matrix

RATE = 100.0


def _sensor(moving: np.ndarray, seed: int) -> SensorSignals:
    """A sensor at rest (gravity, noise) except where ``moving`` (turning at 2 rad/s)."""
    rng = np.random.default_rng(seed)
    n = len(moving)
    gyr = rng.normal(0, 0.01, (n, 3))
    gyr[moving, 0] += 2.0
    acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0, 0.05, (n, 3))
    return SensorSignals(gyr=gyr, acc=acc)


def test_windows_are_where_every_sensor_rests_long_enough():
    n = 1000
    t = np.arange(n) / RATE
    a, b = np.zeros(n, bool), np.zeros(n, bool)
    a[200:500] = True  # the first sensor moves 2-5 s
    b[450:700] = True  # the second 4.5-7 s
    b[900:930] = True  # and 0.3 s near the end: a window of 0.7 s before, too short after
    rec = Recording(t, RATE, {"femur_r_imu": _sensor(a, 1), "tibia_r_imu": _sensor(b, 2)})
    spans = [(w.start, w.stop) for w in still_windows(rec)]
    assert len(spans) == 3
    (a0, a1), (b0, b1), (c0, c1) = spans
    assert a0 == 0 and 180 <= a1 <= 200  # the start, up to the low-pass's reach
    assert 700 <= b0 <= 715 and 885 <= b1 <= 900
    assert 930 <= c0 <= 945 and c1 == n and (c1 - c0) / RATE >= MIN_WINDOW_S
    assert still_windows(rec, ["femur_r_imu"])[1].start >= 500  # one sensor's own windows


def test_a_sensor_with_orientations_only_rests_where_they_stop_turning():
    n = 600
    t = np.arange(n) / RATE
    angle = np.where(t < 2.0, 0.0, np.minimum(t - 2.0, 1.0) * 1.5)  # turns 2-3 s
    q = quat_from_matrix(exp3(np.outer(angle, [0.0, 1.0, 0.0])))
    still = resting(SensorSignals(quat=q), RATE)
    assert still[:180].all() and not still[210:290].any() and still[330:].all()
    assert resting(SensorSignals(), RATE) is None
    rec = Recording(t, RATE, {"pelvis_imu": SensorSignals(quat=q)})
    assert [round(w.t0) for w in still_windows(rec)] == [0, 3]


def test_a_recording_with_nothing_to_judge_has_no_window():
    t = np.arange(100) / RATE
    assert still_windows(Recording(t, RATE, {"pelvis_imu": SensorSignals()})) == []


@pytest.mark.dataset
def test_the_real_walks_standing_start_and_end():
    """S02 stands 0-11 s and from 22 s (README); its walk never rests on all seven sensors."""
    rec = s02_cut(0)
    if rec is None:
        pytest.skip("no S02 data")
    spans = [(round(w.t0, 1), round(w.t1, 1)) for w in still_windows(rec)]
    assert spans == [(0.0, 10.9), (22.1, 25.0)]
