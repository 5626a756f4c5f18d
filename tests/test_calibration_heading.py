"""pipeline.calibration.heading: the subject's right by hand (see test_process.py for the
anatomical heading on simulated walks)."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.heading import heading_rotation, pelvis_axis_right, subject_right
from pipeline.errors import InputError
from pipeline.rotations import rot_y


def test_heading_rotation_by_hand():
    # the subject's right along world +x: Ry(90 deg) takes the model's right (z) to x
    np.testing.assert_allclose(heading_rotation(np.array([1.0, 0, 0])), rot_y(np.pi / 2),
                               atol=1e-15)
    np.testing.assert_allclose(heading_rotation(np.array([0, 0, 1.0])), np.eye(3), atol=1e-15)


def test_pelvis_axis_heading_by_hand():
    # pelvis sensor turned 90 deg about up: its -z axis points along world -x (forward), so the
    # subject's right = forward x up = (-x) x y = -z
    R = np.repeat(rot_y(np.pi / 2)[None], 3, axis=0)
    np.testing.assert_allclose(pelvis_axis_right({"pelvis": R}, "pelvis_imu:-z"), [0, 0, -1],
                               atol=1e-12)
    with pytest.raises(InputError, match="vertical"):
        pelvis_axis_right({"pelvis": R}, "pelvis_imu:y")
    with pytest.raises(InputError, match="heading"):
        subject_right({"pelvis": R}, "pelvis_imu:w")


def test_turning_axis_and_vertical_check_by_hand():
    from pipeline.calibration.heading import check_vertical, turning_axis
    from pipeline.rotations import rot_x, rot_z

    yaw = np.linspace(0, 2 * np.pi, 400)
    sway = 0.1 * np.sin(7 * yaw)  # pelvis list oscillating while turning round
    # a y-up world: the pelvis turns about y
    R = rot_y(yaw) @ rot_z(sway)
    line, largest = turning_axis(R)
    assert abs(line @ [0, 1, 0]) > 0.99 and largest > 3.0
    check_vertical(R)  # passes silently
    # the same motion in a z-up world (as Xsens records it): refused with the fix, both signs
    Rz_up = rot_x(np.pi / 2) @ R
    with pytest.raises(InputError, match=r"z axis.*-1\.5708 0\.0000 0\.0000 \(if z points up"):
        check_vertical(Rz_up)
    with pytest.raises(InputError, match=r"z axis.*-1\.5708 0\.0000 0\.0000 \(if z points up"):
        check_vertical(rot_x(np.pi / 2) @ rot_y(-yaw))  # turning the other way round
    # too little turning: not checked, with a note
    notes: list[str] = []
    check_vertical(rot_y(0.1 * np.sin(yaw)), notes=notes)
    assert notes and "not checked" in notes[0]


def test_knee_cue_takes_out_the_tilt_of_the_knee_axis_by_hand():
    """A standing right knee (no hip motion) flexing about an axis turned 10 deg about the vertical
    from the right (world z at zero heading): taken as the femur's z the
    right comes out turned by 10 deg; told the axis (``knee_axes``), exactly the right."""
    from pipeline.calibration.heading import anatomical_right
    from pipeline.rotations import exp3

    psi = np.radians(10.0)
    axis = rot_y(psi) @ [0, 0, 1.0]  # the knee axis in the world at t0 (pointing right)
    flex = np.radians(60.0) * np.sin(np.linspace(0, np.pi, 200)) ** 2
    femur = np.repeat(np.eye(3)[None], 200, axis=0)
    tibia = exp3(-flex[:, None] * axis)  # the knee flexes about -right
    rot = {"right_femur": femur, "right_tibia": tibia}
    plain = anatomical_right(rot)
    np.testing.assert_allclose(plain, axis, atol=1e-9)  # turned by psi
    told = anatomical_right(rot, knee_axes={"right": axis})
    np.testing.assert_allclose(told, [0, 0, 1.0], atol=1e-9)
    # a cue of a side not told stays as it was
    np.testing.assert_allclose(anatomical_right(rot, knee_axes={"left": axis}), axis, atol=1e-9)
