"""pipeline.analysis.strides: stride parameters of the simulated foot (known truth), the CSV's
exact columns and the summary."""

import csv
import io

import numpy as np

from pipeline.analysis.foot_trajectory import foot_trajectory
from pipeline.analysis.gait_events import GaitEvents, gait_events
from pipeline.analysis.strides import (
    STRIDE_COLUMNS,
    foot_strides,
    stride_summary,
    stride_table,
    strides_csv,
)
from pipeline.simulate.foot_walk import Pace, foot_walk


def _strides(**kw):
    w = foot_walk(**kw)
    ev = gait_events(w.gyr, w.acc, w.rate_hz)
    return w, foot_strides("left", w.time, ev, foot_trajectory(w.gyr, w.acc, w.rate_hz,
                                                                ev.rests))


def test_the_simulated_strides():
    w, strides = _strides(strides=7, pace=Pace(1.2, 1.4), clearance_m=0.1,
                          turns_deg=(0, 0, 70), seed=4)
    assert len(strides) == 6  # 7 swings: 7 detected ICs, 6 strides between them
    for s in strides:
        assert abs(s.stride_time_s - 1.2) < 0.005 and abs(s.cadence_steps_min - 100.0) < 0.5
        assert abs(s.stance_share - 0.6) < 0.01 and abs(s.stride_length_m - 1.4) < 0.02
        assert abs(s.speed_m_s - 1.4 / 1.2) < 0.02 and abs(s.clearance_m - 0.1) < 0.03
    turns = [round(s.turn_deg) for s in strides]
    assert turns[1] == 70 and all(abs(t) <= 1 for i, t in enumerate(turns) if i != 1)
    assert [s.straight for s in strides] == [True, False, True, True, True, True]


def test_a_pause_is_no_stride_and_a_shank_has_no_length():
    t = np.arange(1000) / 100.0
    ev = GaitEvents(np.zeros((0, 2), int), np.array([150, 260, 800]),
                    np.array([200.0, 310.0, 900.0]), np.array([140.0, 250.0, 790.0]),
                    np.array([0.0, 1.0, 0.0]))
    (s,) = foot_strides("right", t, ev, None)  # 3.1 -> 9.0 s is a pause, not a stride
    assert (s.start_s, s.end_s) == (2.0, 3.1) and abs(s.stance_share - 0.5 / 1.1) < 1e-9
    assert np.isnan(s.stride_length_m) and np.isnan(s.turn_deg) and s.straight is False


def test_the_csv_has_exactly_the_issues_columns():
    _, strides = _strides(strides=4, seed=1)
    rows = list(csv.reader(io.StringIO(strides_csv(strides))))
    assert tuple(rows[0]) == ("stride", *STRIDE_COLUMNS, "in_means")
    assert STRIDE_COLUMNS == (
        "side", "start_s", "end_s", "stride_time_s", "stance_share", "stride_length_m",
        "speed_m_s", "cadence_steps_min", "clearance_m", "turn_deg", "straight",
        "steady")
    assert len(rows) == 1 + len(strides) and {r[1] for r in rows[1:]} == {"left"}
    assert [r[0] for r in rows[1:]] == ["1", "2", "3"]
    assert {r[-3] for r in rows[1:]} == {"true"}
    assert [r[-2] for r in rows[1:]] == ["false", "true", "false"]  # the walk's start and stop
    assert [r[-1] for r in rows[1:]] == ["false", "true", "false"]  # in the means
    assert abs(float(rows[1][6]) - 1.3) < 0.02


def test_the_summary_by_side_over_the_straight_steady_strides():
    """Six strides, the second turning 70 deg: the first and the last start and stop the walk,
    the third comes out of the turn (a straight walk's first), the turning one is left out: two
    in the means, each reason counted."""
    _, left = _strides(strides=7, seed=1, turns_deg=(0, 0, 70))
    assert [s.straight for s in left] == [True, False, True, True, True, True]
    assert [s.steady for s in left] == [False, False, False, True, True, False]
    summary = stride_summary(left)
    mean, sd, n = summary["left"]["stride_length_m"]
    assert n == 2 and abs(mean - 1.3) < 0.02 and sd < 0.01
    assert summary["right"]["stride_length_m"][2] == 0
    text = "\n".join(stride_table(left))
    assert "| stride length (m) |  | 1.30 ± 0.00 | 1.30 ± 0.00 |" in text
    assert "| strides turning 20 deg or more | | | 1 |" in text
    assert ("| strides starting or stopping a straight walk (from standing or a turn) | | | 3 |"
            in text)


def test_a_missed_contact_is_left_out_of_the_means():
    """Two strides merged by a missed contact (2.2 s among strides of 1.1): not steady, counted
    as such, not averaged."""
    from dataclasses import replace

    from pipeline.analysis.strides import left_out, mark_steady

    _, left = _strides(strides=8, seed=1)
    merged = replace(left[2], end_s=left[3].end_s, stride_time_s=2.2)
    joined = mark_steady(left[:2] + [merged] + left[4:])
    assert [s.steady for s in joined] == [False, True, False, True, True, False]
    assert left_out(joined) == {"turning": 0, "starting or stopping": 2, "merged": 1}
    mean = stride_summary(joined)["left"]["stride_time_s"][0]
    assert abs(mean - 1.1) < 0.01
