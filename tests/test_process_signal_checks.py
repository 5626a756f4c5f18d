"""pipeline.process.signal_checks: the statistics a sensor's own checks judge (the share of
saturated samples, the speed against the neighbours'), on signals whose answer is known."""

import numpy as np

from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.check_context import CheckContext
from pipeline.process.signal_checks import MAX_SATURATED, saturation, speed_ratio

RATE = 100.0
T = np.arange(2000) / RATE


def _signals(w: np.ndarray) -> SensorSignals:
    """A sensor turning at ``w`` (N,) rad/s about its x axis, at rest on gravity."""
    gyr = np.column_stack([w, 0.01 * np.sin(T), np.zeros_like(w)])
    return SensorSignals(gyr=gyr, acc=np.tile([0.0, 0.0, 9.81], (len(w), 1)))


def test_a_smooth_swing_is_not_saturated_and_a_clipped_one_is_by_its_share():
    swing = 5.0 * np.sin(2 * np.pi * T)  # peaks 286 deg/s, rounded tops
    assert saturation(_signals(swing), RATE) is None
    limit = np.radians(250.0)
    clipped = np.clip(swing, -limit, limit)  # a 250 deg/s range: flat tops
    share, what = saturation(_signals(clipped), RATE)
    held = np.mean(np.abs(clipped) >= limit * (1 - 1e-9))
    assert abs(share - held) < 0.01 and share > MAX_SATURATED and "held at 250 deg/s" in what


def test_a_sensor_still_among_moving_neighbours_turns_at_a_small_share_of_their_speed():
    swing = 3.0 * np.sin(2 * np.pi * T)
    rec = Recording(T, RATE, {"femur_r_imu": _signals(swing), "tibia_r_imu": _signals(0 * T),
                              "calcn_r_imu": _signals(1.2 * swing)})
    ctx = CheckContext.of_recording(rec)
    ratio, slowest, near = speed_ratio("tibia_r_imu", ctx)
    assert ratio < 0.01 and sorted(near) == ["calcn_r_imu", "femur_r_imu"]
    assert abs(slowest - np.median(np.abs(swing))) < 0.05  # the femur's median speed
    still = Recording(T, RATE, {"femur_r_imu": _signals(0 * T), "tibia_r_imu": _signals(swing)})
    assert speed_ratio("tibia_r_imu", CheckContext.of_recording(still)) is None  # still thigh
