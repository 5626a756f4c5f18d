"""The calibration pose step of :func:`pipeline.process.process_recording` (steps 3-4): the
subject's heading and each sensor's placement on its segment, from the first sample or from the
mean of a static trial.

:func:`read_calibration_pose` returns a :class:`CalibrationPose`: the subject's right (world) and
the heading rotation ``H``, the model's segment orientations in the pose, and the placements
(IMU frame -> 4x4 placement in its segment). The heading comes from the motion relative to the
pose (:func:`pipeline.calibration.heading.subject_right`); with a static trial its mean
orientations are put in front of the motion so that the same cue applies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.calibration.attitude import still_start
from pipeline.calibration.heading import heading_rotation, subject_right
from pipeline.calibration.placement import (
    mean_rotation,
    placements_from_pose,
    pose_rotations,
)
from pipeline.errors import InputError
from pipeline.io.opensim import map_sensors
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import matrix_from_quat, rotation_aligning

__all__ = ["MIN_STILL_S", "CalibrationPose", "read_calibration_pose", "static_orientations",
           "still_gravity"]  # fmt: skip

#: A still start shorter than this (s) gives no accelerometer vertical (:func:`still_gravity`).
MIN_STILL_S = 0.5


@dataclass(frozen=True)
class CalibrationPose:
    """The subject's ``right`` (world) at the calibration pose and the heading rotation ``H``;
    ``pose``: segment -> its orientation in the pose (world); ``placements``: IMU frame -> 4x4
    placement on its segment; ``at_pose``: segment -> its sensor's orientation at the pose."""

    right: np.ndarray
    H: np.ndarray
    pose: dict[str, np.ndarray]
    placements: dict[str, np.ndarray]
    at_pose: dict[str, np.ndarray]

    def with_pose(self, pose: dict[str, np.ndarray], geometry, legs) -> CalibrationPose:
        """The same calibration with other segment orientations in the pose (e.g. the measured
        standing posture, :mod:`pipeline.process.posture`), the placements read again."""
        placements = placements_from_pose(pose, geometry, self.at_pose, legs)
        return CalibrationPose(self.right, self.H, pose, placements, self.at_pose)


def still_gravity(trial: Recording, segments) -> dict[str, np.ndarray]:
    """Segment -> the vertical in its sensor's frame over the recording's still start: the mean
    accelerometer direction (at rest it reads gravity alone), for the sensors that start still
    for at least :data:`MIN_STILL_S` (:func:`~pipeline.calibration.attitude.still_start`)."""
    out = {}
    for seg in segments:
        s = trial.sensors.get(SEGMENT_SENSOR[seg])
        if s is None or s.acc is None or s.gyr is None:
            continue
        n0 = still_start(s.gyr, s.acc)
        if n0 >= 2 and trial.time[n0 - 1] - trial.time[0] >= MIN_STILL_S:
            a = s.acc[:n0].mean(axis=0)
            out[seg] = a / np.linalg.norm(a)
    return out


def read_calibration_pose(
    rotations: dict[str, np.ndarray],
    static_pose: dict[str, np.ndarray] | None,
    options,
    pose_model: Skeleton,
    geometry,
    legs: tuple[str, ...],
    notes: list[str] | None,
    gravity: dict[str, np.ndarray] | None = None,
) -> CalibrationPose:
    """The calibration pose (module docstring) from the sensors' orientations ``rotations``
    (segment -> (N, 3, 3), y-up world) and, if given, the static trial's mean orientations.

    ``gravity``: segment -> the vertical in its sensor's frame at a still first sample
    (:func:`still_gravity`): the sensor's orientation there is tilted, by the smallest turn,
    onto it. At rest the accelerometer reads the vertical to a tenth of a degree, where a
    filter's estimate carries what its smoothing brings back from the motion that follows (VQF's
    offline filter put the simulated sensors' vertical 1 deg off during the still start)."""
    if static_pose is not None:
        at_pose = dict(static_pose)
        cue = {seg: np.concatenate([at_pose[seg][None], R]) for seg, R in rotations.items()}
    else:
        at_pose = {seg: R[0] for seg, R in rotations.items()}
        for seg, g in (gravity or {}).items():
            if seg in at_pose:  # the sensor's vertical (y up) turned onto the accelerometer's
                u = at_pose[seg].T @ np.array([0.0, 1.0, 0.0])
                at_pose[seg] = at_pose[seg] @ rotation_aligning(g, u)
        cue = rotations
    start = (np.pi / 2, np.pi / 2) if options.calibration_pose == "seated" else (0.0, 0.0)
    pose0 = pose_rotations(pose_model, options.calibration_pose, np.eye(3))  # zero heading
    knee_axes = {s: pose0[f"{s}_femur"] @ geometry.for_side(s).knee_axis_femur for s in legs}
    right = subject_right(cue, options.heading, notes=notes, start_flexion=start,
                          knee_axes=knee_axes)  # fmt: skip
    H = heading_rotation(right)
    pose = pose_rotations(pose_model, options.calibration_pose, H)
    if options.segment_orientations:
        at_pose = {seg: pose[seg] for seg in rotations}  # placements: the identity
    return CalibrationPose(right, H, pose, placements_from_pose(pose, geometry, at_pose, legs),
                           at_pose)


def static_orientations(
    static: Recording, segments: list[str], notes: list[str], pose_name: str
) -> dict[str, np.ndarray]:
    """Each sensor's mean orientation over the static trial (:func:`mean_rotation`), for the
    ``segments`` the trial's sensors are on; refused when the static trial lacks one."""
    still = {seg: matrix_from_quat(q) for seg, q in map_sensors(static).items()}
    missing = sorted(set(segments) - set(still))
    if missing:
        raise InputError(f"the static trial lacks sensors for {missing}", file=static.source,
                         field="static_trial")  # fmt: skip
    notes.append(f"calibration pose ({pose_name}) from the static trial: mean of "
                 f"{static.n_samples} samples")  # fmt: skip
    return {seg: mean_rotation(still[seg]) for seg in segments}
