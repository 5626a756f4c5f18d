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

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.analysis.joint_angles import joint_angles as isb_joint_angles
from pipeline.analysis.landmarks import frame_trajectories
from pipeline.errors import InputError
from pipeline.io.checks import check_time
from pipeline.model.skeleton import Skeleton
from pipeline.viz.layout import up_axis_index as _check_up_axis
from pipeline.viz.recording import check_series
from pipeline.viz.scene import (
    ANGLE_COLORS,
    BONE_COLOR,
    MotionScene,
    Poses,
    SegmentMesh,
    log_scene,
    meshes_from_urdf,
)

__all__ = ["ANGLE_COLORS", "BONE_COLOR", "SceneOptions", "SegmentMesh", "log_motion",
           "motion_scene", "segment_meshes"]

#: Longer recordings show their 3D content (model, landmarks, IMU frames) at a stride that keeps
#: at most this many samples (36,000: 10 Hz over an hour), the joint angles at the full rate: the
#: viewer plays 3D fluently at that density, and the .rrd of an hour stays ~100 MB.
MAX_3D_SAMPLES = 36_000


def segment_meshes(skeleton: Skeleton) -> dict[str, SegmentMesh]:
    """Segment -> its URDF visual meshes merged, in the segment frame
    (:func:`pipeline.viz.scene.meshes_from_urdf` on the skeleton's URDF)."""
    return meshes_from_urdf(skeleton.urdf, skeleton.source, skeleton.segment_frames)


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


@dataclass(frozen=True)
class SceneOptions:
    """What a motion's recording shows (:func:`log_motion`, :func:`motion_scene`).

    ``landmarks`` / ``imu_frames`` / ``joint_angles``: ``True`` for every landmark / IMU frame /
    ISB angle of the model, ``False`` for none, or a list of names. ``bones``, ``meshes``: draw
    the HJC-KJC-AJC lines, the segments' meshes. ``reference_landmarks``: name -> (N, 3) m (e.g.
    optical markers, keyed like the landmark frames, ``right_EFM``), drawn in another colour
    with error arrows reference -> estimate (``error_arrows``) for the names drawn in both.
    ``reference_angles``: ISB angle name -> (N,) rad (keyed like
    :func:`pipeline.analysis.landmarks.joint_angles`, e.g. ``right_knee_flexion``; NaN where
    unknown), drawn as thin lighter curves ``<angle> (truth)`` in the same plot as the estimate.
    ``extra_scalars``: entity name under ``plots/`` -> (N,) series, logged unchanged.
    ``up_axis``: the view's up (the model is Y-up). ``recording_name``, ``app_id``: the
    recording's. ``imu_axis_length``, ``point_radius`` (m): the IMU axes' and the landmarks'
    size. ``root_path`` (N, 3) m: the model's root moved through the room (every frame drawn
    shifted by it; e.g. the pelvis's path from the feet)."""

    landmarks: bool | Sequence[str] = True
    imu_frames: bool | Sequence[str] = True
    joint_angles: bool | Sequence[str] = True
    bones: bool = True
    meshes: bool = True
    reference_landmarks: Mapping[str, np.ndarray] | None = None
    reference_angles: Mapping[str, np.ndarray] | None = None
    error_arrows: bool = True
    extra_scalars: Mapping[str, np.ndarray] | None = None
    up_axis: str = "y"
    recording_name: str | None = None
    app_id: str = "imu_skeleton_pipeline"
    imu_axis_length: float = 0.06
    point_radius: float = 0.008
    root_path: np.ndarray | None = None


def log_motion(path: str | Path, time: np.ndarray, skeleton: Skeleton, Q: np.ndarray,
               options: SceneOptions | None = None) -> Path:
    """Write the motion ``Q`` (N, nq) of ``skeleton`` at ``time`` (N,) s to ``path`` (.rrd),
    shown as ``options`` say (:class:`SceneOptions`; default: everything). Rows whose
    configuration is not finite are not logged. Returns ``path``; layout in the module
    docstring."""
    return log_scene(path, *_scene(time, skeleton, Q, False, options or SceneOptions()))


def motion_scene(time: np.ndarray, skeleton: Skeleton, Q: np.ndarray,
                 options: SceneOptions | None = None) -> MotionScene:
    """What :func:`log_motion` writes, as arrays: the forward kinematics of every shown sample
    done here, so that :func:`pipeline.viz.scene.log_scene` (e.g. in a forked child, without
    Pinocchio) writes the same recording. Arguments as :func:`log_motion`'s."""
    return _scene(time, skeleton, Q, True, options or SceneOptions())[0]


def _scene(time, skeleton: Skeleton, Q, precompute: bool, o: SceneOptions):
    """``(scene, poses)``: the scene (its poses over every shown sample if ``precompute``) and
    ``poses(start, stop)``, the forward kinematics of ``shown[start:stop]``."""
    t = check_time(time, min_samples=1)
    n = len(t)
    vertical = _check_up_axis(o.up_axis)
    Q = check_series(Q, n, (skeleton.nq,), "Q")
    lm_names = _names(o.landmarks, skeleton.landmark_frames, "landmarks")
    imu_names = _names(o.imu_frames, skeleton.imu_frames, "imu_frames")
    bone_legs = list(skeleton.legs) if o.bones else []
    bone_names = [f"{s}_{j}" for s in bone_legs for j in ("HJC", "KJC", "AJC")]
    segments = skeleton.segment_frames
    scalars = {}
    for name, y in (o.extra_scalars or {}).items():
        scalars[f"plots/{name}"] = check_series(y, n, (), name)

    ok = np.all(np.isfinite(Q), axis=1)
    Q_fk = np.where(ok[:, None], Q, skeleton.neutral())  # FK on finite rows only
    offset = np.zeros((n, 3))
    if o.root_path is not None:  # the body carried through the room
        offset = np.nan_to_num(check_series(o.root_path, n, (3,), "root_path"))
    names = list(dict.fromkeys([*segments.values(), *lm_names, *imu_names, *bone_names]))
    # the 3D content at most MAX_3D_SAMPLES samples (a stride over long recordings), logged in
    # chunks; the joint angles at the full rate
    stride = max(1, -(-n // MAX_3D_SAMPLES))
    shown = np.arange(0, n, stride)

    oriented = {*segments.values(), *imu_names}  # the frames drawn with their rotation

    def trajectories(rows: np.ndarray) -> Poses:
        """Poses of ``names`` at ``rows``; positions only (``R`` None) for points and bones."""
        traj = frame_trajectories(skeleton, Q_fk[rows], names)
        out = {}
        for name, (R, p) in traj.items():
            p += offset[rows]
            p[~ok[rows]] = np.nan
            if name in oriented:
                R[~ok[rows]] = np.nan
            out[name] = (R if name in oriented else None, p)
        return out

    def poses(start: int, stop: int) -> Poses:
        return trajectories(shown[start:stop])

    every = trajectories(shown) if precompute else None
    step = max(1, len(shown) // 2000)  # framing from <= 2000 samples
    view = every if every is not None and step == 1 else trajectories(shown[::step])
    angles = {}
    if o.joint_angles:
        wanted = None if o.joint_angles is True else set(o.joint_angles)
        for key, y in isb_joint_angles(skeleton, Q_fk).items():
            if wanted is not None and key not in wanted:
                continue
            joint, angle = key.rsplit("_", 1)
            angles[f"plots/{joint}/{angle}"] = np.where(ok, y, np.nan)
    truth = {}
    for key, y in (o.reference_angles or {}).items():
        joint, angle = key.rsplit("_", 1)
        if angle not in ANGLE_COLORS:
            raise InputError(f"expected an ISB angle name like right_knee_flexion, got {key!r}",
                             field="reference_angles")
        truth[f"plots/{joint}/{angle}_truth"] = check_series(y, n, (), key)
    reference = {k: check_series(v, n, (3,), k) for k, v in (o.reference_landmarks or {}).items()}
    scene = MotionScene(
        t, shown, ok, skeleton.urdf, skeleton.source, tuple(skeleton.legs), dict(segments),
        lm_names, imu_names, bone_legs, view, every, angles, truth, scalars, reference,
        bool(o.meshes), bool(o.error_arrows), o.up_axis, vertical, o.recording_name, o.app_id,
        float(o.imu_axis_length), float(o.point_radius),
    )
    return scene, poses
