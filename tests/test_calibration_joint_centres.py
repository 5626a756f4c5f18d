"""pipeline.calibration.joint_centres: a joint's centre in both sensors' frames (eq 2, the vector
form of Hu 2021's constraint), against the simulator's truth."""

import numpy as np
import pytest

from pipeline.calibration.joint_centres import joint_centre
from pipeline.simulate.model import SensorNoise, simulate_trial


@pytest.fixture(scope="module")
def trial():
    return simulate_trial(motion="gait", duration_s=12.0, seed=6)


def _fit(trial, a, b, **kw):
    s1, s2 = trial.imus[a].recording.sensor, trial.imus[b].recording.sensor
    return joint_centre(trial.time, s1.gyr, s1.acc, trial.imus[a].rotation, s2.gyr, s2.acc,
                        trial.imus[b].rotation, **kw)


@pytest.mark.parametrize("joint, a, b", [("right_ankle", "right_tibia_imu", "right_foot_imu"),
                                         ("left_hip", "pelvis_imu", "left_femur_imu")])
def test_ball_joints_centre_in_both_frames(trial, joint, a, b):
    c = _fit(trial, a, b, cutoff_hz=1000.0)
    truth = trial.joint_centres[joint]
    assert np.linalg.norm(c.o_1 - truth[a]) < 0.01 and np.linalg.norm(c.o_2 - truth[b]) < 0.01
    assert c.residual < 0.3


def test_a_hinge_leaves_its_axis_undetermined_and_says_which_way(trial):
    """The knee is a hinge: any point of its axis satisfies the constraint. The fit says so (its
    conditioning small) and names the direction: both centres along the knee axis."""
    c = _fit(trial, "right_femur_imu", "right_tibia_imu")
    assert c.conditioning < 0.1
    axis = trial.knee_axis["right_tibia_imu"]
    d = c.weakest[1] / np.linalg.norm(c.weakest[1])
    assert abs(d @ axis) > 0.95
    truth = trial.joint_centres["right_knee"]["right_tibia_imu"]
    off = c.o_2 - truth
    assert np.linalg.norm(off - (off @ axis) * axis) < 0.01  # on the axis through the truth


def test_noise_free_signals_are_exact_without_the_filter():
    t = simulate_trial(motion="gait", duration_s=8.0, seed=2, noise=SensorNoise.none())
    c = _fit(t, "left_tibia_imu", "left_foot_imu", cutoff_hz=1000.0)
    truth = t.joint_centres["left_ankle"]
    assert np.linalg.norm(c.o_1 - truth["left_tibia_imu"]) < 0.002


def test_the_vertical_part_alone_holds_whatever_the_two_headings():
    """Two attitude filters agree on the vertical but not on the heading: with one sensor's world
    turned about the vertical by a heading that wanders (40 deg, +-15 deg over the trial) the full
    vector form misplaces the centre by centimetres; its vertical part alone (``shared_axis``, the
    simulator's z up) still finds it."""
    t = simulate_trial(motion="gait", duration_s=8.0, seed=2, noise=SensorNoise.none())
    a, b = "left_tibia_imu", "left_foot_imu"
    psi = np.radians(40.0 + 15.0 * np.sin(2 * np.pi * t.time / 8.0))
    c, s = np.cos(psi), np.sin(psi)
    Rz = np.zeros((psi.size, 3, 3))
    Rz[:, 0, 0], Rz[:, 0, 1], Rz[:, 1, 0], Rz[:, 1, 1], Rz[:, 2, 2] = c, -s, s, c, 1.0
    s1, s2 = t.imus[a].recording.sensor, t.imus[b].recording.sensor
    R2 = Rz @ t.imus[b].rotation
    truth = t.joint_centres["left_ankle"]

    def error(**kw):
        f = joint_centre(t.time, s1.gyr, s1.acc, t.imus[a].rotation, s2.gyr, s2.acc, R2,
                         cutoff_hz=1000.0, **kw)
        return max(np.linalg.norm(f.o_1 - truth[a]), np.linalg.norm(f.o_2 - truth[b]))

    assert error() > 0.02
    assert error(shared_axis=2) < 0.005
