"""Tests of pipeline.quantiles: NumPy's values (median, linear quantiles) by hand and against
NumPy, without importing numpy.ma."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from pipeline.quantiles import median, nanmedian, quantile


def test_by_hand():
    assert median([3.0, 1.0, 2.0]) == 2.0
    assert median([4.0, 1.0, 2.0, 3.0]) == 2.5
    assert quantile([0.0, 10.0], 0.25) == 2.5  # a quarter of the way
    assert quantile([5.0, 1.0, 3.0], 1.0) == 5.0 and quantile([5.0, 1.0, 3.0], 0.0) == 1.0
    assert nanmedian([np.nan, 1.0, 3.0]) == 2.0 and np.isnan(nanmedian([np.nan]))


def test_equal_to_numpy():
    rng = np.random.default_rng(0)
    for n in (1, 2, 3, 10, 101, 1400):
        x = rng.standard_normal(n)
        assert median(x) == float(np.median(x))
        for q in (0.0, 0.05, 1 / 3, 0.5, 0.7, 0.95, 1.0):
            assert quantile(x, q) == float(np.quantile(x, q))


def test_refusals():
    with pytest.raises(ValueError):
        median([])
    with pytest.raises(ValueError):
        quantile([1.0], 1.5)


def test_no_numpy_ma_import():
    code = ("import sys; from pipeline.quantiles import median, quantile; "
            "median([1.0, 2.0]); quantile([1.0, 2.0], 0.3); print('numpy.ma' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
