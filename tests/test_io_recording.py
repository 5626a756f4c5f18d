"""pipeline.io.recording: the one recording type, from every reader and the simulators."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.recording import Recording, SensorSignals


def test_one_sensor_views_and_rate():
    t = np.arange(5) * 0.01
    gyr = np.ones((5, 3))
    rec = Recording.single("thigh", t, gyr=gyr, acc=2 * gyr)
    assert rec.name == "thigh" and rec.rate_hz == pytest.approx(100.0)
    assert rec.gyr is gyr and rec.quat is None and rec.orientations() == {}
    still = SensorSignals(quat=np.tile([1.0, 0, 0, 0], (5, 1)))
    both = rec.with_sensors({"a": rec.sensor, "b": still})
    assert both.sensor_names == ("a", "b") and list(both.orientations()) == ["b"]
    with pytest.raises(InputError, match="one-sensor"):
        both.gyr  # noqa: B018


def test_readers_and_simulator_return_recordings(sim):
    from pipeline.io.imu_csv import read_imu_csv
    from pipeline.simulate.joint_trials import hinge_trial
    from pipeline.simulate.model import simulate_trial

    csv = read_imu_csv(sim / "imu" / "right_femur_imu.csv")
    assert isinstance(csv, Recording) and csv.name == "right_femur_imu"
    trial = simulate_trial(motion="static", duration_s=0.2)
    rec = trial.recording
    assert isinstance(rec, Recording) and set(rec.sensors) == set(trial.imus)
    pelvis = trial.imus["pelvis_imu"].recording
    np.testing.assert_array_equal(rec.sensors["pelvis_imu"].gyr, pelvis.gyr)
    assert isinstance(hinge_trial("rich", duration=1.0).imu_1, Recording)


def test_a_sensor_turned_on_its_segment_measures_the_same_world_in_its_new_axes():
    """``turned(R)``: the world-frame vectors and the orientation's action are unchanged, the
    sensor-frame vectors are the old ones in the new axes (``R^T x``)."""
    from pipeline.rotations import exp3, matrix_from_quat, quat_from_matrix

    rng = np.random.default_rng(0)
    R0 = exp3(rng.normal(size=(50, 3)))  # the sensor in the world
    x = rng.normal(size=(50, 3))  # a measured vector, sensor frame
    s = SensorSignals(quat=quat_from_matrix(R0), gyr=x, acc=2 * x, mag=None)
    R = exp3(np.array([0.3, -1.2, 2.0]))
    t = s.turned(R)
    assert t.mag is None
    np.testing.assert_allclose(t.gyr, np.einsum("ji,nj->ni", R, x), atol=1e-12)
    world_before = np.einsum("nij,nj->ni", R0, x)
    world_after = np.einsum("nij,nj->ni", matrix_from_quat(t.quat), t.gyr)
    np.testing.assert_allclose(world_after, world_before, atol=1e-12)
    np.testing.assert_allclose(matrix_from_quat(t.quat), R0 @ R, atol=1e-12)


def test_low_passed_filters_the_inertial_signals_only():
    t = np.arange(400) / 100.0
    wave = np.column_stack([np.sin(2 * np.pi * 1.0 * t) + np.sin(2 * np.pi * 20.0 * t)] * 3)
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (400, 1))
    s = SensorSignals(quat=quat, gyr=wave, acc=2 * wave, mag=wave)
    f = s.low_passed(100.0, 5.0)
    slow = np.sin(2 * np.pi * 1.0 * t)[100:300]
    assert np.max(np.abs(f.gyr[100:300, 0] - slow)) < 0.05
    assert np.max(np.abs(f.acc[100:300, 1] - 2 * slow)) < 0.1
    assert f.quat is quat and f.mag is wave
    assert SensorSignals(quat=quat).low_passed(100.0, 5.0).gyr is None


def test_complete_means_both_inertial_signals_every_sample_finite():
    x = np.zeros((5, 3))
    assert SensorSignals(gyr=x, acc=x).complete
    assert not SensorSignals(gyr=x).complete
    gap = x.copy()
    gap[2, 1] = np.nan
    assert not SensorSignals(gyr=x, acc=gap).complete


def test_cropped_is_a_recording_that_starts_there_its_gaps_with_it():
    """Samples 100-300 of a 500-sample recording: its time from 0, every signal cut alike, a gap
    across the start clipped to it, one inside moved with it, one after dropped."""
    from pipeline.io.gaps import Missing

    t = np.arange(500) / 100.0
    gyr = np.column_stack([t, 2 * t, 3 * t])
    rec = Recording(t, 100.0, {"a": SensorSignals(gyr=gyr, acc=gyr + 1.0)},
                    missing=Missing({"a": ((90, 110), (150, 160), (400, 420))}))
    out = rec.cropped(100, 300)
    assert out.n_samples == 200 and out.time[0] == 0.0 and out.time[-1] == pytest.approx(1.99)
    np.testing.assert_array_equal(out.sensors["a"].gyr, gyr[100:300])
    assert out.sensors["a"].quat is None and out.sensors["a"].acc[0, 0] == gyr[100, 0] + 1.0
    assert out.missing.spans == {"a": ((0, 10), (50, 60))}
    assert rec.cropped(450).n_samples == 50 and rec.cropped(450).missing.spans == {}
