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
                               atol=1e-15)  # fmt: skip
    np.testing.assert_allclose(heading_rotation(np.array([0, 0, 1.0])), np.eye(3), atol=1e-15)


def test_pelvis_axis_heading_by_hand():
    # pelvis sensor turned 90 deg about up: its -z axis points along world -x (forward), so the
    # subject's right = forward x up = (-x) x y = -z
    R = np.repeat(rot_y(np.pi / 2)[None], 3, axis=0)
    np.testing.assert_allclose(pelvis_axis_right({"pelvis": R}, "pelvis_imu:-z"), [0, 0, -1],
                               atol=1e-12)  # fmt: skip
    with pytest.raises(InputError, match="vertical"):
        pelvis_axis_right({"pelvis": R}, "pelvis_imu:y")
    with pytest.raises(InputError, match="heading"):
        subject_right({"pelvis": R}, "pelvis_imu:w")
