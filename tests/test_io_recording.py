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
