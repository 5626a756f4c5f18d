"""pipeline.calibration.losses: the robust losses checked by hand at chosen residuals."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.losses import LOSSES, robust_loss
from pipeline.errors import InputError


def test_values_by_hand():
    # e = 3, c = 1: huber 2 (sqrt(10) - 1), cauchy log(10); l2 the square itself
    assert float(robust_loss(9.0, "l2", 1.0)) == 9.0
    assert float(robust_loss(9.0, "huber", 1.0)) == pytest.approx(2 * (np.sqrt(10) - 1))
    assert float(robust_loss(9.0, "cauchy", 1.0)) == pytest.approx(np.log(10))
    # the scale enters as c^2: e = 2c gives c^2 times the c = 1 value at e = 2
    assert float(robust_loss(4 * 0.01, "cauchy", 0.1)) == pytest.approx(0.01 * np.log(5))


def test_small_residuals_unweighted_and_large_ones_discounted():
    for loss in LOSSES:
        assert float(robust_loss(1e-8, loss, 1.0)) == pytest.approx(1e-8, rel=1e-6)
    assert float(robust_loss(1e4, "cauchy", 1.0)) < float(robust_loss(1e4, "huber", 1.0)) < 1e4


def test_unknown_loss_refused():
    with pytest.raises(InputError, match="loss"):
        robust_loss(1.0, "tukey", 1.0)
