"""pipeline.process.sensors: which joints a sensor set observes; a recording's names mapped."""

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.process.sensors import apply_sensor_map, sensor_set


def test_observed_joints_legs_and_landmark_segments():
    s = sensor_set({"right_femur", "right_tibia"})
    assert s.joints == ("right_knee",) and s.legs == ("right",) and not s.pelvis
    assert s.landmark_segments == ("right_femur", "right_tibia")
    s = sensor_set({"pelvis", "right_femur", "right_tibia", "right_foot", "left_femur"})
    assert s.joints == ("right_hip", "right_knee", "right_ankle", "left_hip")
    assert s.landmark_segments == ("right_femur", "right_tibia", "right_foot", "left_femur")
    # an ankle alone (tibia + foot): observed, but no landmark (the knee's position is unknown)
    s = sensor_set({"right_tibia", "right_foot"})
    assert s.joints == ("right_ankle",) and s.landmark_segments == ()


@pytest.mark.parametrize("segments", [set(), {"pelvis"}, {"right_femur", "left_femur"},
                                      {"pelvis", "right_tibia"}, {"right_femur", "right_foot"}])
def test_a_set_observing_no_joint_is_refused(segments):
    with pytest.raises(InputError, match="observe no joint.*knee = femur_r_imu \\+ tibia_r_imu"):
        sensor_set(segments, source="x.sto")


def _rec(*names):
    q = np.tile([1.0, 0, 0, 0], (5, 1))
    return Recording.from_orientations(np.arange(5) / 100.0, 100.0, {n: q for n in names})


def test_map_by_name_or_unique_part_and_aliases():
    rec = _rec("MT_012005D6_00B421AF", "thigh_R", "shank_R", "foot_r_imu")
    out = apply_sensor_map(rec, {"pelvis_imu": "00B421AF", "femur_r_imu": "thigh_R",
                                 "tibia_r_imu": "shank"})  # fmt: skip
    assert set(out.sensor_names) == {"pelvis_imu", "femur_r_imu", "tibia_r_imu", "calcn_r_imu"}
    assert apply_sensor_map(_rec("pelvis_imu"), {}) .sensor_names == ("pelvis_imu",)


@pytest.mark.parametrize(
    "names, mapping, message",
    [
        (("a1", "a2"), {"pelvis_imu": "a"}, "several sensors"),
        (("a1",), {"pelvis_imu": "zz"}, "no sensor"),
        (("a1",), {"pelvis_imu": "a1", "femur_r_imu": "a1"}, "mapped twice"),
        (("calcn_r_imu", "foot_r_imu"), {}, "two sensors for calcn_r_imu"),
    ],
)
def test_unmatched_ambiguous_or_duplicate_names_are_refused(names, mapping, message):
    with pytest.raises(InputError, match=message):
        apply_sensor_map(_rec(*names), mapping)
