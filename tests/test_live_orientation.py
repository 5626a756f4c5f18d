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


def test_the_pi_filter_is_seeded_by_the_still_start_as_offline():
    """A sensor still for 2 s with a gyro bias of 0.02 rad/s about the vertical, then turning:
    fed block by block, the live PI filter's attitudes equal the offline filter's (its
    ``rest_start``) once it moves; unseeded its heading would drift by the bias."""
    from pipeline.calibration.attitude import TUNED, mahony_filter
    from pipeline.io.recording import SensorSignals
    from pipeline.live.orientation import LiveOrientations

    rate, n = 100.0, 600
    t = np.arange(n) / rate
    rng = np.random.default_rng(1)
    gyr = np.tile([0.0, 0.0, 0.02], (n, 1)) + rng.normal(0, 0.002, (n, 3))
    gyr[200:, 0] += 0.8 * np.sin(2.0 * (t[200:] - 2.0))  # it moves from 2 s
    acc = np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0, 0.02, (n, 3))
    live = LiveOrientations(["s"], rate, own=False, method="pi")
    got = np.concatenate([live.update({"s": SensorSignals(gyr=gyr[a:a + 5], acc=acc[a:a + 5])})
                          ["6-D"]["s"] for a in range(0, n, 5)])
    from pipeline.calibration.attitude import still_start
    from pipeline.rotations import matrix_from_quat

    offline = live.world @ matrix_from_quat(mahony_filter(t, gyr, acc, **TUNED).quat)
    moves = still_start(gyr, acc)  # 203: before, the live filter ran unseeded (2.2 deg off)
    assert 200 <= moves < 210
    np.testing.assert_allclose(got[moves:], offline[moves:], atol=1e-3)  # within 0.02 deg
