"""pipeline.process.options: every option of `pipeline ik` checked in one place."""

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.process.options import IKOptions, check_sensor_to_model


def test_defaults_are_the_documented_ones():
    o = IKOptions()
    assert (o.knee, o.correction, o.calibration_pose, o.heading) == (
        "free", "aor", "standing", "anatomical")
    assert o.joint_limits and o.rerun and not o.strict and not o.segment_orientations


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"knee": "ball"}, "knee"),
        ({"correction": "wang"}, "correction"),
        ({"calibration_pose": "kneeling"}, "calibration_pose"),
        ({"heading": "north"}, "heading"),
        ({"joint_limits": "yes"}, "joint_limits"),
        ({"knee_axis_femur": (0, 0, 1)}, "knee_axis_femur"),  # one axis without the other
        ({"knee_axis_femur": (0, 0, 0), "knee_axis_tibia": (0, 0, 1)}, "knee_axis_femur"),
        ({"knee_axis_femur": (0, 0, -1), "knee_axis_tibia": (0, 0, 1)}, "knee_axis_femur"),
        ({"sensor_map": {"thigh": "T1"}}, "sensors.thigh"),
        ({"sensor_map": {"pelvis_imu": ""}}, "sensors.pelvis_imu"),
    ],
)
def test_bad_values_are_refused_naming_the_option(changes, field):
    with pytest.raises(InputError) as exc:
        IKOptions(**changes)
    assert exc.value.field == field


def test_units_hints_for_degrees_and_centimetres():
    with pytest.raises(InputError, match="if you meant degrees, give -1.5708 0.0000 0.0000"):
        check_sensor_to_model((-90, 0, 0))
    with pytest.raises(InputError, match="looks like cm"):
        IKOptions(foot_length_m=26.0)
    with pytest.raises(InputError, match="finite"):
        check_sensor_to_model((np.nan, 0, 0))


def test_axes_are_normalised_and_replace_checks_names():
    o = IKOptions(knee_axis_femur=(0, 0, 2), knee_axis_tibia=(0.3, 0, 0.4))
    assert o.knee_axis_femur == (0.0, 0.0, 1.0)
    np.testing.assert_allclose(o.knee_axis_tibia, (0.6, 0.0, 0.8))
    assert o.replace(knee="hinge").knee == "hinge"
    with pytest.raises(InputError, match="unknown option"):
        o.replace(kne="hinge")
    assert IKOptions(sensor_map={"foot_r_imu": "F"}).sensor_map == {"foot_r_imu": "F"}
