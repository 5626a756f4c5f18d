"""pipeline.simulate.foot_walk: the simulated foot's signals agree with its own truth."""

import numpy as np

from pipeline.simulate.foot_walk import FC_SHARE, Pace, foot_walk


def test_the_signals_are_those_of_the_path():
    """At rest the gyroscope reads noise and the accelerometer 1 g; the strides advance the
    foot by their length, turned by their turn; the events are where the lobes say."""
    w = foot_walk(strides=4, pace=Pace(1.0, 1.2), turns_deg=(0, 90), seed=0)
    still = w.time < 1.5
    assert np.abs(w.gyr[still]).max() < 0.06
    np.testing.assert_allclose(np.linalg.norm(w.acc[still], axis=1), 9.81, atol=0.3)
    assert len(w.ic) == 5 and np.allclose(np.diff(w.ic), 1.0)
    np.testing.assert_allclose(w.fc, w.ic[:-1] + FC_SHARE)
    end = w.position[-1]
    # 1.2 east, 1.2 turned by 45 deg on average, then two strides north
    expected = 1.2 * np.array([1 + np.cos(np.pi / 4), np.sin(np.pi / 4) + 2])
    np.testing.assert_allclose(end[:2], expected, atol=1e-6)
    assert abs(end[2]) < 1e-9 and np.allclose(w.length, 1.2)

