"""Tests of pipeline.io.tables by hand."""

import io

import numpy as np
import pytest

from pipeline.io.tables import csv_text, mean_sd, write_array_csv


def test_array_csv_by_hand_finite_and_missing_rows():
    buf = io.StringIO()
    data = np.array([[0.0, 1 / 3, -2.5e-7], [0.01, np.nan, 1e12], [0.02, np.inf, 7.0]])
    write_array_csv(buf, ["time", "a", "b"], data, digits=6, nan="")
    assert buf.getvalue() == ("time,a,b\n0,0.333333,-2.5e-07\n0.01,,1e+12\n0.02,,7\n")
    buf = io.StringIO()
    write_array_csv(buf, ["x"], np.array([[1.0]]), header=False)
    assert buf.getvalue() == "1\n"
    with pytest.raises(ValueError, match=r"\(N, 2\)"):
        write_array_csv(io.StringIO(), ["a", "b"], np.zeros((3, 3)))


def test_csv_text_and_mean_sd_by_hand():
    assert csv_text([{"a": 1.23456789, "b": "x"}], ["a", "b"], digits=3) == "a,b\n1.23,x\n"
    assert mean_sd([1.0, 3.0]) == "2.0±1.4"
