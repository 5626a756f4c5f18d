"""Rerun recording of a scaled model's motion: segment meshes, landmarks, IMU axes, bones, angles.

:func:`log_motion` takes configurations ``Q`` (N, nq) of a :class:`~pipeline.model.Skeleton`, runs
the forward kinematics of every frame it draws once
(:func:`pipeline.analysis.landmarks.frame_trajectories`) and writes an offline ``.rrd`` with the
columnar API (one ``send_columns`` call per entity for the whole trial; see
:mod:`pipeline.viz.recording`). Layout (timeline ``time``, seconds; model coordinates, m):

* ``world``: view coordinates (``up_axis`` up; the model is Y-up, so ``'y'`` stands it upright).
* ``world/model/<segment>``: the segment pose ``(R, p)`` as ``Transform3D`` columns (translation,
  xyzw quaternion), N rows; ``<segment>`` in ``pelvis``, ``<side>_femur``, ``<side>_tibia``,
  ``<side>_foot``.
* ``world/model/<segment>/mesh``: static ``Mesh3D`` in the segment frame: the URDF visuals of the
  link (STL, scaled by the visual's ``scale``, placed by its ``origin``; the tibia includes the
  knee cap mesh), vertex normals, one translucent bone colour (alpha 150/255: the landmarks,
  bones and IMU axes inside show through). It moves with its parent's transform.
* ``world/landmarks/<frame>``: landmark frames (e.g. ``right_EFM``) as labelled ``Points3D``;
  ``world/reference/<name>`` and ``world/errors/<name>`` for ``reference_landmarks``.
* ``world/imus/<frame>``: IMU frame poses as ``Transform3D`` columns with static axes.
* ``world/bones/<side>``: ``LineStrips3D`` HJC-KJC-AJC, one strip per row.
* ``plots/<side>_<joint>/<angle>``: ISB joint angles
  (:func:`pipeline.analysis.landmarks.joint_angles`) in degrees, one colour per angle
  (``ANGLE_COLORS``: flexion blue, adduction red, rotation green, the colours of the z, x, y axes
  they turn about); ``plots/<name>`` for ``extra_scalars`` (logged as given).

Default layout (blueprint): the 3D view, its camera looking at the legs from the front right
with the line grid on the ground (the lowest point the feet reach), beside one time-series view
per joint ("right hip (deg)", ...) and one for ``extra_scalars``.
"""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.analysis.landmarks import frame_trajectories
from pipeline.analysis.landmarks import joint_angles as isb_joint_angles
from pipeline.errors import InputError
from pipeline.io.stl import read_stl, vertex_normals
from pipeline.model.meshes import resolve_package_uri
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import matrix_from_euler_zyx
from pipeline.viz.layout import default_blueprint as _blueprint
from pipeline.viz.layout import up_axis_index as _check_up_axis
from pipeline.viz.recording import (
    check_series,
    check_time,
    import_rerun,
    log_landmarks,
    log_poses,
    log_scalars,
    open_recording,
    send_columns,
)

__all__ = ["ANGLE_COLORS", "BONE_COLOR", "SegmentMesh", "log_motion", "segment_meshes"]

BONE_COLOR = (227, 218, 201, 150)
BONE_LINE_COLOR = (90, 90, 90)
#: Longer recordings show their 3D content (model, landmarks, IMU frames) at a stride that keeps
#: at most this many samples (36,000: 10 Hz over an hour), the joint angles at the full rate: the
#: viewer plays 3D fluently at that density, and the .rrd of an hour stays ~100 MB.
MAX_3D_SAMPLES = 36_000
_CHUNK_FRAMES = 4096  # frames per block of the ground search (memory: frames x vertices)
#: Samples logged per chunk (memory stays bounded whatever the length).
CHUNK_SAMPLES = 10_000
ANGLE_COLORS = {"flexion": (40, 100, 230), "adduction": (220, 50, 50), "inversion": (220, 50, 50),
                "rotation": (30, 160, 70)}  # fmt: skip


@dataclass(frozen=True)
class SegmentMesh:
    """A triangle mesh in a segment frame (m): ``vertices`` (V, 3), ``triangles`` (F, 3) int
    vertex indices, counter-clockwise seen from outside, ``normals`` (V, 3) unit vertex normals."""

    vertices: np.ndarray
    triangles: np.ndarray
    normals: np.ndarray


@functools.lru_cache(maxsize=32)
def _load_mesh(path: str) -> tuple[np.ndarray, np.ndarray]:
    vertices, faces = read_stl(path)
    vertices.setflags(write=False)
    faces.setflags(write=False)
    return vertices, faces


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


def segment_meshes(skeleton: Skeleton) -> dict[str, SegmentMesh]:
    """Segment -> its URDF visual meshes merged, in the segment (link) frame, in metres.

    A vertex ``v`` of a mesh file becomes ``R_o (s * v) + p_o`` (``s`` the visual's ``scale``,
    ``(R_o, p_o)`` its ``origin``); triangles are reversed when ``prod(s) < 0`` (a mirroring scale)
    so that they stay counter-clockwise. Segments without a mesh visual are left out.
    """
    visuals = _link_visuals(skeleton.urdf, skeleton.source)
    out = {}
    for segment, link in skeleton.segment_frames.items():
        parts_v, parts_f, count = [], [], 0
        for uri, scale, T in visuals.get(link, []):
            v, f = _load_mesh(str(_mesh_file(uri, skeleton.source)))
            parts_v.append((v * scale) @ T[:3, :3].T + T[:3, 3])
            parts_f.append((f[:, ::-1] if np.prod(scale) < 0 else f) + count)
            count += len(v)
        if not parts_v:
            continue
        vertices, triangles = np.concatenate(parts_v), np.concatenate(parts_f)
        out[segment] = SegmentMesh(vertices, triangles, vertex_normals(vertices, triangles))
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
            for lo in range(0, len(R), _CHUNK_FRAMES):
                h = R[lo : lo + _CHUNK_FRAMES, axis, :] @ mesh.vertices.T
                h += p[lo : lo + _CHUNK_FRAMES, axis, None]
                if np.isfinite(h).any():
                    lows.append(float(np.nanmin(h)))
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


def _names(selection: bool | Sequence[str], default: Sequence[str], what: str) -> list[str]:
    if selection is True:
        return list(default)
    if selection is False or selection is None:
        return []
    names = list(selection)
    unknown = [n for n in names if n not in default]
    if unknown:
        raise InputError(f"expected {what} among {list(default)}, got {unknown}", field=what)
    return names


def log_motion(
    path: str | Path,
    time: np.ndarray,
    skeleton: Skeleton,
    Q: np.ndarray,
    *,
    landmarks: bool | Sequence[str] = True,
    imu_frames: bool | Sequence[str] = True,
    joint_angles: bool | Sequence[str] = True,
    bones: bool = True,
    meshes: bool = True,
    reference_landmarks: Mapping[str, np.ndarray] | None = None,
    reference_angles: Mapping[str, np.ndarray] | None = None,
    error_arrows: bool = True,
    extra_scalars: Mapping[str, np.ndarray] | None = None,
    up_axis: str = "y",
    recording_name: str | None = None,
    app_id: str = "imu_skeleton_pipeline",
    imu_axis_length: float = 0.06,
    point_radius: float = 0.008,
) -> Path:
    """Write the motion ``Q`` (N, nq) of ``skeleton`` at ``time`` (N,) s to ``path`` (.rrd).

    ``landmarks`` / ``imu_frames``: ``True`` for every landmark / IMU frame of the model, or a
    list of frame names. ``reference_landmarks``: name -> (N, 3) m (e.g. optical markers, keyed
    like the landmark frames, ``right_EFM``), drawn in another colour with error arrows
    reference -> estimate for the names drawn in both. ``reference_angles``: ISB angle name ->
    (N,) rad (keyed like :func:`pipeline.analysis.landmarks.joint_angles`, e.g.
    ``right_knee_flexion``; NaN where unknown), drawn as thin lighter curves ``<angle> (truth)``
    in the same plot as the estimate. ``extra_scalars``: entity name under
    ``plots/`` -> (N,) series, logged unchanged. Rows whose configuration is not finite are not
    logged. Returns ``path``; layout in the module docstring.
    """
    path = Path(path)
    t = check_time(time)
    n = len(t)
    vertical = _check_up_axis(up_axis)
    Q = check_series(Q, n, (skeleton.nq,), "Q")
    lm_names = _names(landmarks, skeleton.landmark_frames, "landmarks")
    imu_names = _names(imu_frames, skeleton.imu_frames, "imu_frames")
    bone_legs = list(skeleton.legs) if bones else []
    bone_names = [f"{s}_{j}" for s in bone_legs for j in ("HJC", "KJC", "AJC")]
    segments = skeleton.segment_frames
    mesh_data = segment_meshes(skeleton) if meshes else {}
    scalars = {}
    for name, y in (extra_scalars or {}).items():
        scalars[f"plots/{name}"] = check_series(y, n, (), name)

    ok = np.all(np.isfinite(Q), axis=1)
    Q_fk = np.where(ok[:, None], Q, skeleton.neutral())  # FK on finite rows only
    names = list(dict.fromkeys([*segments.values(), *lm_names, *imu_names, *bone_names]))
    # the 3D content at most MAX_3D_SAMPLES samples (a stride over long recordings), logged in
    # chunks; the joint angles at the full rate
    stride = max(1, -(-n // MAX_3D_SAMPLES))
    shown = np.arange(0, n, stride)

    def trajectories(rows: np.ndarray) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        traj = frame_trajectories(skeleton, Q_fk[rows], names)
        for R, p in traj.values():
            R[~ok[rows]] = np.nan
            p[~ok[rows]] = np.nan
        return traj

    view = trajectories(shown[:: max(1, len(shown) // 2000)])  # framing from <= 2000 samples
    angles = {}
    if joint_angles:
        wanted = None if joint_angles is True else set(joint_angles)
        for key, y in isb_joint_angles(skeleton, Q_fk).items():
            if wanted is not None and key not in wanted:
                continue
            joint, angle = key.rsplit("_", 1)
            angles[f"plots/{joint}/{angle}"] = np.where(ok, y, np.nan)
    truth = {}
    for key, y in (reference_angles or {}).items():
        joint, angle = key.rsplit("_", 1)
        if angle not in ANGLE_COLORS:
            raise InputError(f"expected an ISB angle name like right_knee_flexion, got {key!r}",
                             field="reference_angles")  # fmt: skip
        truth[f"plots/{joint}/{angle}_truth"] = check_series(y, n, (), key)

    ground = _lowest_height(view, segments, mesh_data, [view[m][1] for m in lm_names], vertical)
    camera = _camera(view, list(segments.values()), ground, vertical)
    plots = []
    for side in skeleton.legs:
        for joint in ("hip", "knee", "ankle"):
            if any(k.startswith(f"plots/{side}_{joint}/") for k in angles):
                plots.append((f"{side} {joint} (deg)", f"/plots/{side}_{joint}"))
    order = {"hip": 0, "knee": 1, "ankle": 2}
    plots.sort(key=lambda view: order[view[0].split()[1]])  # hip, knee, ankle; right first
    if scalars:
        plots.append(("other", [f"/{entity}" for entity in scalars]))
    blueprint = _blueprint(plots, up_axis, camera=camera, ground=ground)

    rr = import_rerun()
    reference = {k: check_series(v, n, (3,), k) for k, v in (reference_landmarks or {}).items()}
    with open_recording(path, app_id, recording_name, up_axis, blueprint) as rec:
        for seg, mesh in mesh_data.items():
            rec.log(
                f"world/model/{seg}/mesh",
                rr.Mesh3D(
                    vertex_positions=mesh.vertices,
                    triangle_indices=mesh.triangles,
                    vertex_normals=mesh.normals,
                    albedo_factor=BONE_COLOR,
                ),
                static=True,
            )
        for start in range(0, len(shown), CHUNK_SAMPLES):  # bounded memory on long recordings
            rows = shown[start : start + CHUNK_SAMPLES]
            traj, tc, okc = trajectories(rows), t[rows], ok[rows]
            log_poses(rec, tc, "world/model", {s: traj[f] for s, f in segments.items()}, None)
            points = {name: traj[name][1] for name in lm_names}
            ref = {k: v[rows] for k, v in reference.items()} or None
            log_landmarks(rec, tc, points, ref, error_arrows, point_radius)
            log_poses(rec, tc, "world/imus", {m: traj[m] for m in imu_names}, imu_axis_length)
            for side in bone_legs:
                strip = np.stack([traj[f"{side}_{j}"][1] for j in ("HJC", "KJC", "AJC")], axis=1)
                entity = f"world/bones/{side}"
                rec.log(
                    entity,
                    rr.LineStrips3D.from_fields(colors=[BONE_LINE_COLOR], radii=[0.006]),
                    static=True,
                )
                if okc.any():
                    send_columns(rec, entity, tc, okc, rr.LineStrips3D.columns(strips=strip[okc]))
        for entity in angles:
            angle = entity.rsplit("/", 1)[1]
            style = rr.SeriesLines(colors=[ANGLE_COLORS[angle]], names=[angle])
            rec.log(entity, style, static=True)
        log_scalars(rec, t, angles, scale=float(np.degrees(1.0)))
        for entity in truth:
            angle = entity.rsplit("/", 1)[1].removesuffix("_truth")
            light = tuple(int(c + 0.55 * (255 - c)) for c in ANGLE_COLORS[angle])
            style = rr.SeriesLines(colors=[light], names=[f"{angle} (truth)"], widths=[1.0])
            rec.log(entity, style, static=True)
        log_scalars(rec, t, truth, scale=float(np.degrees(1.0)))
        log_scalars(rec, t, scalars)
    return path
