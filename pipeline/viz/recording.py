"""Rerun recordings of a trial: landmarks, reference landmarks, errors, segment axes, joint angles.

Written offline to an ``.rrd`` file with the columnar API (``send_columns`` + ``TimeColumn``: one
call per entity for the whole trial, 50-100x faster than a ``log`` call per frame). Layout (one
timeline ``time``, seconds):

* ``world``: view coordinates (right-handed, ``up_axis`` up).
* ``world/landmarks/<name>``: estimated landmark (``Points3D``), one point per time row, its
  label hidden (shown on hover: labels of nearby landmarks overlap).
* ``world/reference/<name>``: reference landmark (e.g. OMC), another colour.
* ``world/errors/<name>``: arrow from the reference to the estimate (Wang eq 20 error).
* ``world/segments/<name>``: segment pose as a ``Transform3D`` column (translation and the
  rotation as a quaternion: rerun converts ``mat3x3`` columns matrix by matrix in Python, 0.05 s
  per 3000 frames) with static ``TransformAxes3D`` (x red, y green, z blue).
* ``plots/<name>``: joint angles as ``Scalars`` in degrees (the only non-SI output: for reading).
* ``world/model``: a URDF (``log_file_from_path``); ``package://`` meshes resolve through
  ``ROS_PACKAGE_PATH``. Its root link is placed in ``world`` by a static named-frame transform
  (default ``Rx(+90 deg)``: a Y-up model stands upright in a Z-up world).

The file carries a default blueprint (the viewer's layout,
:func:`pipeline.viz.layout.default_layout`): the 3D view of ``world`` on the left, the ``plots``
as time-series views on the right. Files are
written by rerun's native writer through :class:`pipeline.viz.rrd.RrdWriter`, without importing
the ``rerun`` Python package (~0.3 s); reading back uses it.

Samples with NaN are not logged (the viewer shows the last valid one until the next).
:func:`pipeline.viz.model.log_motion` draws a model's motion from its configurations (moving
segment meshes, landmarks, IMU axes, bones and joint-angle plots) with the logging helpers of this
module. ``read_entities`` and ``entity_row_counts`` read a recording back by iterating its chunks
(``rerun.chunk.RrdReader``; no datafusion extra needed). :mod:`pipeline.viz.viewer` opens the
native or web viewer.
"""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.checks import check_time
from pipeline.model.resources import example_robot_data_share
from pipeline.rotations import quat_xyzw_from_matrix, rot_x
from pipeline.viz.arrow import pandas_shortcut_if_asked
from pipeline.viz.layout import default_layout as _layout
from pipeline.viz.layout import up_axis_index as _check_up_axis
from pipeline.viz.rrd import VIEW_COORDINATES, Layout, RrdWriter, pack_colors

__all__ = [
    "check_series",
    "log_landmarks",
    "log_poses",
    "log_scalars",
    "open_recording",
    "send_columns",
    "entity_row_counts",
    "log_trial",
    "read_entities",
]

IMC_COLOR = (230, 90, 40)
REFERENCE_COLOR = (40, 120, 230)
ERROR_COLOR = (200, 40, 160)


def check_series(x: np.ndarray, n: int, tail: tuple[int, ...], what: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.shape != (n, *tail):
        want = ", ".join(str(d) for d in (n, *tail))
        raise InputError(
            f"expected shape ({want}) matching the time axis, got {x.shape}", field=what
        )
    return x


def _finite(x: np.ndarray) -> np.ndarray:
    return np.all(np.isfinite(x.reshape(len(x), -1)), axis=1)


def _urdf_root_link(urdf_path: Path) -> str:
    try:
        root = ET.parse(urdf_path).getroot()
    except (ET.ParseError, OSError) as exc:
        raise InputError(f"cannot read the URDF: {exc}", file=urdf_path) from exc
    links = [e.get("name") for e in root.findall("link")]
    children = {c.get("link") for j in root.findall("joint") for c in j.findall("child")}
    roots = [name for name in links if name not in children]
    if len(roots) != 1:
        raise InputError(f"expected one root link, found {roots}", file=urdf_path)
    return roots[0]


def _default_package_paths(urdf_path: Path) -> list[Path]:
    """Folders that may hold ``package://`` packages: example-robot-data's share, URDF ancestors."""
    paths: list[Path] = []
    try:
        paths.append(example_robot_data_share().parent)
    except FileNotFoundError:
        pass
    paths.extend(list(urdf_path.resolve().parents)[:3])
    return paths


@contextmanager
def _env(name: str, value: str):
    old = os.environ.get(name)
    os.environ[name] = value
    try:
        yield
    finally:
        if old is None:
            os.environ.pop(name, None)
        else:
            os.environ[name] = old


@contextmanager
def open_recording(
    path: Path, app_id: str, recording_name: str | None, up_axis: str,
    layout: Layout | None = None,
):
    """An offline recording (:class:`~pipeline.viz.rrd.RrdWriter`) to ``path`` with view
    coordinates on ``world`` and ``layout`` as its default blueprint; deleted on failure."""
    _check_up_axis(up_axis)
    pandas_shortcut_if_asked()  # before pyarrow converts its first list
    path.parent.mkdir(parents=True, exist_ok=True)
    rec = RrdWriter(path, app_id, recording_name, layout)
    try:
        rec.log("world", "ViewCoordinates", xyz=[VIEW_COORDINATES[up_axis]])
        yield rec
        rec.close()
    except BaseException:
        rec.abort()
        path.unlink(missing_ok=True)  # no half-written recording
        raise


def send_columns(rec: RrdWriter, entity: str, t: np.ndarray, mask: np.ndarray, archetype: str,
                 **columns: np.ndarray) -> None:
    """One columns chunk: the rows of ``t`` (and of each column) selected by ``mask`` on the
    timeline ``time``."""
    rec.send_columns(entity, t[mask], archetype, **{k: v[mask] for k, v in columns.items()})


def _log_points(
    rec, t: np.ndarray, group: str, data: Mapping[str, np.ndarray], color, radius: float
) -> dict[str, np.ndarray]:
    """``world/<group>/<name>``: one labelled point per time row (NaN rows skipped)."""
    out = {}
    for name, xyz in data.items():
        xyz = check_series(xyz, len(t), (3,), name)
        ok = _finite(xyz)
        entity = f"world/{group}/{name}"
        rec.log(entity, "Points3D", radii=[radius], colors=pack_colors([color]), labels=[name],
                show_labels=[False])
        if ok.any():
            send_columns(rec, entity, t, ok, "Points3D", positions=xyz)
        out[name] = xyz
    return out


def _log_error_arrows(
    rec, t: np.ndarray, est: Mapping[str, np.ndarray], ref: Mapping[str, np.ndarray]
) -> None:
    """``world/errors/<name>``: arrow reference -> estimate for the names in both."""
    for name in est.keys() & ref.keys():
        ok = _finite(est[name]) & _finite(ref[name])
        entity = f"world/errors/{name}"
        rec.log(entity, "Arrows3D", colors=pack_colors([ERROR_COLOR]))
        if ok.any():
            send_columns(rec, entity, t, ok, "Arrows3D", origins=ref[name],
                         vectors=est[name] - ref[name])


def log_landmarks(
    rec,
    t: np.ndarray,
    landmarks: Mapping[str, np.ndarray],
    reference: Mapping[str, np.ndarray] | None,
    error_arrows: bool,
    radius: float,
) -> None:
    """Estimated landmarks, optional reference landmarks (e.g. optical) and the error arrows."""
    est = _log_points(rec, t, "landmarks", landmarks, IMC_COLOR, radius)
    if reference:
        ref = _log_points(rec, t, "reference", reference, REFERENCE_COLOR, radius)
        if error_arrows:
            _log_error_arrows(rec, t, est, ref)


def log_poses(
    rec,
    t: np.ndarray,
    group: str,
    poses: Mapping[str, tuple[np.ndarray, np.ndarray]],
    axis_length: float | None,
) -> None:
    """``<group>/<name>``: ``Transform3D`` columns (translation, xyzw quaternion), static axes.
    The quaternions of every pose in one conversion."""
    rows = []
    for name, (R, p) in poses.items():
        R = check_series(R, len(t), (3, 3), f"{name} R")
        p = check_series(p, len(t), (3,), f"{name} p")
        ok = _finite(R) & _finite(p)
        rows.append((name, R[ok], p[ok], ok))
    xyzw = quat_xyzw_from_matrix(np.concatenate([r[1] for r in rows] or [np.eye(3)[None]]))
    start = 0
    for name, R, p, ok in rows:
        entity = f"{group}/{name}"
        if axis_length is not None:
            rec.log(entity, "TransformAxes3D", axis_length=[axis_length])
        if ok.any():  # rerun's quaternions are scalar-last
            q = xyzw[start : start + len(R)]
            rec.send_columns(entity, t[ok], "Transform3D", translation=p, quaternion=q)
        start += len(R)


def log_scalars(rec, t: np.ndarray, series: Mapping[str, np.ndarray], scale: float = 1.0) -> None:
    """Entity path -> ``(N,)`` series times ``scale``, as ``Scalars`` (NaN rows skipped)."""
    for entity, y in series.items():
        y = check_series(y, len(t), (), entity)
        ok = np.isfinite(y)
        if ok.any():
            rec.send_columns(entity, t[ok], "Scalars", scalars=scale * y[ok])


def log_trial(
    path: str | Path,
    time: np.ndarray,
    landmarks: Mapping[str, np.ndarray],
    reference_landmarks: Mapping[str, np.ndarray] | None = None,
    error_arrows: bool = True,
    segment_poses: Mapping[str, tuple[np.ndarray, np.ndarray]] | None = None,
    joint_angles: Mapping[str, np.ndarray] | None = None,
    urdf_path: str | Path | None = None,
    app_id: str = "imu_skeleton_pipeline",
    recording_name: str | None = None,
    *,
    up_axis: str = "z",
    urdf_root: tuple[np.ndarray, np.ndarray] | None = None,
    package_paths: Sequence[str | Path] | None = None,
    axis_length: float = 0.1,
    point_radius: float = 0.008,
) -> Path:
    """Write one trial to ``path`` (.rrd) and return the path.

    ``time`` (N,) s; ``landmarks`` name -> (N, 3) m; ``reference_landmarks`` likewise (drawn in
    another colour, with error arrows reference -> estimate when ``error_arrows``);
    ``segment_poses`` name -> (R (N, 3, 3), p (N, 3)); ``joint_angles`` name -> (N,) rad, logged
    in degrees under ``plots/``; ``urdf_path`` a model logged statically under ``world/model`` with
    its root link posed by ``urdf_root = (R, p)`` in ``world`` (default ``Rx(+90 deg)``, 0).
    ``package_paths`` extend ``ROS_PACKAGE_PATH`` (default: example-robot-data's ``share`` folder
    and the URDF's parent folders). :func:`pipeline.viz.model.log_motion` draws a model's motion.
    """
    path = Path(path)
    t = check_time(time, min_samples=1)
    _check_up_axis(up_axis)
    plots = [("joint angles (deg)", "/plots")] if joint_angles else []
    with open_recording(path, app_id, recording_name, up_axis, _layout(plots, up_axis)) as rec:
        log_landmarks(rec, t, landmarks, reference_landmarks, error_arrows, point_radius)
        log_poses(rec, t, "world/segments", segment_poses or {}, axis_length)
        angles = {f"plots/{name}": q for name, q in (joint_angles or {}).items()}
        log_scalars(rec, t, angles, scale=float(np.degrees(1.0)))
        if urdf_path is not None:
            _log_urdf(rec, Path(urdf_path), urdf_root, package_paths)
    return path


def _log_urdf(rec: RrdWriter, urdf_path: Path, urdf_root, package_paths) -> None:
    if not urdf_path.is_file():
        raise InputError("no such URDF file", file=urdf_path)
    root_link = _urdf_root_link(urdf_path)
    R, p = (rot_x(np.pi / 2), np.zeros(3)) if urdf_root is None else urdf_root
    rec.log("world/model_root", "Transform3D", translation=[np.asarray(p, dtype=float)],
            mat3x3=[np.asarray(R, dtype=float)], parent_frame=["tf#/world"],
            child_frame=[root_link])
    folders = [str(Path(f)) for f in (package_paths or _default_package_paths(urdf_path))]
    existing = os.environ.get("ROS_PACKAGE_PATH")
    if existing:
        folders.append(existing)
    with _env("ROS_PACKAGE_PATH", os.pathsep.join(folders)):
        # the importer streams meshes asynchronously: flushed while the path is set
        rec.log_file_from_path(urdf_path, entity_path_prefix="world/model")


# --------------------------------------------------------------------------- reading back


def _chunks(path: str | Path):
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.is_file():
        raise InputError("no such recording", file=path)
    return RrdReader(path).stream().to_chunks()


def read_entities(path: str | Path) -> set[str]:
    """Entity paths (e.g. ``/world/landmarks/EFM``) in a recording, internal ``/__*`` excluded."""
    return {c.entity_path for c in _chunks(path) if not c.entity_path.startswith("/__")}


def entity_row_counts(path: str | Path) -> dict[str, int]:
    """Per entity, the number of time rows (temporal chunks summed; static-only entities: 0)."""
    counts: dict[str, int] = {}
    for c in _chunks(path):
        if c.entity_path.startswith("/__"):
            continue
        counts[c.entity_path] = counts.get(c.entity_path, 0) + (0 if c.is_static else c.num_rows)
    return counts
