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
:func:`pipeline.viz.layout.default_blueprint`): the 3D view of ``world`` on the left, the
``plots`` as time-series views on the right.

Samples with NaN are not logged (the viewer shows the last valid one until the next).
:func:`pipeline.viz.model.log_motion` draws a model's motion from its configurations (moving
segment meshes, landmarks, IMU axes, bones and joint-angle plots) with the logging helpers of this
module. ``read_entities`` and ``entity_row_counts`` read a recording back by iterating its chunks
(``rerun.chunk.RrdReader``; no datafusion extra needed). :mod:`pipeline.viz.viewer` opens the
native or web viewer.
"""

from __future__ import annotations

import importlib.metadata
import os
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import quat_xyzw_from_matrix, rot_x
from pipeline.viz.arrow import pandas_shortcut_if_asked
from pipeline.viz.layout import default_blueprint as _blueprint
from pipeline.viz.layout import up_axis_index as _check_up_axis

__all__ = [
    "check_series",
    "check_time",
    "import_rerun",
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


def import_rerun():
    import rerun as rr  # deferred: importing rerun costs ~0.3 s

    return rr


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
        for f in importlib.metadata.files("example-robot-data") or []:
            share = next((a for a in Path(str(f.locate())).parents if a.name == "share"), None)
            if share is not None:
                paths.append(share)
                break
    except importlib.metadata.PackageNotFoundError:
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


def check_time(time: np.ndarray) -> np.ndarray:
    t = np.asarray(time, dtype=float)
    if t.ndim != 1 or len(t) == 0 or not np.all(np.isfinite(t)):
        raise InputError(f"time must be a finite (N,) array, got shape {t.shape}", field="time")
    return t


@contextmanager
def open_recording(
    path: Path, app_id: str, recording_name: str | None, up_axis: str, blueprint=None
):
    """An offline recording to ``path`` with view coordinates on ``world`` and ``blueprint`` as its
    default layout; deleted on failure."""
    pandas_shortcut_if_asked()
    rr = import_rerun()
    _check_up_axis(up_axis)
    path.parent.mkdir(parents=True, exist_ok=True)
    rec = rr.RecordingStream(app_id)
    rec.save(path, default_blueprint=blueprint)
    try:
        if recording_name:
            rec.send_recording_name(recording_name)
        view_coordinates = (
            rr.ViewCoordinates.RIGHT_HAND_Z_UP
            if up_axis == "z"
            else rr.ViewCoordinates.RIGHT_HAND_Y_UP
        )
        rec.log("world", view_coordinates, static=True)
        yield rec
        rec.flush()
    except BaseException:
        rec.disconnect()
        path.unlink(missing_ok=True)  # no half-written recording
        raise
    rec.disconnect()


def send_columns(rec, entity: str, t: np.ndarray, mask: np.ndarray, columns) -> None:
    """One ``send_columns`` call: the rows of ``t`` selected by ``mask`` on timeline ``time``."""
    rr = import_rerun()
    rec.send_columns(entity, indexes=[rr.TimeColumn("time", duration=t[mask])], columns=columns)


def _log_points(
    rec, t: np.ndarray, group: str, data: Mapping[str, np.ndarray], color, radius: float
) -> dict[str, np.ndarray]:
    """``world/<group>/<name>``: one labelled point per time row (NaN rows skipped)."""
    rr = import_rerun()
    out = {}
    for name, xyz in data.items():
        xyz = check_series(xyz, len(t), (3,), name)
        ok = _finite(xyz)
        entity = f"world/{group}/{name}"
        rec.log(
            entity,
            rr.Points3D.from_fields(
                colors=[color], radii=[radius], labels=[name], show_labels=False
            ),
            static=True,
        )
        if ok.any():
            send_columns(rec, entity, t, ok, rr.Points3D.columns(positions=xyz[ok]))
        out[name] = xyz
    return out


def _log_error_arrows(
    rec, t: np.ndarray, est: Mapping[str, np.ndarray], ref: Mapping[str, np.ndarray]
) -> None:
    """``world/errors/<name>``: arrow reference -> estimate for the names in both."""
    rr = import_rerun()
    for name in est.keys() & ref.keys():
        ok = _finite(est[name]) & _finite(ref[name])
        entity = f"world/errors/{name}"
        rec.log(entity, rr.Arrows3D.from_fields(colors=[ERROR_COLOR]), static=True)
        if ok.any():
            cols = rr.Arrows3D.columns(origins=ref[name][ok], vectors=est[name][ok] - ref[name][ok])
            send_columns(rec, entity, t, ok, cols)


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
    """``<group>/<name>``: ``Transform3D`` columns (translation, xyzw quaternion), static axes."""
    rr = import_rerun()
    for name, (R, p) in poses.items():
        R = check_series(R, len(t), (3, 3), f"{name} R")
        p = check_series(p, len(t), (3,), f"{name} p")
        ok = _finite(R) & _finite(p)
        entity = f"{group}/{name}"
        if axis_length is not None:
            rec.log(entity, rr.TransformAxes3D(axis_length), static=True)
        if ok.any():
            xyzw = quat_xyzw_from_matrix(R[ok])  # rerun: scalar-last
            columns = rr.Transform3D.columns(translation=p[ok], quaternion=xyzw)
            send_columns(rec, entity, t, ok, columns)


def log_scalars(rec, t: np.ndarray, series: Mapping[str, np.ndarray], scale: float = 1.0) -> None:
    """Entity path -> ``(N,)`` series times ``scale``, as ``Scalars`` (NaN rows skipped)."""
    rr = import_rerun()
    for entity, y in series.items():
        y = check_series(y, len(t), (), entity)
        ok = np.isfinite(y)
        if ok.any():
            send_columns(rec, entity, t, ok, rr.Scalars.columns(scalars=scale * y[ok]))


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
    t = check_time(time)
    _check_up_axis(up_axis)
    plots = [("joint angles (deg)", "/plots")] if joint_angles else []
    blueprint = _blueprint(plots, up_axis)
    with open_recording(path, app_id, recording_name, up_axis, blueprint) as rec:
        log_landmarks(rec, t, landmarks, reference_landmarks, error_arrows, point_radius)
        log_poses(rec, t, "world/segments", segment_poses or {}, axis_length)
        angles = {f"plots/{name}": q for name, q in (joint_angles or {}).items()}
        log_scalars(rec, t, angles, scale=float(np.degrees(1.0)))
        if urdf_path is not None:
            _log_urdf(rec, Path(urdf_path), urdf_root, package_paths)
    return path


def _log_urdf(rec, urdf_path: Path, urdf_root, package_paths) -> None:
    rr = import_rerun()
    if not urdf_path.is_file():
        raise InputError("no such URDF file", file=urdf_path)
    root_link = _urdf_root_link(urdf_path)
    R, p = (rot_x(np.pi / 2), np.zeros(3)) if urdf_root is None else urdf_root
    rec.log(
        "world/model_root",
        rr.Transform3D(
            translation=np.asarray(p, dtype=float),
            mat3x3=np.asarray(R, dtype=float),
            parent_frame="tf#/world",
            child_frame=root_link,
        ),
        static=True,
    )
    folders = [str(Path(f)) for f in (package_paths or _default_package_paths(urdf_path))]
    existing = os.environ.get("ROS_PACKAGE_PATH")
    if existing:
        folders.append(existing)
    with _env("ROS_PACKAGE_PATH", os.pathsep.join(folders)):
        rec.log_file_from_path(urdf_path, entity_path_prefix="world/model", static=True)
        rec.flush()  # the importer streams meshes asynchronously; wait while the path is set


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
