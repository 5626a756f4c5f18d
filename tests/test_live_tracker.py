"""pipeline.live.tracker (with the calibration and the capture around it), against known truth:
a simulated walk through the room (its sensors' own orientations, no artefacts) replayed live:
once the calibration is final, every sagittal angle within 0.5 deg RMS of the simulation's."""

import numpy as np

from pipeline.analysis.joint_angles import joint_angles
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.live.capture import LiveCapture
from pipeline.live.sources import ReplaySource
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.process.options import IKOptions
from pipeline.simulate.model import simulate_trial


def test_a_simulated_walk_live_equals_its_truth_once_calibrated():
    subject = Measures("m", 1.75)
    sk = Skeleton.build(geometry_from_measures(subject)[0], knee="free", root="freeflyer")
    trial = simulate_trial(sk, "walk", duration_s=20.0, seed=1, standing_s=3.0)
    names = {f"{seg}_imu": n for n, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}
    rec = Recording(trial.time, 100.0, {names[f]: i.recording.sensor
                                        for f, i in trial.imus.items()})
    result = LiveCapture(ReplaySource(rec, np.inf), subject, IKOptions(), in_line=True,
                         say=lambda s: None).run()
    at = next(c.from_s for c in result.calibrations if c.final)
    assert at < 12.0  # the walk starts at 3 s: three strides a leg
    k = int(np.searchsorted(result.recording.time, at))
    truth = joint_angles(sk, trial.q)
    for side in ("right", "left"):
        for joint in ("hip", "knee", "ankle"):
            key = f"{side}_{joint}_flexion"
            d = np.degrees(result.angles[key][k:] - truth[key][k:])
            assert np.sqrt(np.nanmean(d**2)) < 0.5, key
