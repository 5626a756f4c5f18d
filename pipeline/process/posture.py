"""The standing posture at the calibration pose: how far the leg leans forward, from the joint
centres the sensors' own signals locate.

A standing calibration that assumes the model's neutral pose (every joint at zero) puts the
subject's standing posture into the sensor placements: a tibia that leans forward by ``t``
degrees while the foot is flat reads afterwards as an ankle ``t`` degrees less dorsiflexed than
it is (on the real walk ``gaittoolbox_s02`` the optical systems see the subject stand with 6-7 deg
of dorsiflexion, and the neutral calibration's ankle angles are 7-10 deg low over the whole walk).
The lean is observable: each joint's centre in the sensors' frames follows from their signals
(:func:`pipeline.calibration.joint_centres.joint_centre`, eq 2 there), so the tibia's long axis in
its sensor's frame is the line from the ankle's centre to the knee's (Hu 2021 eq 30-37 build the
segment frames from the same centres), and at the calibration pose its forward lean is

    lean = atan2(v . x_H, v . y),  v = R_s (o_knee - o_ankle)                      (1)

with ``x_H`` the subject's forward direction (the heading) and ``y`` the vertical. A joint that
turns like a hinge does not determine where its centre lies along its axis (Seel et al. 2012: the
centre may slide along the hinge axis): the fit's weakest direction
(:class:`~pipeline.calibration.joint_centres.JointCentre`) is then the axis, close to the tibia's
medio-lateral one, and the error along it reaches the forward direction by the axis's tilt. A
weakest direction within :data:`HINGE_LIKE_DEG` of the tibia's medio-lateral axis (the model's, in
the sensor's frame at the pose) is left out of ``o_knee - o_ankle`` (the knee's and the ankle's
averaged when both are). Measured once by hand over seeds 0-5, 9-D and 6-D: on the simulated walk
with a hinge knee, weakest directions 3-6 deg (knees) and 4-14 deg (ankles) from the medio-lateral
axis, the lean off by 1.5 deg (median; at most 4.9) with that line kept and 1.2 (at most 4.1)
without it, sagittal median RMSE 1.33 and 1.11 deg; on the walk whose knee is not a hinge
(:mod:`pipeline.simulate.knee`) and whose feet invert (its fits still hinge-like: knees 4-14 deg,
ankles 4-27, seeds 0-3), 2.1 (at most 3.8) both ways, sagittal 1.82 kept and 2.05 without: a
loss there (before the feet inverted: 2.3 and 2.7, sagittal 2.12 and 2.15); with a free ankle
(:mod:`pipeline.simulate.subtalar`) the fits stay hinge-like (knees 3-13 deg, ankles 4-28). Kept,
as neither walk is the real one and the real fits never take the rule. The
real walks' fits are not hinge-like (S02 knees 50-74 deg, ankles 47-53, the x-IMU3 walk 64-65 and
49-52), so their leans do not change; what makes them so is not in the simulator (the knee's
biplane-sized rotations raise an ideal knee fit's conditioning from 0.01-0.02 to 0.05, the thigh
sensor's wobble to 0.15-0.16; S02's are 0.30-0.34); a real walk without turns, on a treadmill say,
may be hinge-like: no such recording here.

The leg is taken straight, as in the neutral pose, leaning as its tibia does: the femur and the
tibia turn by ``-lean`` about their medio-lateral axis (``+z``: a forward lean of the top
turns ``y`` towards ``-x``), so the pose has hip flexion ``-lean``, knee flexion 0 and ankle
dorsiflexion ``lean``, the foot flat. Why the tibia's lean for the whole leg and not the femur's
own: the shank's sensor sits close to the bone and the knee and ankle move it in every stride, while
the thigh's sensor rides on soft tissue; on S02 the femur's own centres put the standing knee 3-5
deg into hyperextension, which the model's knee cannot take, and the hips 3-9 deg further from both
optical references than the straight leg does (``results/bench_real_gait.txt``). The pelvis's tilt
has no centre line the sensors can see and stays at the model's neutral.

A lean is used only when the centres are plausible: the distance between them within
:data:`LENGTH_TOL` of the model's shank length, the fit's residual below :data:`MAX_RESIDUAL`,
and the lean within :data:`MAX_LEAN_DEG`. A leg whose lean is not measured (no shank or foot
sensor, one excluded as faulty, or implausible centres) takes the other leg's: people stand on
both legs alike (measured leans, right / left: S02 +3.5 / +2.9 deg, the x-IMU3 walk +0.8 / -1.1
deg), so the borrowed lean is off by the legs' difference (0.6 and 1.9 deg) where upright is off
by the lean itself (0.8-3.5 deg). With neither leg measured both stand upright.

What the measured lean misses on the simulated walk is the sensors' soft-tissue shift: the
centres are fitted while walking puts the shank's sensor elsewhere on the bone than standing
does (:mod:`pipeline.simulate.artefacts`), and the lean is read at the standing pose. Measured
once by hand (seeds 0-5, 9-D, free ankle): with the true centres the lean is within 1.0 deg,
with centres fitted without soft tissue within 1.5, with it up to 4.3; nothing in the signals
tells the shift apart. Tried: both
measured legs at their mean (two noisy measures of nearly one lean; Vicon's S02 tibias differ by
1.1 deg): on the simulated walk the lean's error fell (median 1.8 to 1.5 deg with the two-axis
ankle, 2.1 to 0.9 with the free one, seeds 0-5, 9-D), but S02's sagittal medians rose by 0.1-0.3
deg on every input (vendor 4.42 to 4.51, 6-D 4.49 to 4.66): not kept. The notes say
which leg was measured, which borrowed and why.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.calibration.joint_centres import JointCentre, joint_centre
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR
from pipeline.model.conventions import other_side
from pipeline.rotations import normalize, rot_z

__all__ = ["HINGE_LIKE_DEG", "LENGTH_TOL", "MAX_LEAN_DEG", "MAX_RESIDUAL", "Posture",
           "lean_pose", "standing_posture"]

#: The centres' distance must be within this fraction of the model's shank length.
LENGTH_TOL = 0.25
#: Largest RMS residual of the centres' fit (m/s^2); real gait leaves 0.4-0.8.
MAX_RESIDUAL = 1.5
#: Largest plausible standing lean of a thigh or shank (deg).
MAX_LEAN_DEG = 20.0
#: A centre fit whose weakest direction lies within this angle (deg) of the tibia's
#: medio-lateral axis is hinge-like: that direction is left out of the tibia's line.
HINGE_LIKE_DEG = 30.0


@dataclass(frozen=True)
class Posture:
    """``lean``: segment (``right_femur``, ``right_tibia``, ...) -> forward lean (rad) at the
    calibration pose, for the legs whose lean was measured or borrowed from the other leg;
    ``length``: leg -> the distance (m)
    between the knee's and the ankle's centres; ``residual``: leg -> the worse of the two
    centres' fits (m/s^2)."""

    lean: dict[str, float]
    length: dict[str, float]
    residual: dict[str, float]

    def joint_angles(self, side: str) -> dict[str, float]:
        """The standing pose's hip flexion, knee flexion and ankle dorsiflexion (rad) of one
        leg (module docstring); a leg without a lean stands upright."""
        t = self.lean.get(f"{side}_tibia", 0.0)
        return {"hip_flexion": -t, "knee_flexion": 0.0, "ankle_flexion": t}


def _centre(trial: Recording, rotations, prox: str, dist: str) -> JointCentre:
    s1, s2 = (trial.sensors.get(SEGMENT_SENSOR[seg]) for seg in (prox, dist))
    if any(s is None or s.gyr is None or s.acc is None for s in (s1, s2)):
        raise InputError("raw gyroscope and accelerometer signals of both sensors are needed")
    return joint_centre(trial.time, s1.gyr, s1.acc, rotations[prox], s2.gyr, s2.acc,
                        rotations[dist])


def _hinge_axis(knee: JointCentre, ankle: JointCentre, ml: np.ndarray) -> np.ndarray | None:
    """The knee's and the ankle's weakest directions in the tibia's sensor frame that lie within
    :data:`HINGE_LIKE_DEG` of its medio-lateral axis ``ml``, signed along it and averaged; None
    when neither fit is hinge-like."""
    near = []
    for d in (knee.weakest[1], ankle.weakest[0]):
        d = d / np.linalg.norm(d)
        if np.degrees(np.arccos(min(1.0, abs(float(d @ ml))))) <= HINGE_LIKE_DEG:
            near.append(d if d @ ml > 0 else -d)
    return normalize(np.sum(near, axis=0)) if near else None


def _tibia_line(knee: JointCentre, ankle: JointCentre, ml: np.ndarray) -> tuple[np.ndarray, bool]:
    """``o_knee - o_ankle`` in the tibia's sensor frame, without its part along a hinge-like
    fit's undetermined axis (module docstring), and whether that part was left out."""
    v = knee.o_2 - ankle.o_1
    axis = _hinge_axis(knee, ankle, ml)
    return (v, False) if axis is None else (v - (v @ axis) * axis, True)


def standing_posture(
    trial: Recording,
    rotations: dict[str, np.ndarray],
    at_pose: dict[str, np.ndarray],
    pose: dict[str, np.ndarray],
    forward: np.ndarray,
    lengths: dict[str, float],
    legs: tuple[str, ...],
    notes: list[str],
) -> Posture:
    """Each leg's lean (module docstring), beyond the model's own in the pose (a hinge knee's
    tibia is turned by its axis's tilt). ``rotations``: segment -> (N, 3, 3) sensor orientations
    in one y-up world (headings aligned); ``at_pose``: segment -> the sensor's orientation at the
    calibration pose; ``pose``: segment -> the model's orientation in the pose; ``forward``: the
    subject's forward direction; ``lengths``: tibia segment -> the model's shank length (m)."""
    up = np.array([0.0, 1.0, 0.0])
    lean: dict[str, float] = {}
    length: dict[str, float] = {}
    residual: dict[str, float] = {}
    unmeasured: dict[str, str] = {}  # leg -> why its lean was not measured
    hinged: dict[str, bool] = {}  # leg -> a hinge-like fit's axis left out of its tibia's line
    for side in legs:
        femur, tibia, foot = (f"{side}_{s}" for s in ("femur", "tibia", "foot"))
        missing = [s for s in (femur, tibia, foot) if s not in rotations]
        if missing:  # the knee and the ankle must both be observed
            unmeasured[side] = f"no {' or '.join(missing)} sensor"
            continue
        try:
            knee = _centre(trial, rotations, femur, tibia)
            ankle = _centre(trial, rotations, tibia, foot)
        except InputError as e:
            unmeasured[side] = e.message
            continue
        ml = at_pose[tibia].T @ pose[tibia] @ np.array([0.0, 0.0, 1.0])
        v_s, hinged[side] = _tibia_line(knee, ankle, ml)
        L, res = float(np.linalg.norm(v_s)), max(knee.residual, ankle.residual)
        v = at_pose[tibia] @ v_s
        model = pose[tibia] @ np.array([0.0, 1.0, 0.0])  # the model's tibia line in the pose
        angle = float(np.arctan2(v @ forward, v @ up) - np.arctan2(model @ forward, model @ up))
        why = None
        if abs(L / lengths[tibia] - 1.0) > LENGTH_TOL:
            why = f"the knee and ankle centres are {L:.3f} m apart (shank {lengths[tibia]:.3f} m)"
        elif res > MAX_RESIDUAL:
            why = f"the centres' fit leaves {res:.2f} m/s^2 (> {MAX_RESIDUAL:g})"
        elif abs(np.degrees(angle)) > MAX_LEAN_DEG:
            why = f"the tibia would lean {np.degrees(angle):.0f} deg (> {MAX_LEAN_DEG:g})"
        if why:
            unmeasured[side] = why
            continue
        lean[femur] = lean[tibia] = angle
        length[side], residual[side] = L, res
    if lean:
        notes.append("standing posture from the knee and ankle centres: " + ", ".join(
            f"{side} leg leans {np.degrees(lean[f'{side}_tibia']):+.1f} deg"
            + (" (hinge-like centre fits: their place along the axis left out)"
               if hinged.get(side) else "")
            for side in legs if f"{side}_tibia" in lean))
    for side, why in unmeasured.items():
        notes.append(f"{side} leg: standing lean not measured ({why}); "
                     + _borrow_other_legs_lean(lean, side))
    return Posture(lean, length, residual)


def _borrow_other_legs_lean(lean: dict[str, float], side: str) -> str:
    """Give ``side``'s femur and tibia the other leg's measured lean (module docstring), in
    place; what was done, for the note."""
    other = other_side(side)
    if f"{other}_tibia" not in lean or f"{other}_femur" not in lean:
        return "taken upright"
    lean[f"{side}_femur"] = lean[f"{side}_tibia"] = lean[f"{other}_tibia"]
    return f"it takes the {other} leg's ({np.degrees(lean[f'{other}_tibia']):+.1f} deg)"


def lean_pose(pose: dict[str, np.ndarray], posture: Posture) -> dict[str, np.ndarray]:
    """The calibration pose's segment orientations with each measured lean applied (a turn of
    ``-lean`` about the segment's own medio-lateral axis, module docstring)."""
    out = dict(pose)
    for seg, angle in posture.lean.items():
        if seg in out:
            out[seg] = out[seg] @ rot_z(-angle)
    return out
