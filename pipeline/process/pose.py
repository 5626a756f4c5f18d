"""The calibration pose step of :func:`pipeline.process.process_recording` (steps 3-4): the
subject's heading and each sensor's placement on its segment, read where the recording shows the
pose, or from the walk itself where it shows none.

:func:`read_calibration_pose` returns a :class:`CalibrationPose`: the subject's right (world) and
the heading rotation ``H``, the model's segment orientations in the pose, and the placements
(IMU frame -> 4x4 placement in its segment), read at one sample (``at``: the first sample of the
still window the pose is read in, :mod:`pipeline.process.still`) or from the mean of a static
trial. The heading comes from the motion relative to the pose
(:func:`pipeline.calibration.heading.subject_right`); a static trial's mean orientations, or a
window's that is not the recording's start, are put in front of the motion so that the same cue
applies. :func:`walking_calibration_pose` builds the same from the segments' axes the walk shows
(:mod:`pipeline.process.walking_pose`).

**Where the pose is read** (:func:`choose_source`): a static trial when given; else the first
still window (every sensor at rest for a second, at the start, the end or in a pause) whose
segments stand as the pose puts them; else the walk (no still window, or none showing the pose,
or ``calibration_pose='walking'``); else, with neither, the first sample, unchecked (a flag).
**The pose is checked, not assumed**: where the subject walks, the walk's own calibration tells
each segment's long axis, and a window's pose must agree with the pose asked for: each of the
pelvis's, thighs' and shanks' long axes within :data:`POSE_TOL_DEG` of where the pose puts it
(standing: vertical; supine: horizontal; seated: the thighs horizontal, the rest vertical).
Measured on S02 (vendor orientations, 6-D): its standing start and end put every long axis within
2-9 deg of the vertical, as a supine pose would put them 90 deg from it.
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
from pipeline.model.geometry import SubjectGeometry
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import matrix_from_quat, rotation_aligning

__all__ = ["MIN_STILL_S", "STILL_HEADING_DEG", "CalibrationPose", "PoseInputs",
           "read_calibration_pose", "static_orientations", "still_gravity",
           "walking_calibration_pose"]

#: A still run shorter than this (s) gives no accelerometer vertical (:func:`still_gravity`).
MIN_STILL_S = 0.5


@dataclass(frozen=True)
class CalibrationPose:
    """The subject's ``right`` (world) at the calibration pose and the heading rotation ``H``;
    ``pose``: segment -> its orientation in the pose (world); ``placements``: IMU frame -> 4x4
    placement on its segment; ``at_pose``: segment -> its sensor's orientation at the pose;
    ``how``: where and how it was read (the summary's line); ``walked``: built from the walk
    (:func:`walking_calibration_pose`), no pose held."""

    right: np.ndarray
    H: np.ndarray
    pose: dict[str, np.ndarray]
    placements: dict[str, np.ndarray]
    at_pose: dict[str, np.ndarray]
    how: str = ""
    walked: bool = False

    def with_pose(self, pose: dict[str, np.ndarray], geometry, legs) -> CalibrationPose:
        """The same calibration with other segment orientations in the pose (e.g. the measured
        standing posture, :mod:`pipeline.process.posture`), the placements read again."""
        placements = placements_from_pose(pose, geometry, self.at_pose, legs)
        return CalibrationPose(self.right, self.H, pose, placements, self.at_pose, self.how,
                               self.walked)


@dataclass(frozen=True)
class PoseInputs:
    """What reading a pose needs besides the orientations: the model (``model``, built for the
    pose's configurations), the subject's ``geometry``, the ``legs`` and the run's ``options``
    (``calibration_pose``, ``heading``, ``segment_orientations``)."""

    model: Skeleton
    geometry: SubjectGeometry
    legs: tuple[str, ...]
    options: object


def still_gravity(trial: Recording, segments, at: int = 0) -> dict[str, np.ndarray]:
    """Segment -> the vertical in its sensor's frame over the still run that starts at sample
    ``at`` (or at its sensor's first own sample after it, up to its next missing one): the mean
    accelerometer direction (at rest it reads gravity alone), for the sensors still from there
    for at least :data:`MIN_STILL_S`
    (:func:`~pipeline.calibration.attitude.still_start`)."""
    out = {}
    for seg in segments:
        s = trial.sensors.get(SEGMENT_SENSOR[seg])
        if s is None or s.acc is None or s.gyr is None:
            continue
        own = trial.present(SEGMENT_SENSOR[seg])
        k = at + int(np.argmax(own[at:])) if own[at:].any() else at  # its first own sample
        n0 = still_start(s.gyr[k:], s.acc[k:])
        n0 = int(np.argmin(own[k : k + n0])) if not own[k : k + n0].all() else n0
        if n0 >= 2 and trial.time[k + n0 - 1] - trial.time[k] >= MIN_STILL_S:
            a = s.acc[k : k + n0].mean(axis=0)
            out[seg] = a / np.linalg.norm(a)
    return out


def _first_known(R: np.ndarray, at: int) -> int:
    """The first sample from ``at`` on where ``R`` (N, 3, 3) is known (``at`` itself if none)."""
    known = np.isfinite(R[at:]).all(axis=(1, 2))
    return at + int(np.argmax(known)) if known.any() else at


def _tilted_onto(R: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``R`` turned by the smallest rotation that puts its vertical (y up) onto ``g``."""
    u = R.T @ np.array([0.0, 1.0, 0.0])
    return R @ rotation_aligning(g, u)


def read_calibration_pose(
    rotations: dict[str, np.ndarray],
    inputs: PoseInputs,
    notes: list[str] | None,
    *,
    at: int = 0,
    static_pose: dict[str, np.ndarray] | None = None,
    gravity: dict[str, np.ndarray] | None = None,
) -> CalibrationPose:
    """The calibration pose (module docstring) from the sensors' orientations ``rotations``
    (segment -> (N, 3, 3), y-up world) at sample ``at`` (each at its first known sample from
    there: a sensor that started late) or, if given, the static trial's mean orientations.

    ``gravity``: segment -> the vertical in its sensor's frame over the still run at ``at``
    (:func:`still_gravity`): the sensor's orientation there is tilted, by the smallest turn,
    onto it. At rest the accelerometer reads the vertical to a tenth of a degree, where a
    filter's estimate carries what its smoothing brings back from the motion that follows (VQF's
    offline filter put the simulated sensors' vertical 1 deg off during the still start)."""
    options = inputs.options
    if static_pose is not None:
        at_pose = dict(static_pose)
    else:
        at_pose = {seg: R[_first_known(R, at)] for seg, R in rotations.items()}
        for seg, g in (gravity or {}).items():
            if seg in at_pose:
                at_pose[seg] = _tilted_onto(at_pose[seg], g)
    cue = rotations
    if static_pose is not None or at > 0:  # the motion relative to the pose
        cue = {seg: np.concatenate([at_pose[seg][None], R]) for seg, R in rotations.items()}
    start = (np.pi / 2, np.pi / 2) if options.calibration_pose == "seated" else (0.0, 0.0)
    pose0 = pose_rotations(inputs.model, options.calibration_pose, np.eye(3))  # zero heading
    knee_axes = {s: pose0[f"{s}_femur"] @ inputs.geometry.for_side(s).knee_axis_femur
                 for s in inputs.legs}
    try:
        right = subject_right(cue, options.heading, notes=notes, start_flexion=start,
                              knee_axes=knee_axes)
    except InputError:
        if _largest_joint_turn(rotations) > np.radians(STILL_HEADING_DEG):
            raise
        right = np.array([0.0, 0.0, 1.0])
        if notes is not None:
            notes.append(f"no joint turns by {STILL_HEADING_DEG:g} deg: the subject's heading is "
                         "not observed and was taken as the world's z (a still subject's joint "
                         "angles do not depend on it)")
    H = heading_rotation(right)
    pose = pose_rotations(inputs.model, options.calibration_pose, H)
    if options.segment_orientations:
        at_pose = {seg: pose[seg] for seg in rotations}  # placements: the identity
    placements = placements_from_pose(pose, inputs.geometry, at_pose, inputs.legs)
    return CalibrationPose(right, H, pose, placements, at_pose)


#: A recording in which no hip or knee turns by more than this (deg) is still: its heading is not
#: observed, and not needed (the joint angles of a still pose do not depend on it). S02's 11 s of
#: standing: 6.3 deg at most (the sway, and the shanks' disturbed magnetometers turning their
#: headings); the heading needs 20 (:func:`pipeline.calibration.heading.anatomical_right`).
STILL_HEADING_DEG = 10.0


def _largest_joint_turn(rotations: dict[str, np.ndarray]) -> float:
    """The largest rotation (rad) of a thigh relative to the pelvis or a shank relative to its
    thigh from its first sample, over the recording."""
    from pipeline.rotations import axis_angle

    largest = 0.0
    for side in ("right", "left"):
        for a, b in (("pelvis", f"{side}_femur"), (f"{side}_femur", f"{side}_tibia")):
            if a in rotations and b in rotations:
                rel = np.swapaxes(rotations[a], 1, 2) @ rotations[b]
                _, angle = axis_angle(rel @ rel[0].T)
                largest = max(largest, float(np.nanmax(angle)))
    return largest


def walking_calibration_pose(
    frames: dict[str, np.ndarray],
    rotations: dict[str, np.ndarray],
    inputs: PoseInputs,
    how: str,
) -> CalibrationPose:
    """A calibration pose built from the walk (:mod:`pipeline.process.walking_pose`): ``frames``
    segment -> the rotation from its sensor's frame to the segment's. The pose is the model's
    standing pose in the heading the pelvis (else the thighs) shows at the first sample, and each
    sensor's orientation in it ``R_seg F``: its placement is ``F`` whatever the heading."""
    up = np.array([0.0, 1.0, 0.0])
    z = (rotations["pelvis"][0] @ frames["pelvis"][2] if "pelvis" in frames else
         np.sum([rotations[f"{s}_femur"][0] @ frames[f"{s}_femur"][2] for s in inputs.legs],
                axis=0))
    right = z - (z @ up) * up
    right = right / np.linalg.norm(right)
    H = heading_rotation(right)
    pose = pose_rotations(inputs.model, "standing", H)
    at_pose = {seg: pose[seg] @ frames[seg] for seg in rotations if seg in frames}
    placements = placements_from_pose(pose, inputs.geometry, at_pose, inputs.legs)
    return CalibrationPose(right, H, pose, placements, at_pose, how, walked=True)


def static_orientations(
    static: Recording, segments: list[str], notes: list[str], pose_name: str
) -> dict[str, np.ndarray]:
    """Each sensor's mean orientation over the static trial (:func:`mean_rotation`), for the
    ``segments`` the trial's sensors are on; refused when the static trial lacks one."""
    still = {seg: matrix_from_quat(q) for seg, q in map_sensors(static).items()}
    missing = sorted(set(segments) - set(still))
    if missing:
        raise InputError(f"the static trial lacks sensors for {missing}", file=static.source,
                         field="static_trial")
    notes.append(f"calibration pose ({pose_name}) from the static trial: mean of "
                 f"{static.n_samples} samples")
    return {seg: mean_rotation(still[seg]) for seg in segments}
