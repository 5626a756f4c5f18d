"""pipeline.process.pose_source: where the calibration is read (a still window before the walk,
checked by the walk; the walk; the first sample, flagged), on the real walk cut and relabelled
as users bring it, and on the simulator."""

import numpy as np
import pytest
from _helpers import s02_cut

from pipeline.model.measures import Measures
from pipeline.process import process_recording
from pipeline.process.pose_source import POSE_TOL_DEG, pose_errors
from pipeline.process.still import StillWindow
from pipeline.process.walking_pose import WalkingFrames
from pipeline.rotations import rot_z

S02_SUBJECT = Measures("m", 1.72)
Z_UP = {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)}


def test_a_windows_pose_error_is_each_long_axis_from_where_the_pose_puts_it():
    n = 100
    window = StillWindow(0, n, 0.0, 0.99)
    frames = WalkingFrames({"pelvis": np.eye(3), "right_femur": np.eye(3),
                            "right_tibia": np.eye(3)}, {})
    upright = {seg: np.tile(np.eye(3), (n, 1, 1)) for seg in frames.frames}
    lying = {seg: np.tile(rot_z(np.pi / 2), (n, 1, 1)) for seg in frames.frames}
    seated = {**upright, "right_femur": lying["right_femur"]}
    assert max(pose_errors(window, frames, upright, "standing").values()) < 1e-6
    assert min(pose_errors(window, frames, upright, "supine").values()) > 89.0
    assert max(pose_errors(window, frames, lying, "supine").values()) < 1e-6
    assert max(pose_errors(window, frames, seated, "seated").values()) < 1e-6
    assert pose_errors(window, frames, seated, "standing")["right_femur"] > POSE_TOL_DEG


def _run(start, stop=None, **options):
    rec = s02_cut(start, stop)
    if rec is None:
        pytest.skip("no S02 data")
    return process_recording(rec, S02_SUBJECT, **Z_UP, **options)


@pytest.mark.dataset
def test_s02_as_recorded_reads_its_standing_start_checked_by_the_walk():
    run = _run(0)
    assert run.calibration.startswith("standing pose, read in the still window 0.00-10.86 s "
                                      "(checked by the walk: ")
    assert run.calibration.endswith("; 1 other still window(s)") and not run.flags


@pytest.mark.dataset
def test_a_stop_after_the_walk_is_not_taken_for_the_calibration_pose():
    """S02 from mid-walk ends standing (22-25 s): a pose not held for the calibration (its hips
    7 deg more flexed than its start's, by Vicon): the walk calibrates, and says why."""
    run = _run(1300)
    assert run.calibration.startswith("from the walk, no pose (no still window before the "
                                      "walk: 1 after its start")
    assert not run.flags


@pytest.mark.dataset
def test_a_pose_the_accelerometers_deny_is_flagged_and_the_walk_calibrates():
    """``--calibration-pose supine`` on S02 (it stands, then walks): no window shows it."""
    run = _run(0, calibration_pose="supine")
    (flag,) = run.flags
    assert flag.startswith("no still window shows the supine pose (0.00-10.86 s: ")
    assert "calibrated from the walk instead; check --calibration-pose" in flag
    assert run.calibration.startswith("from the walk, no pose (no still window shows the supine")


@pytest.mark.dataset
def test_a_standing_only_trial_passes_strict():
    """S02's 11 s of standing alone: the pose read in its window, nothing flagged (no heading
    from a motion, none needed; the straight knees at their limit are the pose)."""
    run = _run(0, 1100)
    assert run.calibration.startswith("standing pose, read in the still window 0.00-10.86 s "
                                      "(not checked: no walk to check it by)")
    assert run.flags == []
    assert any("the subject's heading is not observed" in n for n in run.notes)


def test_no_window_and_no_walk_take_the_first_sample_and_say_so():
    from pipeline.io.recording import Recording
    from pipeline.simulate.model import simulate_trial

    trial = simulate_trial(motion="gait", duration_s=4.0, seed=1)  # orientations, moving
    rec = Recording.from_orientations(trial.time, 100.0, {
        {"pelvis_imu": "pelvis_imu", "right_femur_imu": "femur_r_imu",
         "right_tibia_imu": "tibia_r_imu"}[f]: i.recording.quat
        for f, i in trial.imus.items() if f in ("pelvis_imu", "right_femur_imu",
                                                "right_tibia_imu")})
    run = process_recording(rec, Measures("m", 1.75), **Z_UP)
    assert run.calibration == "standing pose assumed at the first sample (no still window, no walk)"
    assert run.flags[0].startswith("no still window (every sensor at rest for half a second) and "
                                   "no walk to calibrate from (no strides)")
