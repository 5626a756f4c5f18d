"""pipeline.process.functional: the knees' joint-constraint calibration from raw signals and the
evidence that decides whether to trust it (simulated truth, and the real x-IMU3 recording)."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.io.opensim import SENSOR_TO_SEGMENT
from pipeline.io.recording import Recording, SensorSignals
from pipeline.model.anthropometry import Measures
from pipeline.process import process_recording
from pipeline.simulate.model import simulate_trial

XIMU3 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ximu3_lower_body"
NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}


def test_a_simulated_hinge_is_calibrated_trusted_and_matches_the_truth():
    trial = simulate_trial(motion="gait", duration_s=12.0, seed=4, standing_s=2.0)
    raw = Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(gyr=i.recording.gyr,
                                                               acc=i.recording.acc,
                                                               mag=i.recording.mag)
                                        for f, i in trial.imus.items()})  # fmt: skip
    run = process_recording(raw, Measures("m", 1.75), filter="vqf")
    cal = {c.side: c for c in run.knee_calibrations}
    assert set(cal) == {"right", "left"}
    for side, c in cal.items():
        true = trial.knee_axis[f"{side}_femur_imu"]
        err = np.degrees(min(np.arccos(np.clip(abs(c.axis_thigh @ true), -1, 1)), np.pi))
        assert err < 1.0, (side, err)  # the simulated hinge axis in the thigh sensor
        assert c.trusted and c.split_half_deg < 1.0 and c.residual_rad_s < 0.05, c


def test_calibration_method_none_skips_it():
    trial = simulate_trial(motion="gait", duration_s=6.0, seed=4, standing_s=2.0)
    raw = Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(gyr=i.recording.gyr,
                                                               acc=i.recording.acc)
                                        for f, i in trial.imus.items()})  # fmt: skip
    assert process_recording(raw, Measures("m", 1.75), calibration_method="none",
                             filter="pi").knee_calibrations == []  # fmt: skip


@pytest.mark.dataset
def test_the_real_ximu3_recording_is_not_trusted_and_says_why():
    """~18 s of free leg movements: the halves disagree and the hinge residual is large."""
    if not XIMU3.exists():
        pytest.skip("../shared/data/ximu3_lower_body not present")
    from pipeline.io.imu_folder import read_imu_folder

    run = process_recording(read_imu_folder(XIMU3), Measures("m", 1.8), filter="vqf")
    assert len(run.knee_calibrations) == 2
    for c in run.knee_calibrations:
        assert not c.trusted and "apart" in c.reason and c.split_half_deg > 10.0
