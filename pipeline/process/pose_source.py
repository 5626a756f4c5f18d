"""Where the calibration is read (:mod:`pipeline.process.pose`): a static trial, a still window
whose pose is checked, the walk, or, with none of these, the first sample.

In order (:func:`calibrate`):

1. a static trial, when given: its mean orientations;
2. ``calibration_pose='walking'``: the walk (:mod:`pipeline.process.walking_pose`);
3. the first still window (:mod:`pipeline.process.still`) whose segments lie as the pose asked
   for puts them, checked against the walk's calibration where the subject walks
   (:func:`pose_errors`): each of the pelvis's, thighs' and shanks' long axes within
   :data:`POSE_TOL_DEG` of where the pose puts it (standing: vertical; supine: horizontal;
   seated: the thighs horizontal, the pelvis and shanks vertical). Where the subject does not
   walk nothing tells the segments' axes in the sensors' frames, and the first window is used,
   unchecked (the notes say so);
4. the walk, where no window shows the pose (flagged when windows exist: the pose asked for is
   not the recording's) or there is none;
5. with neither a window nor a walk, the first sample, unchecked (a flag).

The tolerance sits between what a pose can be and what a wrong one is: the long axes of a
standing subject lie within a few degrees of the vertical (S02's standing start and end measured
by its walk's calibration: 2-9 deg, vendor and 6-D), a lying or seated segment's 90 deg from it,
and the walk's calibration is off by up to 5 deg per segment (S02, against Vicon's segments).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.calibration.placement import mean_rotation
from pipeline.errors import InputError
from pipeline.process.pose import (
    CalibrationPose,
    PoseInputs,
    read_calibration_pose,
    still_gravity,
    walking_calibration_pose,
)
from pipeline.process.still import StillWindow
from pipeline.process.walking_pose import WalkingFrames, walking_frames

__all__ = ["POSE_TOL_DEG", "PoseSource", "calibrate", "pose_errors"]

#: A window shows the pose when each long axis lies within this angle (deg) of the pose's.
POSE_TOL_DEG = 30.0
#: Each pose's long axes (pelvis, femur, tibia: their ``y``) from the vertical (deg).
_POSE_ELEVATION = {"standing": {"pelvis": 0.0, "femur": 0.0, "tibia": 0.0},
                   "supine": {"pelvis": 90.0, "femur": 90.0, "tibia": 90.0},
                   "seated": {"pelvis": 0.0, "femur": 90.0, "tibia": 0.0}}
_UP = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class PoseSource:
    """The evidence :func:`calibrate` chooses from: the recording's ``windows``, the walk's
    ``frames`` (None where the subject does not walk or they cannot be had, ``why`` then says
    why), the ``static`` trial's mean orientations (None without one), and the sample the walk
    starts at (its first stride; None without strides)."""

    windows: tuple[StillWindow, ...]
    frames: WalkingFrames | None
    why: str = ""
    static: dict[str, np.ndarray] | None = None
    walk_starts: int | None = None


def pose_errors(window: StillWindow, frames: WalkingFrames, rotations, pose: str
                ) -> dict[str, float]:
    """Segment -> how far (deg) its long axis lies in ``window`` from where ``pose`` puts it, its
    axes in its sensor's frame from the walk (``frames``)."""
    want = _POSE_ELEVATION[pose]
    out = {}
    for seg, F in frames.frames.items():
        kind = seg.split("_", 1)[-1]
        if kind not in want or seg not in rotations:
            continue
        y = mean_rotation(rotations[seg][window.rows]) @ F[1]  # the segment's y in the world
        tilt = float(np.degrees(np.arccos(np.clip(abs(y @ _UP), -1.0, 1.0))))
        out[seg] = abs(tilt - want[kind])
    return out


def source_of(trial, rotations, windows, gait, inputs: PoseInputs) -> PoseSource:
    """The walk's frames where the subject walks (else why not), beside the windows."""
    if not gait.strides:
        return PoseSource(tuple(windows), None, "no strides")
    starts = int(np.searchsorted(trial.time, gait.strides[0].start_s))
    try:
        frames = walking_frames(trial, rotations, gait, inputs.geometry, inputs.legs)
    except InputError as e:
        return PoseSource(tuple(windows), None, e.message, walk_starts=starts)
    return PoseSource(tuple(windows), frames, walk_starts=starts)


def calibrate(trial, rotations, source: PoseSource, inputs: PoseInputs, notes: list[str],
              flags: list[str]) -> CalibrationPose:
    """The calibration pose from the first source of the module docstring that holds; what was
    done goes to ``notes``, what was not as asked to ``flags``."""
    pose = inputs.options.calibration_pose
    if source.static is not None:
        cal = read_calibration_pose(rotations, inputs, notes, static_pose=source.static)
        return _described(cal, f"{pose} pose, from the static trial")
    if pose == "walking":
        if source.frames is None:
            raise InputError(f"--calibration-pose walking: {source.why}",
                             field="calibration_pose")
        return _from_walk(rotations, source.frames, inputs, "asked for")
    checked = {w: _fits(w, source.frames, rotations, pose) for w in source.windows
               if _all_oriented(w, rotations)}
    showing = [w for w, fit in checked.items() if fit is None or fit[0]]
    before = [w for w in showing if source.walk_starts is None or w.stop <= source.walk_starts]
    if before or (showing and source.frames is None):
        return _from_window(trial, rotations, (before or showing)[0], inputs, notes, checked)
    if source.frames is not None:
        if checked and not showing:
            flags.append(f"no still window shows the {pose} pose ("
                         + "; ".join(f"{w.span}: {fit[1]}" for w, fit in checked.items())
                         + "): calibrated from the walk instead; check --calibration-pose")
        why = ("no still window" if not checked else f"no still window shows the {pose} pose"
               if not showing else "no still window before the walk: "
               f"{len(showing)} after its start (not a pose held for the calibration)")
        return _from_walk(rotations, source.frames, inputs, why)
    flags.append(f"no still window (every sensor at rest for half a second) and no walk to "
                 f"calibrate from ({source.why}): the first sample is taken as the {pose} pose, "
                 "unchecked")
    cal = read_calibration_pose(rotations, inputs, notes, gravity=still_gravity(trial, rotations))
    return _described(cal, f"{pose} pose assumed at the first sample (no still window, no walk)")


def _all_oriented(window, rotations) -> bool:
    """Whether every segment's orientation is known somewhere in ``window`` (not NaN all
    through: a sensor's missing samples, a heading not observed after its filter started
    again); each is read at its first known sample there (:func:`read_calibration_pose`)."""
    return all(np.isfinite(R[window.rows]).all(axis=(1, 2)).any() for R in rotations.values())


def _fits(window, frames, rotations, pose) -> tuple[bool, str] | None:
    """Whether ``window`` shows ``pose`` by the walk's frames, and the evidence; None without a
    walk to check it by."""
    if frames is None:
        return None
    errors = pose_errors(window, frames, rotations, pose)
    if not errors:
        return None
    worst = max(errors, key=errors.get)
    line = f"{worst}'s long axis {errors[worst]:.0f} deg from the {pose} pose's"
    return errors[worst] <= POSE_TOL_DEG, line


def _from_window(trial, rotations, window, inputs, notes, checked) -> CalibrationPose:
    pose = inputs.options.calibration_pose
    gravity = still_gravity(trial, rotations, window.start)
    cal = read_calibration_pose(rotations, inputs, notes, at=window.start, gravity=gravity)
    fit = checked[window]
    check = ("not checked: no walk to check it by" if fit is None
             else f"checked by the walk: {fit[1]}")
    others = len(checked) - 1
    return _described(cal, f"{pose} pose, read in the still window {window.span} ({check})"
                      + (f"; {others} other still window(s)" if others else ""))


def _from_walk(rotations, frames: WalkingFrames, inputs, why: str) -> CalibrationPose:
    how = f"from the walk, no pose ({why}): {frames.describe()}"
    return walking_calibration_pose(frames.frames, rotations, inputs, how)


def _described(cal: CalibrationPose, how: str) -> CalibrationPose:
    return CalibrationPose(cal.right, cal.H, cal.pose, cal.placements, cal.at_pose, how,
                           cal.walked)
