"""A model's motion as plain arrays, and its logging to rerun: no Pinocchio needed to write it.

:func:`pipeline.viz.model.motion_scene` runs the forward kinematics of a skeleton's motion and
returns a :class:`MotionScene` (poses, landmarks, angles and the URDF text, NumPy arrays and
strings); :func:`log_scene` writes it, reading the segment meshes from the URDF's visuals itself.
So a forked child (:mod:`pipeline.viz.background`) can write the recording having imported only
NumPy, pyarrow and rerun's native writer (:mod:`pipeline.viz.rrd`), while the parent computes.
Layout: :mod:`pipeline.viz.model`.
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.stl import read_stl, vertex_normals
from pipeline.model.meshes import resolve_package_uri
from pipeline.rotations import matrix_from_euler_zyx
from pipeline.viz.layout import default_layout as _layout
from pipeline.viz.recording import (
    log_landmarks,
    log_poses,
    log_scalars,
    open_recording,
    send_columns,
)
from pipeline.viz.rrd import pack_colors

__all__ = ["ANGLE_COLORS", "BONE_COLOR", "CHUNK_SAMPLES", "MotionScene", "SegmentMesh",
           "log_scene", "meshes_from_urdf", "preload_meshes", "warm_recording"]

BONE_COLOR = (227, 218, 201, 150)
BONE_LINE_COLOR = (90, 90, 90)
_CHUNK_FRAMES = 4096  # frames per block of the ground search (memory: frames x vertices)
#: Samples logged per chunk (memory stays bounded whatever the length).
CHUNK_SAMPLES = 10_000
ANGLE_COLORS = {"flexion": (40, 100, 230), "adduction": (220, 50, 50), "inversion": (220, 50, 50),
                "rotation": (30, 160, 70)}

#: name -> (R (n, 3, 3), p (n, 3)) world poses of model frames over some samples (R None for
#: frames drawn as points: landmarks, bone ends)
Poses = dict[str, tuple[np.ndarray | None, np.ndarray]]


@dataclass(frozen=True)
class SegmentMesh:
    """A triangle mesh in a segment frame (m): ``vertices`` (V, 3), ``triangles`` (F, 3) int
    vertex indices, counter-clockwise seen from outside, ``normals`` (V, 3) unit vertex normals."""

    vertices: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray


@functools.lru_cache(maxsize=32)
def _load_mesh(path: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A mesh file's vertices, triangles and unit vertex normals (read once per process)."""
    vertices, faces = read_stl(path)
    normals = vertex_normals(vertices, faces)
    for a in (vertices, faces, normals):
        a.setflags(write=False)
    return vertices, faces, normals


def _floats(text: str | None, default: Sequence[float]) -> np.ndarray:
    return np.array([float(v) for v in text.split()] if text else default, dtype=float)


def _link_visuals(
    urdf: str, source: Path | None
) -> dict[str, list[tuple[str, np.ndarray, np.ndarray]]]:
    """Link name -> [(mesh filename, scale (3,), 4x4 visual origin in the link frame)]."""
    try:
        root = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise InputError(f"cannot read the URDF: {exc}", file=source) from exc
    out: dict[str, list[tuple[str, np.ndarray, np.ndarray]]] = {}
    for link in root.findall("link"):
        for visual in link.findall("visual"):
            mesh = visual.find("geometry/mesh")
            if mesh is None or not mesh.get("filename"):
                continue
            origin = visual.find("origin")
            xyz = _floats(None if origin is None else origin.get("xyz"), (0, 0, 0))
            rpy = _floats(None if origin is None else origin.get("rpy"), (0, 0, 0))
            T = np.eye(4)
            T[:3, :3] = matrix_from_euler_zyx(rpy[::-1])  # URDF: Rz(yaw) Ry(pitch) Rx(roll)
            T[:3, 3] = xyz
            scale = _floats(mesh.get("scale"), (1, 1, 1))
            out.setdefault(link.get("name"), []).append((mesh.get("filename"), scale, T))
    return out


def _mesh_file(uri: str, source: Path | None) -> Path:
    path = resolve_package_uri(uri)
    if uri.startswith("file://"):
        path = Path(uri[len("file://") :])
    if not path.is_absolute() and source is not None:
        path = source.parent / path
    if not path.is_file():
        raise InputError(f"cannot find the mesh {uri!r}", file=source)
    return path


def preload_meshes(urdf: str, source: Path | None = None) -> None:
    """Read (and cache) every mesh file the URDF's visuals name: what a recording's first
    :func:`meshes_from_urdf` would otherwise read on its critical path."""
    for visuals in _link_visuals(urdf, source).values():
        for uri, _, _ in visuals:
            _load_mesh(str(_mesh_file(uri, source)))


def meshes_from_urdf(urdf: str, source: Path | None, segments: Mapping[str, str]
                     ) -> dict[str, SegmentMesh]:
    """Segment -> its URDF visual meshes merged, in the segment (link) frame, in metres.

    ``segments``: segment -> link name. A vertex ``v`` of a mesh file becomes ``R_o (s * v) +
    p_o`` (``s`` the visual's ``scale``, ``(R_o, p_o)`` its ``origin``); triangles are reversed
    when ``prod(s) < 0`` (a mirroring scale) so that they stay counter-clockwise. Normals follow
    by the inverse transpose of that map, ``n -> unit(R_o (n / s))``, from the file's own vertex
    normals (computed once per file: :func:`preload_meshes`). Segments without a mesh visual are
    left out.
    """
    visuals = _link_visuals(urdf, source)
    out = {}
    for segment, link in segments.items():
        parts_v, parts_f, parts_n, count = [], [], [], 0
        for uri, scale, T in visuals.get(link, []):
            v, f, n = _load_mesh(str(_mesh_file(uri, source)))
            parts_v.append((v * scale) @ T[:3, :3].T + T[:3, 3])
            parts_f.append((f[:, ::-1] if np.prod(scale) < 0 else f) + count)
            n = (n / scale) @ T[:3, :3].T
            length = np.linalg.norm(n, axis=1, keepdims=True)
            parts_n.append(np.divide(n, length, out=np.zeros_like(n), where=length > 0))
            count += len(v)
        if not parts_v:
            continue
        out[segment] = SegmentMesh(*map(np.concatenate, (parts_v, parts_f, parts_n)))
    return out


def _lowest_height(
    traj: Mapping[str, tuple[np.ndarray, np.ndarray]],
    segments: Mapping[str, str],
    meshes: Mapping[str, SegmentMesh],
    points: Sequence[np.ndarray],
    axis: int,
) -> float | None:
    """Lowest value of coordinate ``axis`` over the trial: of the foot meshes' vertices ``v`` at
    ``R v + p`` if any (exact, in chunks of frames so that memory stays bounded), else of
    ``points`` ((N, 3) each); ``None`` if no data."""
    lows = []
    for seg, mesh in meshes.items():
        if seg.endswith("foot"):
            R, p = traj[segments[seg]]
            ok = np.isfinite(R[:, axis, :]).all(axis=1) & np.isfinite(p[:, axis])
            d, h0 = R[ok, axis, :], p[ok, axis]  # height of v: d . v + h0 (finite rows only)
            for lo in range(0, len(d), _CHUNK_FRAMES):
                h = (d[lo : lo + _CHUNK_FRAMES] @ mesh.vertices.T).min(axis=1)
                lows.append(float((h + h0[lo : lo + _CHUNK_FRAMES]).min()))
    if not lows:  # no foot mesh, or no finite sample of one
        for x in points:
            h = np.asarray(x)[:, axis]
            if np.isfinite(h).any():
                lows.append(float(np.nanmin(h)))
    return min(lows) if lows else None


def _camera(
    traj: Mapping[str, tuple[np.ndarray, np.ndarray]],
    frames: Sequence[str],
    ground: float | None,
    axis: int,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Eye position and look target framing the segment origins ``frames`` from the front right.

    Target: the median origin, centred vertically between ``ground`` and the highest origin; eye:
    target + 1.5 * height * unit(0.55 anterior (x) + 0.3 up + 1.0 right), ``height`` the vertical
    span (>= 0.5 m). Model axes: x anterior, ``axis`` up, the remaining one to the right.
    """
    p = np.concatenate([traj[f][1] for f in frames])
    p = p[np.all(np.isfinite(p), axis=1)]
    if not len(p):
        return None
    top = float(p[:, axis].max())
    bottom = float(p[:, axis].min()) if ground is None else ground
    target = np.median(p, axis=0)
    target[axis] = 0.5 * (top + bottom)
    direction = np.zeros(3)
    direction[0], direction[axis], direction[3 - axis] = 0.55, 0.3, 1.0
    distance = 1.5 * max(top - bottom, 0.5)
    return target + distance * direction / np.linalg.norm(direction), target


#: A pelvis whose horizontal path spans more than this (m) walks through the room: the camera
#: frames the room walked and the recording draws the path and the footprints.
WALKS_M = 1.0
PATH_COLOR = (60, 160, 90)
#: The room camera: raised this much (deg) above the horizontal, this many path lengths away
#: (a path filling about the 3D view's width at rerun's field of view).
ROOM_ELEVATION_DEG = 30.0
ROOM_DISTANCE = 1.1


def _pelvis_walk(traj: Mapping[str, tuple[np.ndarray, np.ndarray]], segments: Mapping[str, str],
                 axis: int) -> np.ndarray | None:
    """The pelvis's positions (finite rows) when they span more than :data:`WALKS_M`
    horizontally, else None."""
    frame = segments.get("pelvis")
    if frame is None:
        return None
    p = traj[frame][1]
    p = p[np.all(np.isfinite(p), axis=1)]
    if not len(p) or np.max(np.ptp(np.delete(p, axis, axis=1), axis=0)) <= WALKS_M:
        return None
    return p


def _room_camera(walk: np.ndarray, traj, frames: Sequence[str], ground: float | None,
                 axis: int) -> tuple[np.ndarray, np.ndarray] | None:
    """Eye and target framing the whole walk from its side: aimed at the middle of the pelvis's
    path (at the body's mid-height, as :func:`_camera`), from the horizontal direction across the
    path's main direction (its principal axis), raised by :data:`ROOM_ELEVATION_DEG`, at
    :data:`ROOM_DISTANCE` times the path's length along that axis (at least the body's height)."""
    body = _camera(traj, frames, ground, axis)
    if body is None:
        return None
    eye, target = body
    up = np.zeros(3)
    up[axis] = 1.0
    flat = walk - walk.mean(axis=0)
    flat[:, axis] = 0.0
    main = np.linalg.svd(flat, full_matrices=False)[2][0]
    across = np.cross(up, main)
    along = flat @ main
    middle = walk.mean(axis=0) + 0.5 * (along.max() + along.min()) * main
    middle[axis] = target[axis]
    e = np.radians(ROOM_ELEVATION_DEG)
    away = np.cos(e) * across / np.linalg.norm(across) + np.sin(e) * up
    length = max(float(np.ptp(along)), float(np.linalg.norm(eye - target)))
    return middle + ROOM_DISTANCE * length * away, middle


def _log_walk(rec, walk: np.ndarray, reference: Mapping[str, np.ndarray], ground: float | None,
              axis: int) -> None:
    """Static: the pelvis's path on the floor (``world/walk/path``) and each foot's footprints
    (``world/walk/<side>_footprints``: the rests of ``reference``'s ``<side>_footprint``)."""
    path = walk.copy()
    path[:, axis] = ground if ground is not None else float(walk[:, axis].min())
    rec.log("world/walk/path", "LineStrips3D", strips=[path], radii=[0.008],
            colors=pack_colors([PATH_COLOR]))
    for name, xyz in reference.items():
        if name.endswith("_footprint"):
            prints = np.unique(xyz[np.all(np.isfinite(xyz), axis=1)], axis=0)
            if len(prints):
                rec.log(f"world/walk/{name}s", "Points3D", positions=prints, radii=[0.03],
                        colors=pack_colors([PATH_COLOR]))


@dataclass(frozen=True)
class MotionScene:
    """What a recording of a model's motion shows, as arrays (:func:`log_scene` writes it).

    ``time`` (N,) s; ``shown``: the rows whose 3D content is drawn (a stride over long
    recordings); ``ok`` (N,): rows with a finite configuration; ``poses``: frame -> world poses
    over ``shown`` (None: the caller of :func:`log_scene` computes them chunk by chunk);
    ``view``: poses over a subset of ``shown`` that frames the camera; ``segments``: segment ->
    frame; ``angles``/``truth``/``scalars``: entity -> (N,) series (radians for the first two);
    ``reference``: name -> (N, 3) m.
    """

    time: np.ndarray
    shown: np.ndarray
    ok: np.ndarray
    urdf: str
    source: Path | None
    legs: tuple[str, ...]
    segments: dict[str, str]
    landmark_names: list[str]
    imu_names: list[str]
    bone_legs: list[str]
    view: Poses
    poses: Poses | None
    angles: dict[str, np.ndarray]
    truth: dict[str, np.ndarray]
    scalars: dict[str, np.ndarray]
    reference: dict[str, np.ndarray]
    meshes: bool
    error_arrows: bool
    up_axis: str
    vertical: int
    recording_name: str | None
    app_id: str
    imu_axis_length: float
    point_radius: float


def log_scene(path: str | Path, scene: MotionScene,
              poses: Callable[[int, int], Poses] | None = None) -> Path:
    """Write ``scene`` to ``path`` (.rrd); ``poses(start, stop)``: the poses of the shown samples
    ``shown[start:stop]`` when ``scene.poses`` is None (e.g. forward kinematics per chunk)."""
    path = Path(path)
    if poses is None:
        if scene.poses is None:
            raise InputError("the scene has no poses and none were given", field="poses")

        def poses(start: int, stop: int) -> Poses:
            return {k: (None if R is None else R[start:stop], p[start:stop])
                    for k, (R, p) in scene.poses.items()}

    t, ok, view, segments = scene.time, scene.ok, scene.view, scene.segments
    lm_names, imu_names, bone_legs = scene.landmark_names, scene.imu_names, scene.bone_legs
    mesh_data = meshes_from_urdf(scene.urdf, scene.source, segments) if scene.meshes else {}
    ground = _lowest_height(view, segments, mesh_data, [view[m][1] for m in lm_names],
                            scene.vertical)
    walk = _pelvis_walk(view, segments, scene.vertical)
    if walk is None:
        camera = _camera(view, list(segments.values()), ground, scene.vertical)
    else:
        camera = _room_camera(walk, view, list(segments.values()), ground, scene.vertical)
    plots = []
    for side in scene.legs:
        for joint in ("hip", "knee", "ankle"):
            if any(k.startswith(f"plots/{side}_{joint}/") for k in scene.angles):
                plots.append((f"{side} {joint} (deg)", f"/plots/{side}_{joint}"))
    order = {"hip": 0, "knee": 1, "ankle": 2}
    plots.sort(key=lambda view: order[view[0].split()[1]])  # hip, knee, ankle; right first
    if scene.scalars:
        plots.append(("other", [f"/{entity}" for entity in scene.scalars]))
    layout = _layout(plots, scene.up_axis, camera=camera, ground=ground)

    with open_recording(path, scene.app_id, scene.recording_name, scene.up_axis,
                        layout) as rec:
        for seg, mesh in mesh_data.items():
            rec.log(f"world/model/{seg}/mesh", "Mesh3D", vertex_positions=mesh.vertices,
                    triangle_indices=mesh.triangles, vertex_normals=mesh.normals,
                    albedo_factor=pack_colors([BONE_COLOR]))
        if walk is not None:
            _log_walk(rec, walk, scene.reference, ground, scene.vertical)
        shown = scene.shown
        for start in range(0, len(shown), CHUNK_SAMPLES):  # bounded memory on long recordings
            rows = shown[start : start + CHUNK_SAMPLES]
            traj, tc, okc = poses(start, start + len(rows)), t[rows], ok[rows]
            log_poses(rec, tc, "world/model", {s: traj[f] for s, f in segments.items()}, None)
            points = {name: traj[name][1] for name in lm_names}
            ref = {k: v[rows] for k, v in scene.reference.items()} or None
            log_landmarks(rec, tc, points, ref, scene.error_arrows, scene.point_radius)
            log_poses(rec, tc, "world/imus", {m: traj[m] for m in imu_names},
                      scene.imu_axis_length)
            for side in bone_legs:
                strip = np.stack([traj[f"{side}_{j}"][1] for j in ("HJC", "KJC", "AJC")], axis=1)
                entity = f"world/bones/{side}"
                rec.log(entity, "LineStrips3D", radii=[0.006],
                        colors=pack_colors([BONE_LINE_COLOR]))
                if okc.any():
                    send_columns(rec, entity, tc, okc, "LineStrips3D", strips=strip)
        for entity in scene.angles:
            angle = entity.rsplit("/", 1)[1]
            rec.log(entity, "SeriesLines", colors=pack_colors([ANGLE_COLORS[angle]]),
                    names=[angle])
        log_scalars(rec, t, scene.angles, scale=float(np.degrees(1.0)))
        for entity in scene.truth:
            angle = entity.rsplit("/", 1)[1].removesuffix("_truth")
            light = tuple(int(c + 0.55 * (255 - c)) for c in ANGLE_COLORS[angle])
            rec.log(entity, "SeriesLines", colors=pack_colors([light]),
                    names=[f"{angle} (truth)"], widths=[1.0])
        log_scalars(rec, t, scene.truth, scale=float(np.degrees(1.0)))
        log_scalars(rec, t, scene.scalars)
    return path


def warm_recording() -> None:
    """What a recording's first call would otherwise do on the critical path, done in the
    forked child (:mod:`pipeline.viz.background`) while the parent works, without Pinocchio:
    pyarrow's and rerun's native writer's imports, pyarrow's pandas check (our own child: nothing
    else runs in it), the shipped meshes read (cached)."""
    from pipeline.viz.arrow import pyarrow_without_pandas

    pyarrow_without_pandas()
    from pipeline.viz.rrd import warm

    warm()  # the native writer's import and first use
    np.ones((64, 3)) @ np.ones((3, 64))  # BLAS's first call (its buffers)
    from pipeline.model.builder import urdf_text
    from pipeline.model.geometry import SubjectGeometry

    preload_meshes(urdf_text(SubjectGeometry.default(), check=False))
