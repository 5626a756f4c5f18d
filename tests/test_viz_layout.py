"""Tests of pipeline.viz.layout: the default blueprint, saved to a file and read back."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from _helpers import blueprint_views, read_blueprint

from pipeline.errors import InputError
from pipeline.viz.layout import default_blueprint, up_axis_index


def _saved(blueprint, path: Path) -> dict[str, dict[str, list]]:
    """Save ``blueprint`` and read it back as the viewer does."""
    blueprint.save("test_viz_layout", path)
    return read_blueprint(path)


def _containers(bp: dict[str, dict[str, list]]) -> dict[str, dict[str, list]]:
    return {p: v for p, v in bp.items() if "ContainerBlueprint:container_kind" in v}


def test_up_axis_index():
    assert up_axis_index("y") == 1
    assert up_axis_index("z") == 2
    with pytest.raises(InputError, match="up_axis") as err:
        up_axis_index("x")
    assert err.value.field == "up_axis"
    with pytest.raises(InputError):
        default_blueprint([], "x")


def test_3d_view_beside_a_two_column_grid_of_plots(tmp_path):
    plots = [("a", "/plots/a"), ("b", ["/plots/x", "/plots/y"]), ("c", "/plots/c")]
    bp = _saved(default_blueprint(plots, "z"), tmp_path / "bp.rbl")
    views = blueprint_views(bp)
    assert {k: v[:2] for k, v in views.items()} == {
        "3D": ("3D", "/world"),
        "a": ("TimeSeries", "/plots/a"),
        "b": ("TimeSeries", "/"),  # an explicit list of entities: rooted at "/"
        "c": ("TimeSeries", "/plots/c"),
    }
    assert bp[f"{views['b'][2]}/ViewContents"]["ViewContents:query"] == ["/plots/x", "/plots/y"]
    assert bp[f"{views['a'][2]}/ViewContents"]["ViewContents:query"] == ["$origin/**"]
    (grid,) = [v for v in _containers(bp).values() if "ContainerBlueprint:grid_columns" in v]
    assert grid["ContainerBlueprint:grid_columns"] == [2]
    assert grid["ContainerBlueprint:contents"] == [views[k][2][1:] for k in ("a", "b", "c")]
    (row,) = [v for v in _containers(bp).values() if "ContainerBlueprint:col_shares" in v]
    assert row["ContainerBlueprint:col_shares"] == [3.0, 2.0]  # the 3D view takes 3/5
    assert row["ContainerBlueprint:contents"][0] == views["3D"][2][1:]
    # no camera or ground given: the viewer frames the scene, grid through the origin
    assert not any(p.endswith(("/EyeControls3D", "/LineGrid3D")) for p in bp)


def test_single_plot_one_column_and_no_plot_only_3d(tmp_path):
    bp = _saved(default_blueprint([("angles", "/plots")], "z"), tmp_path / "one.rbl")
    (grid,) = [v for v in _containers(bp).values() if "ContainerBlueprint:grid_columns" in v]
    assert grid["ContainerBlueprint:grid_columns"] == [1]
    bp = _saved(default_blueprint([], "z"), tmp_path / "none.rbl")
    assert {k: v[:2] for k, v in blueprint_views(bp).items()} == {"3D": ("3D", "/world")}
    assert not any("ContainerBlueprint:col_shares" in v for v in bp.values())


@pytest.mark.parametrize("up_axis", ["y", "z"])
def test_orbital_camera_and_ground_grid_follow_up_axis(tmp_path, up_axis):
    import rerun.blueprint as rrb

    up = np.eye(3)[up_axis_index(up_axis)]
    eye, target = np.array([1.5, 0.4, 1.2]), np.array([0.0, -0.5, 0.1])
    blueprint = default_blueprint([], up_axis, camera=(eye, target), ground=-0.9)
    bp = _saved(blueprint, tmp_path / "cam.rbl")
    path3d = blueprint_views(bp)["3D"][2]
    controls = bp[f"{path3d}/EyeControls3D"]
    assert controls["EyeControls3D:kind"] == [rrb.Eye3DKind.Orbital.value]
    np.testing.assert_allclose(controls["EyeControls3D:position"][0], eye, rtol=1e-6)
    np.testing.assert_allclose(controls["EyeControls3D:look_target"][0], target, rtol=1e-6)
    np.testing.assert_allclose(controls["EyeControls3D:eye_up"][0], up)
    grid = bp[f"{path3d}/LineGrid3D"]
    assert grid["LineGrid3D:visible"] == [True]
    assert grid["LineGrid3D:spacing"] == [0.5]
    # rerun's Hesse form dot(n, P) - d = 0 with n = up, d = ground: the plane height -0.9 m
    plane = np.array(grid["LineGrid3D:plane"][0])
    np.testing.assert_allclose(plane[:3], up)
    point_on_ground = np.array([0.3, 0.2, 0.7])
    point_on_ground[up_axis_index(up_axis)] = -0.9
    assert plane[:3] @ point_on_ground - plane[3] == pytest.approx(0.0, abs=1e-6)


def test_panels_collapsed_selection_and_time_playing_in_a_loop(tmp_path):
    from rerun.blueprint.components import LoopMode, PanelState, PlayState

    bp = _saved(default_blueprint([("angles", "/plots")], "y"), tmp_path / "panels.rbl")
    assert bp["/selection_panel"]["PanelBlueprint:state"] == [PanelState.Collapsed.value]
    panel = bp["/time_panel"]
    assert panel["TimePanelBlueprint:timeline"] == ["time"]
    assert panel["TimePanelBlueprint:play_state"] == [PlayState.Playing.value]
    assert panel["TimePanelBlueprint:loop_mode"] == [LoopMode.All.value]
