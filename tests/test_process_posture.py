"""pipeline.process.posture: the standing lean of each leg from the joint centres, against the
simulator's truth (a subject standing with each leg leaning 2-6 deg)."""

import numpy as np
import pytest

from pipeline.analysis.joint_angles import joint_angles
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.model.measures import Measures
from pipeline.process import process_recording
from pipeline.process.posture import Posture, lean_pose
from pipeline.rotations import rot_z
from pipeline.simulate.model import simulate_trial

M = Measures("m", 1.75)
NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}


@pytest.fixture(scope="module")
def trial():
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton

    geometry, _ = geometry_from_measures(M)  # the estimator's own geometry
    model = Skeleton.build(geometry, knee="hinge", root="freeflyer")
    return simulate_trial(model, "gait", duration_s=17.0, seed=0, standing_s=2.0)


def test_each_legs_lean_is_measured_and_the_standing_angles_follow(trial):
    raw = Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(gyr=i.recording.gyr,
                                                                acc=i.recording.acc)
                                        for f, i in trial.imus.items()})
    truth = joint_angles(trial.skeleton, trial.q)
    measured = process_recording(raw, M, filter="vqf")
    upright = process_recording(raw, M, filter="vqf", posture="neutral")
    for side in ("right", "left"):
        true_lean = np.degrees(truth[f"{side}_ankle_flexion"][100])  # the foot flat
        lean = np.degrees(measured.posture.lean[f"{side}_tibia"])
        assert 2.0 < true_lean < 6.0 and abs(lean - true_lean) < 1.0, (side, lean, true_lean)
        assert measured.posture.lean[f"{side}_femur"] == measured.posture.lean[f"{side}_tibia"]
        for joint in ("hip", "ankle"):  # the lean's angles: 3-5 deg off upright, ~0.5 measured
            key = f"{side}_{joint}_flexion"
            rms = {r: np.sqrt(np.mean(np.degrees(run.joint_angles[key] - truth[key])[200:] ** 2))
                   for r, run in (("measured", measured), ("upright", upright))}
            assert rms["measured"] < 1.0 and rms["measured"] < 0.5 * rms["upright"], (key, rms)
    assert any("standing posture from the knee and ankle centres" in n and "hinge-like centre "
               "fits" in n for n in measured.notes)  # the simulator's hinge knee
    assert upright.posture is None


def test_the_lean_turns_femur_and_tibia_about_their_medio_lateral_axis():
    pose = {"right_femur": np.eye(3), "right_tibia": np.eye(3), "right_foot": np.eye(3)}
    p = Posture({"right_femur": 0.1, "right_tibia": 0.1}, {"right": 0.4}, {"right": 0.5})
    out = lean_pose(pose, p)
    np.testing.assert_allclose(out["right_tibia"], rot_z(-0.1))
    np.testing.assert_allclose(out["right_foot"], np.eye(3))  # the foot stays flat
    assert out["right_tibia"][:, 1] @ np.array([1.0, 0, 0]) > 0  # its top turned forward
    assert p.joint_angles("right") == {"hip_flexion": -0.1, "knee_flexion": 0.0,
                                       "ankle_flexion": 0.1}


def test_a_leg_without_foot_or_raw_signals_stands_upright(trial):
    quats = Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(quat=i.recording.quat)
                                          for f, i in trial.imus.items()})
    run = process_recording(quats, M, sensor_to_model=(-np.pi / 2, 0, 0))
    assert run.posture.lean == {}
    assert any("standing lean not measured" in n for n in run.notes)


def test_a_leg_without_its_shank_sensor_takes_the_other_legs_lean(trial):
    raw = Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(gyr=i.recording.gyr,
                                                                acc=i.recording.acc)
                                        for f, i in trial.imus.items()
                                        if f != "right_tibia_imu"})
    truth = joint_angles(trial.skeleton, trial.q)
    run = process_recording(raw, M, filter="vqf")
    upright = process_recording(raw, M, filter="vqf", posture="neutral")
    lean = run.posture.lean
    assert lean["right_femur"] == lean["right_tibia"] == lean["left_tibia"]
    assert "right" not in run.posture.length  # borrowed, not measured
    assert any("right leg: standing lean not measured (no right_tibia sensor); it takes the "
               "left leg's" in n for n in run.notes)
    key = "right_hip_flexion"
    err = {r: np.degrees(np.mean(x.joint_angles[key][200:] - truth[key][200:]))
           for r, x in (("borrowed", run), ("upright", upright))}
    legs_differ = np.degrees(truth["right_ankle_flexion"][100] - truth["left_ankle_flexion"][100])
    # off by the legs' difference and the other leg's own error (within 1 deg, the test above)
    assert abs(err["borrowed"]) < abs(legs_differ) + 1.0 < abs(err["upright"]), err


def _centre(o_1, o_2, d_1, d_2):
    from pipeline.calibration.joint_centres import JointCentre

    return JointCentre(np.asarray(o_1, float), np.asarray(o_2, float), 0.5, 0.05,
                       (np.asarray(d_1, float), np.asarray(d_2, float)))


def test_a_hinge_like_fit_leaves_its_axis_out_of_the_tibias_line():
    from pipeline.process.posture import HINGE_LIKE_DEG, _tibia_line

    ml = np.array([0.0, 0.0, 1.0])  # the tibia's medio-lateral axis in its sensor frame
    tilt = np.radians(10.0)  # both fits' weakest direction: a hinge axis 10 deg from it
    axis = np.array([np.sin(tilt), 0.0, np.cos(tilt)])
    true = np.array([0.02, 0.40, 0.0])  # knee minus ankle: leaning forward in x
    knee = _centre([0, 0, 0], true + 0.08 * axis, [0, 0, 0], axis)  # slid 8 cm along its axis
    ankle = _centre([0, 0, 0], [0, 0, 0], -axis, [0, 0, 0])
    v, hinged = _tibia_line(knee, ankle, ml)
    assert hinged
    raw = knee.o_2 - ankle.o_1
    lean = {k: np.degrees(np.arctan2(x[0], x[1])) for k, x in (("true", true), ("raw", raw),
                                                               ("line", v))}
    assert abs(lean["raw"] - lean["true"]) > 1.5  # the slide leaks into the lean
    assert abs(lean["line"] - lean["true"]) < 0.1, lean
    far = np.array([np.sin(np.radians(HINGE_LIKE_DEG + 20)), 0.0,
                    np.cos(np.radians(HINGE_LIKE_DEG + 20))])
    real = _centre([0, 0, 0], true, [0, 0, 0], far)  # a determined fit (a real knee's)
    v, hinged = _tibia_line(real, _centre([0, 0, 0], [0, 0, 0], far, [0, 0, 0]), ml)
    np.testing.assert_allclose(v, true)
    assert not hinged
