"""IMU placement on its segment: the sensor-to-segment rotation (and position) of each IMU frame.

* :func:`placements_from_pose`: from a calibration pose in which every segment's world orientation
  is known up to the heading (:func:`pose_rotations`). Standing: the model's neutral pose turned
  by the heading ``H`` about the vertical; supine: the same joint angles lying on the back;
  seated: hips and knees flexed 90 deg. Each IMU's rotation in its segment is
  ``R_seg,imu = R_seg^T R_s`` with ``R_seg`` the segment's world orientation in the pose (in the
  neutral pose the identity times ``H`` for the free knee; a hinge about a tilted AoR turns the
  tibia and foot by the rotation aligning the tibial AoR onto the femoral) and ``R_s`` the
  sensor's orientation then (the first sample, or the mean of a static trial,
  :func:`mean_rotation`). Positions are not observable from orientations: the model's default IMU
  positions are kept.
* :func:`imu_placements_from_calibration`: thigh and shank IMU frames from a joint-constraint
  hinge calibration (Hu 2021 eq 4-6, 16): what the data determine and what must be assumed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np

from pipeline.calibration.conventions import CALIBRATION_POSES
from pipeline.errors import InputError
from pipeline.model.builder import default_imu_placements
from pipeline.model.geometry import SubjectGeometry
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import normalize, project_to_so3, rot_z, rotation_aligning_with_twist

__all__ = [
    "PlacementEstimate",
    "imu_placements_from_calibration",
    "mean_rotation",
    "placements_from_pose",
    "pose_configuration",
    "pose_rotations",
]


def pose_configuration(skeleton: Skeleton, pose: str) -> np.ndarray:
    """The joint configuration of a calibration pose (module docstring) on ``skeleton``.

    ``standing`` and ``supine``: the neutral configuration (``q = 0``); ``seated``: hip flexion
    and knee flexion of 90 deg on every leg (the root, if any, is left at its neutral value).
    """
    if pose not in CALIBRATION_POSES:
        raise InputError(f"expected a calibration pose in {CALIBRATION_POSES}, got {pose!r}",
                         field="calibration_pose")
    q = skeleton.neutral()
    if pose == "seated":
        knee = "knee_Z" if skeleton.knee == "free" else "knee"
        for side in skeleton.legs:
            q[skeleton.q_index(f"{side}_hip_Z")] = np.pi / 2
            q[skeleton.q_index(f"{side}_{knee}")] = np.pi / 2
    return q


def pose_rotations(skeleton: Skeleton, pose: str, heading: np.ndarray) -> dict[str, np.ndarray]:
    """Segment name -> world orientation (3x3) of every segment in a calibration pose.

    ``R_seg = H B R_seg^0(q_pose)`` with ``H`` the heading (rotation about the vertical y),
    ``R_seg^0`` the segment's orientation relative to the pelvis in the pose's configuration
    (:func:`pose_configuration`) and ``B`` the body's attitude: the identity standing or seated,
    ``Rz(+90 deg)`` supine (the body turned about its right axis so that anterior, x, points up
    and the head, y, points to -x of the heading frame).
    """
    skeleton.forward(pose_configuration(skeleton, pose))
    B = rot_z(np.pi / 2) if pose == "supine" else np.eye(3)
    root = np.asarray(heading, dtype=float) @ B
    return {seg: root @ skeleton.frame_rotation(seg) for seg in skeleton.segment_frames}


def placements_from_pose(
    pose: Mapping[str, np.ndarray],
    geometry: SubjectGeometry,
    sensors: Mapping[str, np.ndarray],
    legs: Sequence[str] = ("right", "left"),
) -> dict[str, np.ndarray]:
    """IMU frame -> 4x4 placement in its segment from one calibration pose (module docstring).

    ``pose``: segment name -> its world orientation in the pose (:func:`pose_rotations`);
    ``sensors``: segment name -> the world orientation (3x3) of the sensor on that segment at that
    moment. ``R_seg,imu = R_seg^T R_s``; positions are the model's defaults
    (:func:`default_imu_placements`). Segments missing from ``pose`` are left out.
    """
    defaults: dict[str, np.ndarray] = {}
    for side in legs:
        defaults.update(default_imu_placements(geometry.for_side(side)))
    placements = {}
    for seg, R in sensors.items():
        frame = f"{seg}_imu"
        if seg not in pose or frame not in defaults:
            continue
        T = np.eye(4)
        T[:3, :3] = np.asarray(pose[seg]).T @ np.asarray(R, dtype=float)
        T[:3, 3] = defaults[frame][:3, 3]
        placements[frame] = T
    return placements


def mean_rotation(R: np.ndarray) -> np.ndarray:
    """Chordal L2 mean of rotations ``(N, 3, 3)`` (NaN rows skipped): the rotation nearest to
    their arithmetic mean (SVD projection), the standard average of a still sensor's samples."""
    R = np.asarray(R, dtype=float)
    ok = np.all(np.isfinite(R), axis=(1, 2))
    if not ok.any():
        raise InputError("expected at least one finite orientation sample", field="orientations")
    return project_to_so3(R[ok].mean(axis=0))


@dataclass(frozen=True)
class PlacementEstimate:
    """IMU frame name -> 4x4 placement in its segment frame (for ``build_urdf``), the common
    shift along the knee axis that was assumed (``axial_shift_m``: KJC -> eq-16 point, m), and
    how the twist about the axis was fixed (``twist_from``: 'static pose' or 'default')."""

    placements: dict[str, np.ndarray]
    axial_shift_m: float
    twist_from: str
    notes: tuple[str, ...]


def imu_placements_from_calibration(
    skeleton,
    axis_1: np.ndarray,
    axis_2: np.ndarray,
    position_1_m: np.ndarray,
    position_2_m: np.ndarray,
    *,
    side: str = "right",
    static_acc: tuple[np.ndarray, np.ndarray] | None = None,
    static_up: tuple[np.ndarray, np.ndarray] = ((0.0, 1.0, 0.0), (0.0, 1.0, 0.0)),
    undetermined: Sequence[str] = (),
) -> PlacementEstimate:
    """Thigh and shank IMU frames from a hinge calibration (Hu 2021 eq 4-6, 16) on ``skeleton``.

    Inputs: the knee axis ``axis_S`` and the eq-16 joint point ``position_S_m`` (sensor -> point)
    in the thigh (1) and shank (2) sensor frames. The model gives the knee axis ``a_G`` pointing
    right and the knee centre ``c_G`` in each segment (:meth:`Skeleton.knee_axis`, KJC frames).

    Rotation ``R_GS`` (sensor axes in the segment): ``R_GS j_S = a_G`` fixes two of its three
    DoF. The twist about the axis is not determined by a hinge calibration. It is fixed

    * from a static pose when ``static_acc`` (mean specific force of sensors 1, 2 while still)
      is given: ``R_GS f_S`` is aligned with the up direction ``static_up`` of each segment in
      that pose (default: standing in the neutral pose, segment y axes vertical);
    * otherwise by keeping the model's current IMU frame orientation ``R_def`` as far as the
      axis allows (the rotation with ``R j = a`` nearest to ``R_def``).

    The axis signs (both flipped together by the calibration) are chosen so that ``R_def j_1``
    points right, i.e. the current frames must be within 90 deg of the truth.

    Position: the eq-16 point lies on the axis, ``p_GS + R_GS o_S = c_G + lambda a_G``. The
    relative position of both sensors along the axis is determined; one common shift ``lambda``
    is not (any point of a hinge axis satisfies the constraint). It is chosen so that the mean
    axial coordinate of the two sensors stays that of the current IMU frames (least squares).
    """
    if static_acc is not None and len(static_acc) != 2:
        raise InputError("expected static_acc as (thigh, shank) 3-vectors", field="static_acc")
    a_f, a_t = skeleton.knee_axis(side)
    names = (f"{side}_femur", f"{side}_tibia")
    q0 = skeleton.neutral()
    centres = [skeleton.relative_pose(f"{side}_KJC", seg, q0)[:3, 3] for seg in names]
    defaults = [skeleton.relative_pose(f"{seg}_imu", seg, q0) for seg in names]
    js = [normalize(np.asarray(axis_1, float)), normalize(np.asarray(axis_2, float))]
    os_ = [np.asarray(position_1_m, float), np.asarray(position_2_m, float)]
    if np.dot(defaults[0][:3, :3] @ js[0], a_f) < 0:
        js = [-js[0], -js[1]]
    notes = []
    rotations = []
    for k, (j, a, T) in enumerate(zip(js, (a_f, a_t), defaults, strict=True)):
        if static_acc is not None:
            f = normalize(np.asarray(static_acc[k], float))
            R = rotation_aligning_with_twist(j, a, f, np.asarray(static_up[k], float))
        else:
            R = rotation_aligning_with_twist(j, a, np.eye(3), T[:3, :3].T)
        rotations.append(R)
    twist = "static pose" if static_acc is not None else "default"
    if static_acc is None:
        notes.append("twist about the knee axis kept from the current IMU frames (undetermined)")
    # lambda_S = a.(p_def - c) + j.o per sensor; the common shift is their mean.
    lams = [
        float(a @ (T[:3, 3] - c) + j @ o)
        for a, T, c, j, o in zip((a_f, a_t), defaults, centres, js, os_, strict=True)
    ]
    lam = float(np.mean(lams))
    notes.append(f"common shift along the knee axis assumed: {lam * 1000:.1f} mm from the KJC")
    placements = {}
    for seg, R, a, c, o in zip(names, rotations, (a_f, a_t), centres, os_, strict=True):
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = c + lam * a - R @ o
        placements[f"{seg}_imu"] = T
    if undetermined:
        notes.append("calibration reported undetermined: " + "; ".join(undetermined))
    return PlacementEstimate(placements, lam, twist, tuple(notes))
