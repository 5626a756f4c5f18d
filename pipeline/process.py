"""From a recording of IMU orientations to joint angles and landmark trajectories.

:func:`process_recording` is the pipeline that the Python API, ``pipeline ik``, the demo and the
reproduction share; it writes nothing (outputs are the commands' job). On our scaled Pinocchio
model, the workflow of OpenSim's OpenSense:

1. **World.** Sensor orientations ``R_s(t)`` (sensor axes in the IMU world) are pre-multiplied by a
   fixed ``sensor_to_model`` rotation (OpenSense's ``sensor_to_opensim_rotations``, space-fixed XYZ
   angles; ``-pi/2 0 0`` for Xsens' z-up world) so that the world's y axis points up.
2. **Heading** (:mod:`pipeline.calibration.heading`): the subject's right at the calibration pose,
   from hip and knee flexion by default or from an axis of the pelvis sensor (OpenSense's way).
3. **Calibration pose** (:func:`pipeline.calibration.placement.placements_from_pose`): the first
   sample is a standing pose; each IMU's rotation on its segment follows from it.
4. **IK.** Weighted orientation IK of all IMU frames (:func:`pipeline.ik.solve_ik`) with a spherical
   pelvis root; ISB joint angles (:func:`pipeline.analysis.joint_angles`) and landmark trajectories
   (pelvis fixed at the origin: translations are not observable from orientations) follow.
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field

import numpy as np

from pipeline.analysis.landmarks import joint_angles, landmark_trajectories
from pipeline.analysis.quality import quality_flags
from pipeline.calibration.heading import check_vertical, heading_rotation, subject_right
from pipeline.calibration.placement import placements_from_pose
from pipeline.errors import InputError
from pipeline.ik.solver import solve_ik
from pipeline.io.opensim import (
    SENSOR_TO_SEGMENT,
    map_sensors,
    rotate_world,
    sensor_to_opensim_matrix,
)
from pipeline.io.recording import Recording
from pipeline.model.anthropometry import Measures
from pipeline.model.conventions import DEFAULT_KNEE
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import (
    euler_zxy_from_matrix,
    matrix_from_quat,
    quat_xyzw_from_matrix,
    unwrap_angles,
)

__all__ = ["MOT_NAMES", "IKRun", "check_sensor_to_model", "mot_columns", "process_recording"]

#: OpenSim-style coordinate names (Rajagopal 2015 style: knee flexion positive) for our ISB angles.
MOT_NAMES = {
    "hip_flexion": "hip_flexion",
    "hip_adduction": "hip_adduction",
    "hip_rotation": "hip_rotation",
    "knee_flexion": "knee_angle",
    "knee_adduction": "knee_adduction",
    "knee_rotation": "knee_rotation",
}


@dataclass
class IKRun:
    """Everything :func:`process_recording` produced (SI units).

    ``skeleton``: the calibrated subject model (spherical pelvis root; its ``urdf`` text carries
    the IMU frames), ``q`` its configurations; ``joint_angles`` ISB angles (rad) and the pelvis'
    ZXY angles, each continuous (unwrapped: no jump of 2 pi between samples, so a range may
    exceed [-pi, pi] when the subject turns round); ``landmarks`` (N, 3) m, pelvis at the origin;
    ``heading_right`` the subject's right at t0 (world); ``flags`` implausible results
    (:mod:`pipeline.analysis.quality`); ``residual_rms`` (N,) rad; ``seconds_ik``
    the solve time.
    """

    time: np.ndarray
    q: np.ndarray
    joint_angles: dict[str, np.ndarray]
    landmarks: dict[str, np.ndarray]
    heading_right: np.ndarray
    heading_method: str
    residual_rms: np.ndarray
    skeleton: Skeleton
    seconds_ik: float
    notes: list[str] = field(default_factory=list)
    flags: list[str] = field(default_factory=list)


def process_recording(
    trial: Recording,
    measures: Measures,
    *,
    knee: str = DEFAULT_KNEE,
    sensor_to_model: tuple[float, float, float] | None = None,
    heading: str = "anatomical",
) -> IKRun:
    """Steps 1-4 of the module docstring on a read recording; nothing is written."""
    notes = list(trial.notes)
    world = np.eye(3)
    if sensor_to_model is not None:
        world = sensor_to_opensim_matrix(check_sensor_to_model(sensor_to_model))
        trial = rotate_world(trial, world)
    rotations = {seg: matrix_from_quat(q) for seg, q in map_sensors(trial).items()}
    if "pelvis" not in rotations:
        raise InputError("a pelvis sensor (pelvis_imu) is required", file=trial.source)
    legs = tuple(s for s in ("right", "left") if f"{s}_femur" in rotations)
    if not legs:
        raise InputError("no thigh sensor (femur_r_imu / femur_l_imu)", file=trial.source)
    ignored = sorted(set(trial.sensor_names) - set(_used_sensor_names(trial)))
    if ignored:
        notes.append(f"sensors without a segment in this lower-limb model, ignored: {ignored}")

    check_vertical(rotations["pelvis"], notes=notes, applied=world)
    right = subject_right(rotations, heading, notes=notes)
    H = heading_rotation(right)
    geometry, _ = geometry_from_measures(measures)
    # the model's segment orientations in its neutral (standing) pose: the world axes for a free
    # knee; a hinge about a tilted AoR turns the tibia (and foot) by the aligning rotation
    neutral = Skeleton.build(geometry, knee=knee, legs=legs)
    placements = placements_from_pose(neutral, geometry, rotations, H)
    sk = Skeleton.build(geometry, knee=knee, legs=legs, imu_placements=placements,
                        root="spherical")  # fmt: skip
    targets = {f"{seg}_imu": R for seg, R in rotations.items() if f"{seg}_imu" in placements}
    q0 = sk.neutral()
    q0[:4] = quat_xyzw_from_matrix(H)
    t0 = _time.perf_counter()
    result = solve_ik(sk.model, targets, q0=q0)
    seconds = _time.perf_counter() - t0
    if not np.all(result.converged):
        notes.append(f"IK did not converge on {int(np.sum(~result.converged))} frames")
    angles = joint_angles(sk, result.q)
    pelvis_world = rotations["pelvis"] @ placements["pelvis_imu"][:3, :3].T
    zxy = euler_zxy_from_matrix(np.einsum("ij,njk->nik", H.T, pelvis_world))
    angles["pelvis_tilt"], angles["pelvis_list"], angles["pelvis_rotation"] = zxy.T
    # continuous angles: a subject turning round must not make pelvis_rotation jump by 360 deg
    angles = {name: unwrap_angles(a) for name, a in angles.items()}
    landmarks = landmark_trajectories(sk, result.q)
    flags = quality_flags(sk, result.q, result.residual_rms, notes)
    return IKRun(trial.time, result.q, angles, landmarks, right, heading, result.residual_rms,
                 sk, seconds, notes, flags)  # fmt: skip


def check_sensor_to_model(angles: tuple[float, float, float]) -> tuple[float, float, float]:
    """The three ``sensor_to_model`` angles (rad) if finite and within [-2 pi, 2 pi]; refused
    otherwise, with a hint when they look like degrees (e.g. ``-90 0 0`` for ``-1.5708 0 0``)."""
    a = np.asarray(angles, dtype=float).ravel()
    if a.shape != (3,):
        raise InputError(f"expected three angles, got {a.size}", field="sensor_to_model")
    if not np.all(np.isfinite(a)):
        raise InputError(f"expected finite angles in radians, got {a.tolist()}",
                         field="sensor_to_model")  # fmt: skip
    if np.any(np.abs(a) > 2 * np.pi + 1e-9):
        rad = " ".join(f"{v:.4f}" for v in np.radians(a))
        raise InputError(
            f"angles {a.tolist()} exceed 2 pi: they are radians; if you meant degrees, give "
            f"{rad}",
            field="sensor_to_model",
        )
    return float(a[0]), float(a[1]), float(a[2])


def _used_sensor_names(trial: Recording) -> list[str]:
    return [s for s in trial.sensor_names if SENSOR_TO_SEGMENT.get(s, "torso") != "torso"]


def mot_columns(run: IKRun) -> dict[str, np.ndarray]:
    """OpenSim-style coordinate columns (radians; :func:`write_mot` converts to degrees)."""
    cols = {k: run.joint_angles[k] for k in ("pelvis_tilt", "pelvis_list", "pelvis_rotation")}
    for side, suffix in (("right", "r"), ("left", "l")):
        for ours, theirs in MOT_NAMES.items():
            key = f"{side}_{ours}"
            if key in run.joint_angles:
                cols[f"{theirs}_{suffix}"] = run.joint_angles[key]
    return cols


