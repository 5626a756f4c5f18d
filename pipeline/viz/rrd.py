"""A rerun recording (``.rrd``) written by rerun's own native writer, without the ``rerun``
Python package.

``import rerun`` costs a command ~0.3-0.4 s: hundreds of generated archetype, component and
blueprint classes, of which a recording of a motion uses a dozen. What those classes finally do is
hand Arrow arrays, each tagged with a component descriptor (archetype, component, component
type), to the SDK's compiled core, the ``rerun_bindings`` extension that ``rerun-sdk`` ships
(``log_arrow_msg`` for a static batch, ``send_arrow_chunk`` for columns over a timeline), and
save the stream with
a blueprint recorded the same way. :class:`RrdWriter` makes those same calls with the same
arrays, built here with pyarrow from NumPy (``_FIELDS``: the descriptors and Arrow types of the
archetype fields the pipeline logs), so the file is written by rerun itself and a command pays
~0.06 s of imports (pyarrow and the extension) instead.

The descriptors are those of rerun-sdk :data:`RERUN_VERSION` (the version ``pyproject.toml``
allows); ``tests/test_viz_rrd.py`` writes the same content through rerun's Python API and checks
that both files hold the same chunks and the same blueprint (up to its random view ids). Another
version of rerun is refused with a message (:func:`check_version`) rather than written wrongly.
Blueprint enum values (container kinds, panel states, ...) are rerun's, listed in ``_ENUMS``.
"""

from __future__ import annotations

import uuid
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = ["RERUN_VERSION", "Layout", "RrdWriter", "check_version", "pack_colors", "rrd_problem",
           "warm"]

#: The rerun-sdk release series whose component descriptors ``_FIELDS`` holds.
RERUN_VERSION = "0.41"

_VEC3, _VEC4, _MAT3 = "vec3", "vec4", "mat3"  # Arrow kinds: see _FIXED
#: (archetype, field) -> (component type, Arrow kind); the component is "<archetype>:<field>".
_FIELDS = {
    ("Points3D", "positions"): ("rerun.components.Position3D", _VEC3),
    ("Points3D", "radii"): ("rerun.components.Radius", "f32"),
    ("Points3D", "colors"): ("rerun.components.Color", "rgba"),
    ("Points3D", "labels"): ("rerun.components.Text", "text"),
    ("Points3D", "show_labels"): ("rerun.components.ShowLabels", "bool"),
    ("Arrows3D", "origins"): ("rerun.components.Position3D", _VEC3),
    ("Arrows3D", "vectors"): ("rerun.components.Vector3D", _VEC3),
    ("Arrows3D", "colors"): ("rerun.components.Color", "rgba"),
    ("Mesh3D", "vertex_positions"): ("rerun.components.Position3D", _VEC3),
    ("Mesh3D", "triangle_indices"): ("rerun.components.TriangleIndices", "u32x3"),
    ("Mesh3D", "vertex_normals"): ("rerun.components.Vector3D", _VEC3),
    ("Mesh3D", "albedo_factor"): ("rerun.components.AlbedoFactor", "rgba"),
    ("Transform3D", "translation"): ("rerun.components.Translation3D", _VEC3),
    ("Transform3D", "quaternion"): ("rerun.components.RotationQuat", _VEC4),
    ("Transform3D", "mat3x3"): ("rerun.components.TransformMat3x3", _MAT3),
    ("Transform3D", "parent_frame"): ("rerun.components.TransformFrameId", "text"),
    ("Transform3D", "child_frame"): ("rerun.components.TransformFrameId", "text"),
    ("TransformAxes3D", "axis_length"): ("rerun.components.AxisLength", "f32"),
    ("LineStrips3D", "strips"): ("rerun.components.LineStrip3D", "strip"),
    ("LineStrips3D", "radii"): ("rerun.components.Radius", "f32"),
    ("LineStrips3D", "colors"): ("rerun.components.Color", "rgba"),
    ("SeriesLines", "colors"): ("rerun.components.Color", "rgba"),
    ("SeriesLines", "names"): ("rerun.components.Name", "text"),
    ("SeriesLines", "widths"): ("rerun.components.StrokeWidth", "f32"),
    ("Scalars", "scalars"): ("rerun.components.Scalar", "f64"),
    ("ViewCoordinates", "xyz"): ("rerun.components.ViewCoordinates", "u8x3"),
    # blueprint archetypes (rerun.blueprint.archetypes.*)
    ("ViewContents", "query"): ("rerun.blueprint.components.QueryExpression", "text"),
    ("ViewBlueprint", "class_identifier"): ("rerun.blueprint.components.ViewClass", "text"),
    ("ViewBlueprint", "display_name"): ("rerun.components.Name", "text"),
    ("ViewBlueprint", "space_origin"): ("rerun.blueprint.components.ViewOrigin", "text"),
    ("LineGrid3D", "visible"): ("rerun.components.Visible", "bool"),
    ("LineGrid3D", "spacing"): ("rerun.blueprint.components.GridSpacing", "f32"),
    ("LineGrid3D", "plane"): ("rerun.components.Plane3D", _VEC4),
    ("EyeControls3D", "kind"): ("rerun.blueprint.components.Eye3DKind", "u8"),
    ("EyeControls3D", "position"): ("rerun.components.Position3D", _VEC3),
    ("EyeControls3D", "look_target"): ("rerun.components.Position3D", _VEC3),
    ("EyeControls3D", "eye_up"): ("rerun.components.Vector3D", _VEC3),
    ("ContainerBlueprint", "container_kind"): ("rerun.blueprint.components.ContainerKind", "u8"),
    ("ContainerBlueprint", "contents"): ("rerun.blueprint.components.IncludedContent", "text"),
    ("ContainerBlueprint", "grid_columns"): ("rerun.blueprint.components.GridColumns", "u32"),
    ("ContainerBlueprint", "col_shares"): ("rerun.blueprint.components.ColumnShare", "f32"),
    ("ViewportBlueprint", "root_container"): ("rerun.blueprint.components.RootContainer", "uuid"),
    ("PanelBlueprint", "state"): ("rerun.blueprint.components.PanelState", "u8"),
    ("TimePanelBlueprint", "timeline"): ("rerun.blueprint.components.TimelineName", "text"),
    ("TimePanelBlueprint", "loop_mode"): ("rerun.blueprint.components.LoopMode", "u8"),
    ("TimePanelBlueprint", "play_state"): ("rerun.blueprint.components.PlayState", "u8"),
}
_BLUEPRINT = {"ViewContents", "ViewBlueprint", "LineGrid3D", "EyeControls3D", "ContainerBlueprint",
              "ViewportBlueprint", "PanelBlueprint", "TimePanelBlueprint"}
#: rerun's enum values used by the layout
_ENUMS = {"tabs": 1, "horizontal": 2, "grid": 4, "orbital": 2, "collapsed": 2, "loop_all": 3,
          "playing": 2}
#: ViewCoordinates of a right-handed world with y or z up (x right ... as rerun encodes them)
VIEW_COORDINATES = {"y": (3, 1, 6), "z": (3, 5, 1)}


def _bindings():
    import rerun_bindings

    return rerun_bindings


def check_version() -> None:
    """Refuse a rerun-sdk other than :data:`RERUN_VERSION` (its descriptors may differ)."""
    words = _bindings().version().split()
    found = words[1] if len(words) > 1 else "?"
    if not found.startswith(RERUN_VERSION + "."):
        raise RuntimeError(f"recordings are written for rerun-sdk {RERUN_VERSION}.x, found "
                           f"{found}: pip install 'rerun-sdk=={RERUN_VERSION}.*'")


def pack_colors(colors: Sequence[Sequence[int]]) -> np.ndarray:
    """RGB(A) 0-255 colours as rerun's packed ``0xRRGGBBAA`` (alpha 255 if not given)."""
    out = []
    for c in colors:
        r, g, b, a = (*c, 255) if len(c) == 3 else c
        out.append((int(r) << 24) | (int(g) << 16) | (int(b) << 8) | int(a))
    return np.array(out, dtype=np.uint32)


def _arrow(kind: str, value) -> object:
    """The Arrow array of ``value`` (one batch of instances) for an Arrow ``kind``."""
    import pyarrow as pa

    if kind in _FIXED:
        item, n = _FIXED[kind]
        if kind == _MAT3:  # rerun's matrices are column-major
            value = np.swapaxes(np.asarray(value, dtype=float).reshape(-1, 3, 3), 1, 2)
        return _fixed(value, item, n)
    if kind == "strip":  # (strips, points, 3): one line strip per item
        v = np.asarray(value, dtype=np.float32)
        points = _fixed(v.reshape(-1, 3), "float32", 3)
        offsets = np.arange(0, v.shape[0] * v.shape[1] + 1, max(v.shape[1], 1), dtype=np.int32)
        item = pa.field("item", points.type, nullable=False)
        return pa.ListArray.from_arrays(pa.array(offsets), points, type=pa.list_(item))
    if kind in _SCALARS:
        dtype = _SCALARS[kind]
        return pa.array(np.asarray(value, dtype=dtype).reshape(-1), pa.from_numpy_dtype(dtype))
    if kind == "text":
        return pa.array([str(v) for v in value], pa.utf8())
    raise ValueError(f"unknown Arrow kind {kind!r}")


#: fixed-size lists: kind -> (NumPy item type, size)
_FIXED = {_VEC3: ("float32", 3), _VEC4: ("float32", 4), _MAT3: ("float32", 9),
          "u32x3": ("uint32", 3), "u8x3": ("uint8", 3), "uuid": ("uint8", 16)}
_SCALARS = {"f32": "float32", "f64": "float64", "u8": "uint8", "u32": "uint32", "rgba": "uint32",
            "bool": "bool"}


def _fixed(value, item: str, n: int):
    """``value`` (M, n) as Arrow ``fixed_size_list<item not null>[n]``, rerun's vectors."""
    import pyarrow as pa

    flat = np.ascontiguousarray(value, dtype=item).reshape(-1)
    typ = pa.from_numpy_dtype(np.dtype(item))
    return pa.FixedSizeListArray.from_arrays(
        pa.array(flat, typ), type=pa.list_(pa.field("item", typ, nullable=False), n))


def _components(archetype: str, fields: dict, columns: bool) -> dict:
    """``{descriptor: Arrow array}``; with ``columns`` each field's first axis is the rows, each
    row one instance (partitioned by a list array)."""
    import pyarrow as pa

    rb = _bindings()
    prefix = "rerun.blueprint.archetypes." if archetype in _BLUEPRINT else "rerun.archetypes."
    out = {}
    for name, value in fields.items():
        try:
            ctype, kind = _FIELDS[(archetype, name)]
        except KeyError:
            raise ValueError(f"{archetype}.{name} is not a field this writer knows") from None
        arr = _arrow(kind, value)
        if columns:
            offsets = pa.array(np.arange(len(arr) + 1, dtype=np.int32))
            arr = pa.ListArray.from_arrays(offsets, arr)
        desc = rb.ComponentDescriptor(f"{archetype}:{name}", archetype=prefix + archetype,
                                      component_type=ctype)
        out[desc] = arr
    return out


@dataclass(frozen=True)
class Layout:
    """The viewer's default layout (:func:`pipeline.viz.layout.default_layout`): the 3D view of
    ``world`` (3/5 of the width) beside ``views`` (title, origin entity or list of entities) in
    a grid of ``grid_columns``; ``up`` (3,) the vertical, ``camera`` (eye, target) or None,
    ``ground`` the height of the line grid or None; the time panel plays timeline ``time`` in a
    loop, the selection panel starts collapsed."""

    views: tuple[tuple[str, str | tuple[str, ...]], ...]
    grid_columns: int
    up: tuple[float, float, float]
    camera: tuple[tuple[float, ...], tuple[float, ...]] | None
    ground: float | None


def _log_blueprint(rec, layout: Layout) -> None:
    rb = _bindings()

    def log(entity, archetype, static=False, **fields):
        rb.log_arrow_msg(entity, components=_components(archetype, fields, False),
                         static_=static, recording=rec)

    def view(cls, title, origin, query, **properties) -> str:
        path = f"view/{uuid.uuid4()}"
        log(f"{path}/ViewContents", "ViewContents", query=query)
        log(path, "ViewBlueprint", class_identifier=[cls], display_name=[title],
            space_origin=[origin])
        for archetype, fields in properties.items():
            log(f"{path}/{archetype}", archetype, **fields)
        return path

    props = {}
    if layout.ground is not None:  # rerun's plane: {P : n . P - d = 0}
        props["LineGrid3D"] = dict(visible=[True], spacing=[0.5],
                                   plane=[[*layout.up, float(layout.ground)]])
    if layout.camera is not None:
        eye, target = layout.camera
        props["EyeControls3D"] = dict(kind=[_ENUMS["orbital"]], position=[eye],
                                      look_target=[target], eye_up=[layout.up])
    view3d = view("3D", "3D", "/world", ["$origin/**"], **props)
    paths = []
    for title, what in layout.views:
        if isinstance(what, str):
            paths.append(view("TimeSeries", title, what, ["$origin/**"]))
        else:
            paths.append(view("TimeSeries", title, "/", list(what)))

    def container(kind, contents, **fields) -> uuid.UUID:
        cid = uuid.uuid4()
        log(f"container/{cid}", "ContainerBlueprint", container_kind=[_ENUMS[kind]],
            contents=contents, **fields)
        return cid

    if paths:
        grid = container("grid", paths, grid_columns=[layout.grid_columns])
        root = container("horizontal", [view3d, f"container/{grid}"], col_shares=[3.0, 2.0])
    else:
        root = container("tabs", [view3d])
    log("viewport", "ViewportBlueprint", root_container=[np.frombuffer(root.bytes, np.uint8)])
    log("selection_panel", "PanelBlueprint", state=[_ENUMS["collapsed"]])
    log("time_panel", "TimePanelBlueprint", timeline=["time"], loop_mode=[_ENUMS["loop_all"]])
    log("time_panel", "TimePanelBlueprint", static=True, play_state=[_ENUMS["playing"]])


class RrdWriter:
    """One recording written to ``path`` by rerun's native writer (module docstring).

    ``log(entity, archetype, **fields)``: a static batch; ``send_columns(entity, t, archetype,
    **fields)``: one row per time ``t`` (s) on timeline ``time``; ``close()`` flushes and
    finishes the file; ``abort()`` stops writing (the caller removes the file).
    """

    def __init__(self, path: str | Path, app_id: str, recording_name: str | None = None,
                 layout: Layout | None = None) -> None:
        check_version()
        rb = _bindings()
        self.path = Path(path)
        self._rec = rb.new_recording(application_id=app_id, recording_id=uuid.uuid4().hex,
                                     make_default=False, make_thread_default=False,
                                     default_enabled=True, send_properties=True,
                                     batcher_config=None)
        storage = None
        if layout is not None:
            bp = rb.new_blueprint(application_id=app_id, make_default=False,
                                  make_thread_default=False, default_enabled=True)
            rb.set_time_sequence("blueprint", 0, recording=bp)
            _log_blueprint(bp, layout)
            storage = rb.memory_recording(recording=bp)
            rb.flush(timeout_sec=0.0, recording=bp)
        rb.save(path=str(self.path), default_blueprint=storage, recording=self._rec,
                write_footer=True)
        if recording_name:
            rb.send_recording_name(recording_name, recording=self._rec)

    def log(self, entity: str, archetype: str, **fields) -> None:
        _bindings().log_arrow_msg(entity, components=_components(archetype, fields, False),
                                  static_=True, recording=self._rec)

    def send_columns(self, entity: str, t: np.ndarray, archetype: str, **fields) -> None:
        import pyarrow as pa

        times = pa.array((np.asarray(t, dtype=float) * 1e9).astype("timedelta64[ns]"),
                         pa.duration("ns"))
        _bindings().send_arrow_chunk(entity, timelines={"time": times},
                                     components=_components(archetype, fields, True),
                                     recording=self._rec)

    def log_file_from_path(self, path: str | Path, entity_path_prefix: str) -> None:
        """A file rerun's importers read (e.g. a URDF and its meshes), static."""
        rb = _bindings()
        rb.log_file_from_path(Path(path), entity_path_prefix=entity_path_prefix, static_=True,
                              recording=self._rec)
        rb.flush(timeout_sec=1e38, recording=self._rec)

    def close(self) -> None:
        rb = _bindings()
        rb.flush(timeout_sec=1e38, recording=self._rec)
        rb.disconnect(recording=self._rec)

    def abort(self) -> None:
        _bindings().disconnect(recording=self._rec)


def warm() -> None:
    """Pay the first-use costs of the native writer (its runtime) and of each Arrow conversion
    (~10 ms) ahead of a recording, e.g. in the forked child while it waits: a blueprint logged
    to a stream without a sink (its data are kept, then dropped), no file written."""
    check_version()
    rb = _bindings()
    bp = rb.new_blueprint(application_id="warm", make_default=False, make_thread_default=False,
                          default_enabled=True)
    rb.set_time_sequence("blueprint", 0, recording=bp)
    _log_blueprint(bp, Layout((("v", "/plots/v"),), 1, (0.0, 1.0, 0.0),
                              ((1.0, 1.0, 1.0), (0.0, 0.0, 0.0)), 0.0))
    for (archetype, _), (_, kind) in _FIELDS.items():
        if archetype not in _BLUEPRINT:
            size = _FIXED.get(kind, ("", 1))[1]
            value = np.zeros((2, 2, 3)) if kind == "strip" else np.zeros((2, size))
            _arrow(kind, ["a", "b"] if kind == "text" else value)


#: An ``.rrd`` stream: the magic, 4 version bytes and 4 option bytes, then messages, each a
#: little-endian ``(kind: u64, length: u64)`` header and its payload; kind 0 ends the stream (its
#: payload, the footer, and a trailer follow).
RRD_MAGIC = b"RRF2"
_STREAM_HEAD = 12


def rrd_problem(path: str | Path) -> str | None:
    """What makes ``path`` not a whole rerun recording (not a file, empty, not a recording, cut
    short), or None: its messages are walked to the end-of-stream message without reading them."""
    import struct

    path = Path(path)
    if not path.is_file():
        return "not a file"
    size = path.stat().st_size
    with path.open("rb") as f:
        if f.read(4) != RRD_MAGIC:
            if size == 0:
                return "empty"
            return f"not a rerun recording (it does not start with {RRD_MAGIC!r})"
        at = _STREAM_HEAD
        while at + 16 <= size:
            f.seek(at)
            kind, length = struct.unpack("<QQ", f.read(16))
            at += 16 + length
            if kind == 0:
                return None if at <= size else "cut short (its footer is incomplete)"
    return "cut short (no end-of-stream message: a recording that was still being written?)"
