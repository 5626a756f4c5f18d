"""pipeline.process.sensors: which joints a sensor set observes; a recording's names mapped."""

import pytest

from pipeline.errors import InputError
from pipeline.process.sensors import sensor_set


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
