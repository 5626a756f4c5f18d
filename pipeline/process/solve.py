"""Step 6 of :func:`pipeline.process.process_recording`: the IK of the calibrated model on every
sensor frame, and what the solved configurations give: the observed joints' ISB angles, the
pelvis's angles in the subject's heading, the landmark trajectories.
"""

from __future__ import annotations

import numpy as np

from pipeline.analysis.joint_angles import joint_angles
from pipeline.analysis.landmarks import landmark_trajectories
from pipeline.calibration.placement import pose_configuration
from pipeline.ik.bounds import remove_limits
from pipeline.ik.solver import IKResult, solve_ik
from pipeline.model.conventions import landmark_segment
from pipeline.model.skeleton import Skeleton
from pipeline.process.options import IKOptions
from pipeline.process.pose import CalibrationPose
from pipeline.process.sensors import SensorSet
from pipeline.rotations import euler_zxy_from_matrix, quat_xyzw_from_matrix, unwrap_angles

__all__ = ["PELVIS_ANGLES", "joint_angles_of", "landmarks_of", "observed", "observed_angles",
           "same_sensor_runs", "solve"]

#: The pelvis's ZXY angles in the subject's heading, OpenSim's names.
PELVIS_ANGLES = ("pelvis_tilt", "pelvis_list", "pelvis_rotation")


def solve(geometry, opts: IKOptions, legs, placements, rotations, cal: CalibrationPose,
          pelvis: bool) -> tuple[Skeleton, np.ndarray, IKResult]:
    """Step 6: the IK of every sensor frame; ``(skeleton, Q, result)`` with Q the spherical-root
    configurations. Each run of frames over which the same sensors are present (a sensor's
    missing samples are NaN, :mod:`pipeline.process.missing`) is solved on its own, started from
    the pose's joint angles with the pelvis where its sensor puts it at the run's first frame
    (the pose may be read anywhere in the recording; a warm start carried across a gap, where a
    segment was free, could settle in another branch). Without a pelvis sensor the pelvis is
    held in its calibration-pose orientation and the hips absorb the thighs' whole orientation,
    so they are not limited."""
    targets = {f"{seg}_imu": R for seg, R in rotations.items()}
    if pelvis:
        sk = Skeleton.build(geometry, knee=opts.knee, legs=legs, imu_placements=placements,
                            root="spherical")
        result = _by_runs(sk.model, targets, opts, lambda first: _pose_q(
            sk, _held_pose(opts), _pelvis_at(rotations, placements, first)))
        return sk, result.q, result
    fixed = Skeleton.build(geometry, knee=opts.knee, legs=legs, imu_placements=placements)
    remove_limits(fixed.model, [f"{s}_hip_{a}" for s in legs for a in "ZXY"])
    q0 = _pose_q(fixed, _held_pose(opts), None)
    result = _by_runs(fixed.model, targets, opts, lambda first: q0, root=cal.pose["pelvis"])
    root = np.tile(quat_xyzw_from_matrix(cal.pose["pelvis"]), (len(result.q), 1))
    return fixed.with_root("spherical"), np.hstack([root, result.q]), result


def _pelvis_at(rotations, placements, k: int) -> np.ndarray | None:
    """The pelvis's world orientation at frame ``k`` (None where its sensor misses it)."""
    R = rotations["pelvis"][k] @ placements["pelvis_imu"][:3, :3].T
    return R if np.all(np.isfinite(R)) else None


def same_sensor_runs(targets: dict[str, np.ndarray]) -> list[slice]:
    """The runs of frames over which the same targets are finite (one run without gaps)."""
    present = np.stack([np.all(np.isfinite(R), axis=(1, 2)) for R in targets.values()], axis=1)
    cuts = np.flatnonzero(np.any(present[1:] != present[:-1], axis=1)) + 1
    bounds = [0, *cuts.tolist(), len(present)]
    return [slice(a, b) for a, b in zip(bounds[:-1], bounds[1:], strict=True)]


def _by_runs(model, targets, opts: IKOptions, start, root=None) -> IKResult:
    """:func:`~pipeline.ik.solve_ik` on each of :func:`same_sensor_runs`, each started from
    ``start(its first frame)``, the results put back in one."""
    parts = [solve_ik(model, {k: R[run] for k, R in targets.items()}, q0=start(run.start),
                      root=root, limits=opts.joint_limits)
             for run in same_sensor_runs(targets)]
    if len(parts) == 1:
        return parts[0]
    return IKResult(*(np.concatenate([getattr(p, f) for p in parts]) for f in
                      ("q", "residual_rms", "iterations", "converged", "task_errors")),
                    parts[0].tasks)


def joint_angles_of(sk, Q, sensors: SensorSet, rotations, placements, H) -> dict[str, np.ndarray]:
    """The observed joints' ISB angles and, with a pelvis sensor, the pelvis' ZXY angles in the
    subject's heading; continuous (a subject turning round must not jump by 360 deg)."""
    return observed_angles(joint_angles(sk, Q), sensors, rotations, placements, H)


def observed_angles(angles, sensors: SensorSet, rotations, placements, H) -> dict[str, np.ndarray]:
    """:func:`joint_angles_of` from the model's joint angles ``angles`` (all joints)."""
    angles = {k: v for k, v in angles.items() if observed(k, sensors)}
    if sensors.pelvis:
        pelvis_world = rotations["pelvis"] @ placements["pelvis_imu"][:3, :3].T
        zxy = euler_zxy_from_matrix(np.einsum("ij,njk->nik", H.T, pelvis_world))
        angles.update(zip(PELVIS_ANGLES, zxy.T, strict=True))
    return {name: unwrap_angles(a) for name, a in angles.items()}


def _side(segment: str) -> str:
    return segment.split("_", 1)[0]


def observed(name: str, sensors: SensorSet) -> bool:
    """Whether an angle (``right_knee_flexion``) or joint (``right_knee_Z``) is observed."""
    side, rest = name.split("_", 1)
    return sensors.observes(side, rest.split("_", 1)[0])


def _held_pose(opts: IKOptions) -> str:
    """The pose the model holds at the calibration (the walk's calibration: standing)."""
    return "standing" if opts.calibration_pose == "walking" else opts.calibration_pose


def _pose_q(sk: Skeleton, pose: str, pelvis: np.ndarray | None) -> np.ndarray:
    q = pose_configuration(sk, pose)
    if pelvis is not None:
        q[:4] = quat_xyzw_from_matrix(pelvis)
    return q


def landmarks_of(sk: Skeleton, Q: np.ndarray, sensors: SensorSet) -> dict[str, np.ndarray]:
    names = [f for f in sk.landmark_frames if landmark_segment(f) in sensors.landmark_segments]
    if not names:
        return {}
    hips = [f"{s}_HJC" for s in sensors.legs]
    traj = landmark_trajectories(sk, Q, names + [h for h in hips if h not in names])
    if not sensors.pelvis:
        traj = {n: traj[n] - traj[f"{_side(n)}_HJC"] for n in names}
    return {n: traj[n] for n in names}
