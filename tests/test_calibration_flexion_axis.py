"""pipeline.calibration.flexion_axis: a segment's flexion axis from its own gait, signed alike
down the leg, on the simulator's truth."""

import numpy as np
import pytest

from pipeline.calibration.flexion_axis import (
    flexion_axis,
    leg_flexion_axes,
    pelvis_lateral_line,
    stride_frequency,
)
from pipeline.errors import InputError
from pipeline.rotations import exp3
from pipeline.simulate.model import simulate_trial


@pytest.fixture(scope="module")
def trial():
    return simulate_trial(motion="gait", duration_s=14.0, seed=4, standing_s=2.0)


def _segment(trial, frame):
    imu = trial.imus[frame]
    up = imu.rotation[:, 2, :]  # the world's vertical (z up) in the sensor frame
    return imu.recording.gyr, up


def _axis_in_sensor(trial, frame, seg):
    """The segment's medio-lateral axis (+z, right) in its sensor's frame (the truth)."""
    return trial.imus[frame].R_segment.T @ np.array([0.0, 0.0, 1.0])


def test_each_segments_axis_is_its_medio_lateral_axis_pointing_right(trial):
    for side in ("right", "left"):
        segs = {seg: _segment(trial, f"{side}_{seg}_imu") for seg in ("femur", "tibia", "foot")}
        axes = leg_flexion_axes(100.0, segs)
        for seg, a in axes.items():
            truth = _axis_in_sensor(trial, f"{side}_{seg}_imu", seg)
            err = np.degrees(np.arccos(np.clip(a.axis @ truth, -1, 1)))
            assert err < 12.0, (side, seg, err)  # pointing right: a wrong sign is 168+ deg
            assert 0.6 < a.share <= 1.0 and 0.2 < a.moving < 1.0


def test_a_signs_flip_is_undone_and_the_pitch_rule_picks_the_pair(trial):
    gyr, up = _segment(trial, "right_tibia_imu")
    single = flexion_axis(gyr, up, 100.0).axis
    # the simulator's sinusoidal swing has no skew: a shank alone may point either way, the knee
    # (thigh and shank together) decides
    pair = leg_flexion_axes(100.0, {"femur": _segment(trial, "right_femur_imu"),
                                    "tibia": (gyr, up)})["tibia"].axis
    assert abs(abs(single @ pair) - 1.0) < 1e-9
    assert pair @ _axis_in_sensor(trial, "right_tibia_imu", "tibia") > 0.9


def test_the_axis_needs_no_heading(trial):
    """Turning the sensor's world about the vertical (a 6-D filter's own heading) changes nothing:
    the axis lives in the sensor's frame, the vertical is all it takes from the world."""
    gyr, up = _segment(trial, "left_femur_imu")
    R = exp3(np.array([0.0, 0.0, 1.3]))  # a turn of the world about z does not move z
    a = flexion_axis(gyr, up @ R.T @ R, 100.0).axis
    np.testing.assert_allclose(a, flexion_axis(gyr, up, 100.0).axis, atol=1e-12)


def test_a_segment_that_does_not_walk_has_no_axis():
    n = 500
    with pytest.raises(InputError, match="does it walk"):
        flexion_axis(np.zeros((n, 3)), np.tile([0.0, 0.0, 1.0], (n, 1)), 100.0)


def _walking_pelvis(f: float, mounting: np.ndarray, seconds: float = 30.0, rate: float = 100.0):
    """A pelvis sensor's gyroscope and vertical: list +-5 deg about the antero-posterior axis
    (x) once per stride, tilt +-2.5 deg about the medio-lateral axis (z) twice, rotation +-4 deg
    about the vertical (y) once, in the segment's frame; the sensor turned by ``mounting``."""
    t = np.arange(int(seconds * rate)) / rate
    w = 2 * np.pi * f
    rates = np.stack([np.radians(5) * w * np.cos(w * t), np.radians(4) * w * np.cos(w * t + 1),
                      np.radians(2.5) * 2 * w * np.cos(2 * w * t + 0.3)], axis=1)
    up = np.tile([0.0, 1.0, 0.0], (len(t), 1))
    return rates @ mounting, up @ mounting, rate


def test_the_pelvis_line_is_its_medio_lateral_axis_whatever_the_mounting():
    """The list at the stride frequency dominates the band: its axis is antero-posterior, and
    up x it the medio-lateral line (sign free), in the sensor's frame."""
    for seed in range(3):
        M = exp3(np.random.default_rng(seed).normal(size=3))
        gyr, up, rate = _walking_pelvis(0.9, M)
        line = pelvis_lateral_line(gyr, up, rate, stride_hz=0.9)
        truth = np.array([0.0, 0.0, 1.0]) @ M
        assert abs(line.axis @ truth) > np.cos(np.radians(1.0)), seed
        assert line.share > 0.8


def test_the_stride_frequency_is_the_thighs_swing():
    t = np.arange(3000) / 100.0
    rate = 3.0 * np.cos(2 * np.pi * 0.85 * t) + 1.0 * np.cos(2 * np.pi * 1.7 * t + 0.5)
    assert abs(stride_frequency(rate, 100.0) - 0.85) < 0.04  # the spectrum's bins: 1/30 Hz
    with pytest.raises(InputError, match="does not swing"):
        stride_frequency(np.zeros(3000), 100.0)
    slow = np.cos(2 * np.pi * 0.25 * t)  # a supine hip flexion: nothing in the walking band
    with pytest.raises(InputError, match="does not swing once per stride"):
        stride_frequency(slow, 100.0)


def test_a_pelvis_that_does_not_list_has_no_line():
    gyr, up, rate = _walking_pelvis(0.9, np.eye(3))
    with pytest.raises(InputError, match="does not list"):
        pelvis_lateral_line(0.005 * gyr, up, rate, stride_hz=0.9)
