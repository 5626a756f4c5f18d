"""pipeline.simulate.artefacts: soft tissue, wandering bias and the floor's field, applied so that
every signal stays consistent with the sensor's own motion."""

import numpy as np
import pytest

from pipeline.calibration.magnetometer import field_trust
from pipeline.rotations import log3
from pipeline.simulate.artefacts import Artefacts
from pipeline.simulate.model import GRAVITY, SensorNoise, simulate_trial


@pytest.fixture(scope="module")
def trials():
    kw = dict(motion="gait", duration_s=8.0, seed=3, standing_s=2.0, noise=SensorNoise.none())
    return simulate_trial(**kw), simulate_trial(artefacts=Artefacts(acc_bias_sd=0.0), **kw)


def test_the_signals_are_the_derivatives_of_the_sensors_own_pose(trials):
    """Noise-free: the gyroscope is the rate of the (soft-tissue-moved) orientation and the
    accelerometer the second derivative of its position less gravity, in its own frame."""
    _, real = trials
    for frame in ("right_femur_imu", "left_tibia_imu", "pelvis_imu"):
        imu = real.imus[frame]
        R, P, s = imu.rotation, imu.position, imu.recording.sensor
        w = log3(np.swapaxes(R[:-1], 1, 2) @ R[1:]) * 100.0  # body rate, mid-interval
        gyr_mid = 0.5 * (s.gyr[:-1] + s.gyr[1:]) - imu.gyro_bias
        assert np.sqrt(np.mean((w - gyr_mid)[250:] ** 2)) < 0.01, frame
        ddp = (P[2:] - 2 * P[1:-1] + P[:-2]) * 1e4
        f = np.einsum("nji,nj->ni", R[1:-1], ddp - GRAVITY)
        assert np.sqrt(np.mean((f - s.acc[1:-1])[250:] ** 2)) < 0.05, frame


def test_the_sensors_move_on_their_segments_during_the_motion_only(trials):
    ideal, real = trials
    for frame, lo, hi in (("right_femur_imu", 1.5, 5.0), ("right_tibia_imu", 0.5, 2.5)):
        rel = np.swapaxes(ideal.imus[frame].rotation, 1, 2) @ real.imus[frame].rotation
        turn = np.degrees(np.linalg.norm(log3(rel), axis=1))
        assert turn[:150].max() < 0.05  # the standing start: the calibration pose holds
        assert lo < np.sqrt(np.mean(turn[400:] ** 2)) < hi, (frame, turn[400:].std())


def test_the_floor_bends_the_feets_field_and_not_the_thighs():
    real = simulate_trial(motion="gait", duration_s=10.0, seed=1, standing_s=2.0,
                          artefacts=Artefacts())
    fields = {f: (i.recording.mag, i.rotation[:, 2, :]) for f, i in real.imus.items()}
    trust = field_trust(fields)
    assert trust["right_femur_imu"].trusted and trust["pelvis_imu"].trusted
    assert not trust["right_foot_imu"].trusted and not trust["left_foot_imu"].trusted


def test_the_gyro_bias_wanders():
    still = simulate_trial(motion="static", duration_s=60.0, seed=2, noise=SensorNoise.none(),
                           artefacts=Artefacts())
    b = still.imus["pelvis_imu"].recording.gyr - still.imus["pelvis_imu"].gyro_bias
    drift = np.linalg.norm(b[-500:].mean(axis=0) - b[:500].mean(axis=0))
    assert 2e-4 < drift < 1e-2  # ~ 2e-4 rad/s per sqrt(s) over ~55 s, per axis
