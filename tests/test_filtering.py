"""pipeline.filtering: the Gaussian low-pass, checked against its stated response."""

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.filtering import lowpass


@pytest.mark.parametrize("f, expected", [(1.0, 0.957), (4.0, 0.5), (8.0, 0.0625)])
def test_the_gain_of_a_sine_is_the_stated_response(f, expected):
    """-3 dB in power (|H| = 1/sqrt 2) at the cut-off; |H(f)| = exp(-2 pi^2 sigma^2 f^2)."""
    rate, fc = 100.0, 4.0
    t = np.arange(4000) / rate
    y = lowpass(np.sin(2 * np.pi * f * t), rate, fc)
    gain = np.sqrt(2 * np.mean(y[500:-500] ** 2))
    assert gain ** 2 == pytest.approx(expected, abs=0.01)


def test_no_lag_levels_kept_at_the_ends_and_columns_apart():
    rate = 100.0
    t = np.arange(300) / rate
    x = np.stack([np.full(300, 3.0), 0.5 * t], axis=1)
    y = lowpass(x, rate, 4.0)
    np.testing.assert_allclose(y[:, 0], 3.0, atol=1e-12)
    np.testing.assert_allclose(y[50:-50, 1], x[50:-50, 1], atol=1e-12)  # a ramp passes unchanged
    short = lowpass(np.arange(5.0), rate, 1.0)
    assert short.shape == (5,) and np.all(np.isfinite(short))
    with pytest.raises(InputError):
        lowpass(x, rate, 0.0)
