"""pipeline.report.plots: the report's figures as PNG, from the cycles' means as _figures.json
lists them."""

import io

import numpy as np
import pytest

from pipeline.report.plots import PANELS, cycle_figure, group_figure, skeleton_figure

pytest.importorskip("matplotlib")


def _means(sides=("right", "left"), columns=("knee_angle", "hip_flexion")):
    x = np.linspace(0, 1, 101)
    curve = {"n": 3, "mean_deg": list(30 + 30 * np.sin(2 * np.pi * x)), "sd_deg": [2.0] * 101}
    return {side: {c: curve for c in columns} for side in sides}


def _image(png: bytes) -> np.ndarray:
    from PIL import Image

    assert png[:8] == b"\x89PNG\r\n\x1a\n"
    return np.asarray(Image.open(io.BytesIO(png)).convert("RGB")).astype(int)


def _has(img: np.ndarray, colour: str) -> bool:
    rgb = np.array([int(colour[k:k + 2], 16) for k in (1, 3, 5)])
    return bool(np.any(np.all(np.abs(img - rgb) < 12, axis=2)))


def test_the_cycle_figure_draws_each_side_in_its_colour():
    img = _image(cycle_figure(_means(), {"right": 0.6, "left": 0.62}))
    assert _has(img, "#1a9641") and _has(img, "#d7191c")  # right green, left red
    one = _image(cycle_figure(_means(sides=("left",)), {"left": 0.6}))
    assert _has(one, "#d7191c") and not _has(one, "#1a9641")


def test_every_panel_has_a_column_or_says_it_is_not_measured():
    assert [len(row) for row in PANELS.values()] == [3, 3, 3, 3]
    columns = [c for row in PANELS.values() for c, _ in row if c is not None]
    from pipeline.analysis.cycles import CYCLE_COLUMNS

    assert sorted(columns) == sorted(CYCLE_COLUMNS.values())  # every cycle column is drawn


def test_the_skeleton_and_the_group_figures():
    points = {f"{side}_{lm}": np.array([0.0, -h, z]) for side, z in (("right", 0.1),
              ("left", -0.1)) for lm, h in (("HJC", 0.1), ("KJC", 0.5), ("AJC", 0.9))}
    assert _has(_image(skeleton_figure(points, "still")), "#1a9641")
    rows = _image(group_figure([("a", _means()), ("b", _means(sides=("right",)))]))
    assert rows.shape[0] > rows.shape[1] * 0.4  # two rows of curves
