"""Joint angles over the gait cycle: known curves back at 0-100 %, gaps never bridged."""

import csv
import io

import numpy as np

from pipeline.analysis.cycles import (
    CYCLE_POINTS,
    cycle_angles,
    cycle_means,
    cycle_table,
    cycles_csv,
    cycles_figures,
)
from pipeline.analysis.strides import Stride, mark_steady

RATE = 100.0


def _walk(n_strides=6, period=1.1, side="right", turn_at=None):
    """Strides back to back from t = 0.5 s; the knee's flexion a known function of the phase."""
    starts = 0.5 + period * np.arange(n_strides + 1)
    strides = [Stride(side, float(a), float(b), float(b - a), 0.6, 1.3, 1.3 / (b - a),
                      120 / (b - a), 0.1, 40.0 if k == turn_at else 0.0, k != turn_at)
               for k, (a, b) in enumerate(zip(starts[:-1], starts[1:], strict=True))]
    time = np.arange(0, starts[-1] + 0.5, 1 / RATE)
    phase = np.clip((time - 0.5) / period, 0, None) % 1.0
    knee = np.radians(30 + 30 * np.sin(2 * np.pi * phase))
    angles = {f"{side}_knee_flexion": knee, "pelvis_rotation": np.radians(90 + 0 * time)}
    return time, angles, mark_steady(strides)


def test_a_known_curve_comes_back_at_each_percent():
    time, angles, strides = _walk()
    cycles = cycle_angles(time, angles, strides)
    expected = np.radians(30 + 30 * np.sin(2 * np.pi * np.linspace(0, 1, CYCLE_POINTS)))
    assert cycles.angles["knee_angle"].shape == (6, CYCLE_POINTS)
    assert np.max(np.abs(cycles.angles["knee_angle"][2] - expected)) < np.radians(0.2)
    # the pelvis's rotation about the direction of progression: its heading of 90 deg taken out
    assert np.allclose(cycles.angles["pelvis_rotation"], 0.0)
    assert "hip_flexion" not in cycles.angles  # a joint the run does not have


def test_a_gap_in_a_stride_leaves_that_stride_without_a_curve():
    time, angles, strides = _walk()
    k = int(np.searchsorted(time, strides[3].start_s + 0.3))
    angles["right_knee_flexion"][k:k + 5] = np.nan
    curves = cycle_angles(time, angles, strides).angles["knee_angle"]
    assert np.all(np.isnan(curves[3])) and np.all(np.isfinite(curves[[1, 2, 4]]))


def test_the_means_are_over_the_straight_steady_strides_only():
    time, angles, strides = _walk(n_strides=7, turn_at=3)
    angles["right_knee_flexion"] = angles["right_knee_flexion"] + np.radians(
        20.0 * ((time > strides[3].start_s) & (time < strides[3].end_s)))  # the turn differs
    means = cycle_means(cycle_angles(time, angles, strides))
    knee = means["right"]["knee_angle"]
    # 7 strides: the first, the last, the turning one and the two beside it left out
    assert knee.n == 2
    expected = np.radians(30 + 30 * np.sin(2 * np.pi * np.linspace(0, 1, CYCLE_POINTS)))
    assert np.max(np.abs(knee.mean - expected)) < np.radians(0.2)
    assert np.max(knee.sd) < np.radians(0.2) and means["left"] == {}


def test_the_csv_has_101_rows_per_stride_in_degrees():
    time, angles, strides = _walk(n_strides=3)
    rows = list(csv.DictReader(io.StringIO(cycles_csv(cycle_angles(time, angles, strides)))))
    assert len(rows) == 3 * CYCLE_POINTS
    assert list(rows[0])[:6] == ["stride", "side", "straight", "steady", "in_means",
                                 "cycle_percent"]
    assert [r["stride"] for r in rows[::CYCLE_POINTS]] == ["1", "2", "3"]
    assert [r["in_means"] for r in rows[::CYCLE_POINTS]] == ["false", "true", "false"]
    quarter = rows[CYCLE_POINTS + 25]
    assert quarter["cycle_percent"] == "25" and abs(float(quarter["knee_angle"]) - 60.0) < 0.2


def test_the_figures_and_the_table_state_the_same_means():
    time, angles, strides = _walk(n_strides=6)
    cycles = cycle_angles(time, angles, strides)
    fig = cycles_figures(cycles)["right"]["knee_angle"]
    assert fig["n"] == 4 and len(fig["mean_deg"]) == CYCLE_POINTS
    assert abs(max(fig["mean_deg"]) - 60.0) < 0.2
    row = next(line for line in cycle_table(cycles) if line.startswith("| knee_angle"))
    assert row.startswith("| knee_angle | 60.0 ± 0.0 | 0.0 ± 0.0 | 60.0 ± 0.0 |")


def test_a_side_without_a_steady_stride_is_averaged_over_its_straight_ones_and_says_so():
    """Two strides: the walk's start and its stop, neither steady; the means are over both,
    named as such in the figures and the summary, never silently empty nor called steady."""
    from pipeline.analysis.cycles import STEADY, STRAIGHT_ONLY, cycle_table, cycles_figures

    time, angles, strides = _walk(n_strides=2)
    assert not any(s.steady for s in strides)
    cycles = cycle_angles(time, angles, strides)
    knee = cycle_means(cycles)["right"]["knee_angle"]
    assert (knee.n, knee.over) == (2, STRAIGHT_ONLY)
    assert cycles_figures(cycles)["right"]["knee_angle"]["over"] == STRAIGHT_ONLY
    assert any("right side's means are over its straight strides" in line
               for line in cycle_table(cycles))
    time, angles, strides = _walk(n_strides=4)  # two steady strides: the means over them
    assert cycle_means(cycle_angles(time, angles, strides))["right"]["knee_angle"].over == STEADY
