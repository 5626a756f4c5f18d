"""pipeline.live.orientation: a stream's own orientations turned into the model's world, or VQF's
online filter on raw signals (its vertical from gravity; 9-D where the calibration trusts it)."""

import numpy as np

from pipeline.io.recording import SensorSignals
from pipeline.live.orientation import LiveOrientations
from pipeline.rotations import rot_x


def test_own_orientations_are_turned_into_the_models_world():
    world = rot_x(-np.pi / 2)  # z up -> y up
    live = LiveOrientations(["s"], 100.0, own=True, world=world)
    q = np.tile([1.0, 0.0, 0.0, 0.0], (4, 1))
    q[2] = np.nan  # a frame the stream missed
    out = live.chosen(live.update({"s": SensorSignals(quat=q)}))
    np.testing.assert_allclose(out["s"][0], world)
    assert np.isnan(out["s"][2]).all()


def test_the_online_filter_finds_the_vertical_and_keeps_its_state_across_blocks():
    live = LiveOrientations(["s"], 100.0, own=False)
    n = 300
    tilt = rot_x(0.3)  # the sensor tilted 0.3 rad about its x axis, at rest
    acc = np.tile(tilt.T @ [0.0, 0.0, 9.81], (n, 1))
    signals = SensorSignals(gyr=np.zeros((n, 3)), acc=acc, mag=np.tile([0.2, 0.0, -0.4], (n, 1)))
    for k in range(0, n, 10):  # blocks of 10 samples: one filter fed on
        kinds = live.update({"s": SensorSignals(gyr=signals.gyr[k:k + 10],
                                                 acc=signals.acc[k:k + 10],
                                                 mag=signals.mag[k:k + 10])})
    assert set(kinds) == {"6-D", "9-D"}
    R = live.chosen(kinds)["s"][-1]  # in the model's y-up world
    up_in_sensor = R.T @ [0.0, 1.0, 0.0]
    np.testing.assert_allclose(up_in_sensor, tilt.T @ [0.0, 0.0, 1.0], atol=0.02)
    live.nine_d = frozenset({"s"})
    assert live.chosen(kinds)["s"] is kinds["9-D"]["s"]
