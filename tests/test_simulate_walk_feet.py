"""pipeline.simulate.walk_feet: the feet's poses stride by stride equal the sums over every
stride they stand for."""

import numpy as np

from pipeline.simulate.foot_walk import bump_integral
from pipeline.simulate.walk_feet import _ramps


def test_ramps_computed_on_their_own_samples_equal_the_whole_sum():
    tau = np.concatenate([np.zeros(50), np.linspace(0, 30, 3000)])  # standing, then the walk
    windows = [(a, a + 0.4, size) for a, size in zip(np.arange(-0.2, 29.0, 1.1),
                                                     np.sin(np.arange(27)), strict=False)]
    whole = sum(size * bump_integral((tau - a) / (b - a)) for a, b, size in windows)
    assert np.max(np.abs(_ramps(tau, windows, bump_integral) - whole)) < 1e-12
