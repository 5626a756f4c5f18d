"""Default layout (rerun blueprint) of the recordings written by :mod:`pipeline.viz.recording`.

The viewer opens the 3D view of ``world`` (3/5 of the width) beside the time-series views, laid
out in a grid of two columns (rerun's own heuristic would open one small plot per angle, leave
some out and shrink the 3D view to a tile). The 3D view may get an orbital camera (eye position
and look target, ``up_axis`` up) and a line grid on the ground plane ``{P : up . P = ground}``.
The time panel shows timeline ``time``, playing from the start in a loop (the viewer would
otherwise jump to the last frame); the selection panel starts collapsed.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pipeline.errors import InputError
from pipeline.viz.arrow import pandas_shortcut_if_asked
from pipeline.viz.rrd import Layout

__all__ = ["default_blueprint", "default_layout", "sdk_blueprint", "up_axis_index"]


def up_axis_index(up_axis: str) -> int:
    """Index (1 or 2) of the vertical coordinate for ``up_axis`` 'y' or 'z'."""
    if up_axis not in ("y", "z"):
        raise InputError(f"up_axis must be 'y' or 'z', got {up_axis!r}", field="up_axis")
    return 1 if up_axis == "y" else 2


def default_layout(
    plots: Sequence[tuple[str, str | Sequence[str]]],
    up_axis: str,
    camera: tuple[np.ndarray, np.ndarray] | None = None,
    ground: float | None = None,
) -> Layout:
    """Default layout: the 3D view of ``world`` (3/5 of the width) beside the time-series views.

    ``plots``: (view title, origin entity or list of entity paths) per time-series view, laid out
    in a grid of two columns (one column for a single view). ``camera``: (eye position, look
    target) in ``world`` (m), orbiting about the target with ``up_axis`` up; ``None`` lets the
    viewer frame the scene. ``ground``: height (m) along ``up_axis`` of the 3D view's line grid
    (default: the plane through the origin). The selection panel starts collapsed.
    """
    up = [0.0, 0.0, 0.0]
    up[up_axis_index(up_axis)] = 1.0
    views = tuple((str(title), what if isinstance(what, str) else tuple(map(str, what)))
                  for title, what in plots)
    cam = None
    if camera is not None:
        cam = tuple(tuple(float(x) for x in np.asarray(v, dtype=float)) for v in camera)
    return Layout(views, 2 if len(views) > 1 else 1, tuple(up), cam,
                  None if ground is None else float(ground))


def default_blueprint(
    plots: Sequence[tuple[str, str | Sequence[str]]],
    up_axis: str,
    camera: tuple[np.ndarray, np.ndarray] | None = None,
    ground: float | None = None,
):
    """:func:`default_layout` as a ``rerun.blueprint.Blueprint`` (rerun's Python API: e.g. a
    ``.rbl`` file, a viewer). Recordings carry the same layout, written by
    :mod:`pipeline.viz.rrd`."""
    return sdk_blueprint(default_layout(plots, up_axis, camera, ground))


def sdk_blueprint(spec: Layout):
    """A :class:`~pipeline.viz.rrd.Layout` as a ``rerun.blueprint.Blueprint``."""
    pandas_shortcut_if_asked()  # before rerun converts the blueprint's first list
    import rerun as rr  # deferred: importing rerun costs ~0.3 s
    import rerun.blueprint as rrb

    up = np.array(spec.up)
    options = {}
    if spec.camera is not None:
        position, target = (np.array(v) for v in spec.camera)
        options["eye_controls"] = rrb.EyeControls3D(
            kind=rrb.Eye3DKind.Orbital, position=position, look_target=target, eye_up=up
        )
    if spec.ground is not None:
        plane = rr.components.Plane3D(up, spec.ground)  # {P : up . P = ground}
        options["line_grid"] = rrb.LineGrid3D(visible=True, spacing=0.5, plane=plane)
    view3d = rrb.Spatial3DView(origin="/world", name="3D", **options)
    views = []
    for title, what in spec.views:
        if isinstance(what, str):
            views.append(rrb.TimeSeriesView(origin=what, name=title))
        else:
            views.append(rrb.TimeSeriesView(origin="/", contents=list(what), name=title))
    # open playing from the start in a loop (the viewer would otherwise jump to the last frame)
    parts = [
        rrb.SelectionPanel(state="collapsed"),
        rrb.TimePanel(timeline="time", play_state="Playing", loop_mode="All"),
    ]
    if not views:
        return rrb.Blueprint(view3d, *parts)
    grid = rrb.Grid(*views, grid_columns=spec.grid_columns)
    return rrb.Blueprint(rrb.Horizontal(view3d, grid, column_shares=[3, 2]), *parts)
