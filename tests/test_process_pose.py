"""pipeline.process.pose: the calibration pose, and the accelerometer's vertical at a still
start."""

import numpy as np

from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.pose import MIN_STILL_S, still_gravity
from pipeline.rotations import exp3


def test_the_still_starts_vertical_is_the_mean_accelerometer_direction():
    t = np.arange(300) / 100.0
    R = exp3(np.array([0.3, -0.2, 1.0]))
    g = R.T @ np.array([0.0, 0.0, 9.81])  # gravity in the sensor frame of a tilted sensor
    rng = np.random.default_rng(1)
    acc = np.tile(g, (300, 1)) + rng.normal(0, 0.05, (300, 3))
    gyr = rng.normal(0, 0.005, (300, 3))
    gyr[150:] += 1.0  # moves after 1.5 s
    walking = gyr.copy()
    walking[:] += 1.0  # never still
    rec = Recording(t, 100.0, {"femur_r_imu": SensorSignals(gyr=gyr, acc=acc),
                               "tibia_r_imu": SensorSignals(gyr=walking, acc=acc),
                               "pelvis_imu": SensorSignals(quat=np.tile([1.0, 0, 0, 0], (300, 1)))})
    out = still_gravity(rec, ["right_femur", "right_tibia", "pelvis"])
    assert set(out) == {"right_femur"}  # still long enough (>= MIN_STILL_S), raw signals
    assert np.degrees(np.arccos(out["right_femur"] @ (g / 9.81))) < 0.2
    assert MIN_STILL_S <= 1.5
