"""Gap filling of missing samples (pipeline.io.gaps)."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import rotation_about_axis, times

from pipeline.errors import InputError
from pipeline.io.gaps import fill_gaps
from pipeline.io.notes import Notes
from pipeline.rotations import log3, matrix_from_quat


def test_short_vector_gap_interpolated_exactly_and_reported():
    t = times()
    truth = np.column_stack([2 * t + 1, -t, np.full_like(t, 3.0)])  # linear: exact
    v = truth.copy()
    v[50:55] = np.nan
    v[80, 1] = np.nan  # one component missing makes the sample missing
    notes = Notes()
    out = fill_gaps(t, v, notes=notes, file="f.csv", field="acc")
    np.testing.assert_allclose(out, truth, atol=1e-12)
    assert np.isnan(v[50]).all()  # input untouched
    assert len(notes) == 2
    assert "f.csv: field acc: filled 5 missing sample(s) from t=0.5 s to t=0.54 s" in notes.items[0]


def test_gap_at_ends_held_and_reported():
    t = times(50)
    v = np.arange(50.0)
    v[:3] = np.nan
    v[-2:] = np.nan
    notes = Notes()
    out = fill_gaps(t, v, notes=notes)
    assert out[:3].tolist() == [3.0] * 3 and out[-2:].tolist() == [47.0] * 2
    assert all("held the nearest valid sample" in n for n in notes)


def test_long_gap_refused_with_time_range():
    t = times()
    v = np.ones((200, 3))
    v[100:120] = np.nan  # 0.2 s
    with pytest.raises(
        InputError, match=r"gap of 20 missing samples \(0\.2 s\) from t=1 s to t=1\.19 s"
    ):
        fill_gaps(t, v, max_gap_s=0.1)
    out = fill_gaps(t, v, max_gap_s=0.25)  # allowed when the user says so
    assert np.isfinite(out).all()


def test_gap_exactly_max_length_is_filled():
    t = times()
    v = np.ones(200)
    v[10:20] = np.nan  # 10 samples = 0.1 s
    assert np.isfinite(fill_gaps(t, v, max_gap_s=0.1)).all()


def test_all_missing_refused():
    with pytest.raises(InputError, match="no finite values"):
        fill_gaps(times(10), np.full((10, 3), np.nan))


def test_quaternion_gap_filled_by_slerp_matches_truth():
    t = times()
    truth = rotation_about_axis(t)
    q = truth.copy()
    q[60:68] = np.nan
    q[68:] *= -1  # neighbour in the other hemisphere: same rotation, slerp must not care
    notes = Notes()
    out = fill_gaps(t, q, kind="quaternion", notes=notes)
    err = angle_between_rotations(out[60:68], truth[60:68])
    assert err.max() < 1e-9
    assert "slerp" in notes.items[0]


def test_zero_quaternion_next_to_gap_refused():
    q = rotation_about_axis(times(20))
    q[5:7] = np.nan
    q[7] = 0.0
    with pytest.raises(InputError, match="zero quaternion at row 7"):
        fill_gaps(times(20), q, kind="quaternion")


def angle_between_rotations(q1, q2):
    R = np.swapaxes(matrix_from_quat(q1), -1, -2) @ matrix_from_quat(q2)
    return np.linalg.norm(log3(R), axis=-1)
