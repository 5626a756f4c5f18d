"""pipeline.live.calibration: the offline pipeline on the capture so far; not final before the
walk has checked the pose and given the heading; a capture without a pelvis sensor refused."""


import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.formats import read_recording
from pipeline.live.calibration import calibrate_capture
from pipeline.model.measures import Measures
from pipeline.process.options import IKOptions


def test_final_only_once_the_walk_has_checked_the_pose():
    rec, subject = read_recording("example:ximu3_lower_body"), Measures("m", 1.8)
    still = calibrate_capture(rec.cropped(0, 60), subject, IKOptions(), {})
    assert not still.final and "no walk to check it by" in still.how
    assert still.turns and all(t == 0.0 for t in still.turns.values())  # nothing aligned yet
    walked = calibrate_capture(rec, subject, IKOptions(), {})
    assert walked.final and "checked by the walk" in walked.how
    assert np.isfinite(walked.q).all() and walked.at_s == pytest.approx(rec.time[-1])


def test_a_capture_without_a_pelvis_sensor_is_refused():
    rec = read_recording("example:ximu3_lower_body")
    legs = rec.with_sensors({k: s for k, s in rec.sensors.items() if k != "pelvis_imu"})
    with pytest.raises(InputError, match="needs a pelvis sensor"):
        calibrate_capture(legs, Measures("m", 1.8), IKOptions(), {})
