"""pipeline.analysis.foot_trajectory: the simulated foot's path (known truth) and the real S02
foot's straight strides against the Vicon heel marker."""

import numpy as np
import pytest

from pipeline.analysis.foot_trajectory import foot_trajectory
from pipeline.analysis.gait_events import gait_events
from pipeline.simulate.foot_walk import foot_walk


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_path_between_rests_is_the_simulated_one(seed):
    """Positions at every rest within 1.5 cm of the truth (relative to the first rest) after 8
    strides with two turns; heights back to the floor at every rest."""
    w = foot_walk(strides=8, seed=seed, turns_deg=(0, 90, 0, -45))
    ev = gait_events(w.gyr, w.acc, w.rate_hz)
    path = foot_trajectory(w.gyr, w.acc, w.rate_hz, ev.rests)
    mids = [(a + b) // 2 for a, b in ev.rests]
    ours = path.position[mids] - path.position[mids[0]]
    truth = w.position[mids] - w.position[mids[0]]
    # our world's heading is the sensor's at its first rest: compare horizontal distances
    d_ours = np.linalg.norm(ours[:, :2][:, None] - ours[:, :2][None], axis=-1)
    d_truth = np.linalg.norm(truth[:, :2][:, None] - truth[:, :2][None], axis=-1)
    assert np.abs(d_ours - d_truth).max() < 0.05
    assert abs(d_ours[1, 2] - 1.3) < 0.015  # rests 0 and 1: standing, then the first loading
    assert np.abs(ours[:, 2]).max() < 0.02


def test_no_rest_no_path():
    rng = np.random.default_rng(0)
    p = foot_trajectory(rng.normal(size=(50, 3)), rng.normal(size=(50, 3)), 100.0,
                        np.zeros((0, 2), int))
    assert np.all(np.isnan(p.position)) and np.all(np.isnan(p.rotation))
