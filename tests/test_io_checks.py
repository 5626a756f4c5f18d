"""Shared input checks (pipeline.io.checks) and atomic output (pipeline.io.atomic)."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import rotation_about_axis, times

from pipeline.errors import InputError
from pipeline.io import checks
from pipeline.io.notes import Notes
from pipeline.rotations import matrix_from_quat

# ---------------------------------------------------------------- time stamps


def test_time_ok_and_returned_as_float():
    t = checks.check_time([0, 1, 2])
    assert t.dtype == float and t.tolist() == [0.0, 1.0, 2.0]


def test_repeated_time_stamp_names_first_row():
    t = times(10)
    t[4] = t[3]
    with pytest.raises(InputError, match=r"repeated time stamp 0\.03 s at row 4 \(line 11\)") as e:
        checks.check_time(t, file="a.sto", first_line=7)
    assert e.value.file == "a.sto" and e.value.field == "time"


def test_unsorted_time_stamps_name_first_row():
    t = times(10)
    t[[5, 6]] = t[[6, 5]]
    with pytest.raises(InputError, match=r"not sorted: 0\.05 s at row 6 comes after 0\.06 s"):
        checks.check_time(t)


def test_unsorted_reported_before_later_repeat():
    t = np.array([0.0, 0.2, 0.1, 0.3, 0.3])
    with pytest.raises(InputError, match="not sorted.*row 2"):
        checks.check_time(t)


@pytest.mark.parametrize(
    ("t", "msg"),
    [([0.0], "at least 2 samples, found 1"), ([0.0, np.nan, 0.2], "not a finite number at row 1")],
)
def test_time_too_short_or_nan(t, msg):
    with pytest.raises(InputError, match=msg):
        checks.check_time(t)


# ---------------------------------------------------------------- rate


def test_rate_estimate_and_jitter_match_construction():
    rng = np.random.default_rng(0)
    dt = 0.01 + rng.normal(0, 1e-4, 5000)
    t = np.concatenate([[0.0], np.cumsum(dt)])
    info = checks.estimate_rate(t)
    assert info.rate_hz == pytest.approx(100.0, rel=1e-3)
    assert info.jitter_s == pytest.approx(1e-4, rel=0.05)


def test_rate_matches_declared():
    info = checks.check_rate(times(), 100.0)
    assert info.rate_hz == pytest.approx(100.0)


def test_wrong_declared_rate_refused():
    with pytest.raises(InputError, match=r"declared rate 50 Hz but the time stamps give 100 Hz"):
        checks.check_rate(times(), 50.0, file="x.sto")


def test_jitter_and_dropped_samples_noted_not_refused():
    rng = np.random.default_rng(1)
    t = np.concatenate([[0.0], np.cumsum(0.01 + rng.normal(0, 2e-3, 300))])
    notes = Notes()
    checks.check_rate(t, None, notes=notes)
    assert any("irregular sampling" in n for n in notes)
    t2 = np.delete(times(), [50, 51])
    notes2 = Notes()
    checks.check_rate(t2, 100.0, notes=notes2)
    assert any("1 interval(s) longer than 1.5 sampling periods" in n for n in notes2)


def test_mismatched_lengths_and_rates_refused():
    with pytest.raises(InputError, match=r"different numbers of samples \(acc: 100, gyr: 99\)"):
        checks.check_same_length({"acc": 100, "gyr": 99}, file="f")
    assert checks.check_same_length({"a": 5, "b": 5}) == 5
    with pytest.raises(InputError, match=r"different sampling rates \(a: 100 Hz, b: 60 Hz\)"):
        checks.check_same_rate({"a": 100.0, "b": 60.0})


# ---------------------------------------------------------------- quaternions


def test_slightly_non_unit_normalised_and_noted():
    q = rotation_about_axis(times(20))
    notes = Notes()
    out = checks.check_quaternions(q * 1.05, notes=notes, field="pelvis_imu")
    np.testing.assert_allclose(out, q, atol=1e-12)
    assert "normalised 20 quaternion(s) with |norm - 1| up to 0.05" in notes.items[0]


def test_tiny_norm_error_normalised_silently():
    q = rotation_about_axis(times(20)) * (1 + 1e-6)
    notes = Notes()
    checks.check_quaternions(q, notes=notes)
    assert len(notes) == 0


def test_far_from_unit_refused_with_norm_and_row():
    q = rotation_about_axis(times(20))
    q[7] *= 0.5
    with pytest.raises(InputError, match=r"not unit quaternions \(norm 0\.5 at row 7"):
        checks.check_quaternions(q)


def test_zero_and_nonfinite_quaternions_refused():
    q = rotation_about_axis(times(20))
    q[3] = 0
    with pytest.raises(InputError, match="zero quaternion at row 3"):
        checks.check_quaternions(q)
    q[3] = [np.inf, 0, 0, 0]
    with pytest.raises(InputError, match="non-finite quaternion at row 3"):
        checks.check_quaternions(q)
    with pytest.raises(InputError, match=r"\(N, 4\)"):
        checks.check_quaternions(np.ones((5, 3)))


def test_hemisphere_flips_fixed_silently():
    q = rotation_about_axis(times(50))
    flipped = q.copy()
    flipped[10:20] *= -1
    flipped[30] *= -1
    notes = Notes()
    out = checks.check_quaternions(flipped, notes=notes)
    assert np.all(np.sum(out[1:] * out[:-1], axis=1) > 0)
    np.testing.assert_allclose(out, q, atol=1e-12)  # q[0] kept, so same signs as the truth
    assert not notes.items  # no orientation changed, nothing to report
    np.testing.assert_allclose(matrix_from_quat(out), matrix_from_quat(flipped), atol=1e-12)


# ---------------------------------------------------------------- units


def test_positions_in_mm_given_as_m_refused():
    rng = np.random.default_rng(2)
    pts_m = rng.uniform(-1.0, 1.0, (100, 4, 3)) + [0, 0, 1.0]
    checks.check_position_units(pts_m)  # plausible
    with pytest.raises(InputError, match="look like millimetres given as metres"):
        checks.check_position_units(pts_m * 1000, file="m.c3d")


def test_gyro_in_deg_per_s_refused_rad_per_s_accepted():
    t = times(1000)
    w = np.column_stack([3 * np.sin(2 * np.pi * t), 0.5 * np.cos(3 * t), 0.1 * t])  # rad/s
    checks.check_gyro_units(w)
    with pytest.raises(InputError, match="looks like deg/s"):
        checks.check_gyro_units(np.degrees(w))


def test_acc_in_g_refused_m_per_s2_accepted():
    rng = np.random.default_rng(3)
    a = np.array([0.3, 0.2, 9.81]) + rng.normal(0, 0.5, (500, 3))
    checks.check_acc_units(a)
    with pytest.raises(InputError, match="looks like it is in g"):
        checks.check_acc_units(a / 9.81)
    with pytest.raises(InputError, match="raw counts or mm/s"):
        checks.check_acc_units(a * 1000)


def test_notes_prefix_like_errors():
    n = Notes()
    n.add("did x", file="a.sto", field="pelvis_imu")
    n.add("did y")
    assert n.as_tuple() == ("a.sto: field pelvis_imu: did x", "did y")


def test_time_in_milliseconds_is_refused_with_a_hint():
    # 100 Hz stamped in ms reads as 0.1 Hz; in us as 1e-4 Hz
    with pytest.raises(InputError, match=r"milliseconds \(that would be 100 Hz\)"):
        checks.check_rate(np.arange(50) * 10.0)
    with pytest.raises(InputError, match="microseconds"):
        checks.check_rate(np.arange(50) * 1e4)
    assert checks.check_rate(np.arange(50) / 100.0).rate_hz == pytest.approx(100.0)


def test_sto_in_milliseconds_without_datarate_is_refused(tmp_path):
    from pipeline.io.opensim import read_orientations_sto

    rows = "\n".join(f"{10 * k}\t1,0,0,0" for k in range(20))
    path = tmp_path / "ms.sto"
    path.write_text(f"DataType=Quaternion\nversion=3\nendheader\ntime\tpelvis_imu\n{rows}\n")
    with pytest.raises(InputError, match="milliseconds") as err:
        read_orientations_sto(path)
    assert str(path) in str(err.value)
