"""The calibration without a pose: each sensor's placement on its segment from the walk itself.

A standing calibration reads each sensor's placement at a moment whose segment orientations the
model knows (:mod:`pipeline.process.pose`). A recording without such a moment (it starts
mid-walk, or its protocol has no static pose) still shows each segment's anatomical axes in
its sensor's frame while the subject walks, which is what Hu et al. 2021's joint-constraint
calibration set out to use (its eq 30-37 build the thigh's and shank's frames from the knee axis
and the joint centres; Seel et al. 2012 and 2014 the same axis and centres from gait):

* **medio-lateral axis** ``z`` of the thighs, shanks and feet: the segment's flexion axis, the
  principal axis of its horizontal angular velocity in walking, signed to the subject's right
  (:func:`~pipeline.calibration.flexion_axis.leg_flexion_axes`);
* **long axis** ``y`` of the thigh and shank, as ISB and the model define them (femur: knee centre
  to hip centre; tibia: ankle centre to knee centre, Wu et al. 2002; Hu eq 34), from the joint
  centres located by the sensors' accelerations (Hu eq 2, vector form:
  :func:`~pipeline.calibration.joint_centres.joint_centre`); the part of ``y`` along ``z`` is
  left out (a hinge-like fit does not locate its centre along the axis);
* **the foot**: flat on the floor while it rests (in stance, the zero-velocity phases, Skog et
  al. 2010; and wherever the subject stands), so its ``y`` (the model's foot frame has its sole
  in the x-z plane) is the vertical its accelerometer reads then, ``z`` its flexion axis;
* **the pelvis**: upright on average over the strides (its tilt and list swing a few degrees
  about their standing values, Perry & Burnfield 2010 ch. 8): ``y`` the mean specific force over
  the walk's strides (the linear accelerations average out over whole strides), ``z`` the thighs'
  flexion axes, both carried into its frame and averaged (in walking both swing about the
  body's medio-lateral line).

The angles' zeros then follow from these anatomical definitions, not from a posture: the knee at
zero where the femur's and the tibia's centre lines align, the ankle where the sole is flat under
a tibia whose centre line is vertical (the model's neutral). Where a centre is not located (no
pelvis or foot sensor) the long axis is the segment's mean vertical over the strides instead, an
assumption the notes state; centres the signals place implausibly (their distance more than
:data:`~pipeline.process.posture.LENGTH_TOL` from the model's segment length: signals without
the joints' accelerations)
refuse the calibration.

Measured on S02 (vendor orientations and VQF 6-D; the recording cut to start at samples 0, 1120,
1300 and 1500; ``scripts/bench_real_gait.py``): against Vicon's segments the thighs' sagittal
inclination is off by +1.7 / -2.4 deg, the shanks' +1.3 / +4.3, the feet's -2.7 / -0.9 (right /
left), and the pelvis's +5.5 (Vicon's pelvis is tilted so against ours in every calibration: the
standing one leaves +6.7).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.calibration.flexion_axis import leg_flexion_axes
from pipeline.calibration.joint_centres import JointCentre, joint_centre
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR
from pipeline.process.posture import LENGTH_TOL
from pipeline.rotations import normalize, rotation_aligning_with_twist

__all__ = ["WalkingFrames", "walking_frames"]

_X, _Y, _Z = np.eye(3)


@dataclass(frozen=True)
class WalkingFrames:
    """``frames``: segment -> (3, 3) rotation from its sensor's frame to the segment's (its rows
    the segment's axes in the sensor's frame); ``how``: segment -> how its long axis was found;
    ``assumed``: the segments whose long axis is the mean vertical, not a centre line."""

    frames: dict[str, np.ndarray]
    how: dict[str, str]
    assumed: tuple[str, ...] = ()

    def describe(self) -> str:
        """One line for the notes and the summary."""
        parts = [f"{seg}: {how}" for seg, how in self.how.items()]
        return "; ".join(parts)


def _up(R: np.ndarray) -> np.ndarray:
    """The world's vertical (y) in the sensor's frame per sample."""
    return np.einsum("nji,j->ni", R, _Y)


def _has_signals(trial: Recording, seg: str, rotations) -> bool:
    s = trial.sensors.get(SEGMENT_SENSOR[seg])
    return seg in rotations and s is not None and s.complete


def _centre(trial: Recording, rotations, prox: str, dist: str) -> JointCentre | None:
    if not (_has_signals(trial, prox, rotations) and _has_signals(trial, dist, rotations)):
        return None
    s1, s2 = (trial.sensors[SEGMENT_SENSOR[s]] for s in (prox, dist))
    return joint_centre(trial.time, s1.gyr, s1.acc, rotations[prox], s2.gyr, s2.acc,
                        rotations[dist])


def _walking_rows(trial: Recording, strides) -> np.ndarray:
    """The samples of the walk's straight strides (all strides where none is straight)."""
    chosen = [s for s in strides if s.straight] or list(strides)
    keep = np.zeros(trial.n_samples, dtype=bool)
    for s in chosen:
        keep |= (trial.time >= s.start_s) & (trial.time <= s.end_s)
    return np.flatnonzero(keep)


def _mean_vertical(trial: Recording, seg: str, rows: np.ndarray) -> np.ndarray:
    acc = trial.sensors[SEGMENT_SENSOR[seg]].acc[rows]
    return normalize(np.nanmean(acc, axis=0))


def _frame(z: np.ndarray, y: np.ndarray, *, upright: bool = False) -> np.ndarray:
    """The rotation taking the sensor-frame axes ``z`` and ``y`` onto the segment's z and y:
    ``z`` exactly and ``y`` as near as it can, or (``upright``: a vertical measured better than
    the flexion axis, the foot's and the pelvis's) ``y`` exactly and ``z`` as near as it can."""
    if upright:
        return rotation_aligning_with_twist(y, _Y, z, _Z)
    return rotation_aligning_with_twist(z, _Z, y, _Y)


def _leg_axes(trial: Recording, rotations, side: str) -> dict[str, np.ndarray]:
    segments = {}
    for seg in ("femur", "tibia", "foot"):
        name = f"{side}_{seg}"
        if _has_signals(trial, name, rotations):
            segments[seg] = (trial.sensors[SEGMENT_SENSOR[name]].gyr, _up(rotations[name]))
    return {f"{side}_{k}": a.axis for k, a in leg_flexion_axes(trial.rate_hz, segments).items()}


def _long_axis(line: np.ndarray | None, length: float, fallback: np.ndarray, what: str):
    """``(y, how, assumed)``: the centre ``line``, or the mean vertical ``fallback`` where a
    sensor it needs is absent (``line`` None); refused where the centres' distance is not within
    :data:`~pipeline.process.posture.LENGTH_TOL` of the model's ``length`` (the signals do not
    locate the joints)."""
    if line is None:
        return fallback, f"its mean vertical over the strides (no sensor locates {what}: " \
                         "assumed)", True
    d = float(np.linalg.norm(line))
    if abs(d / length - 1.0) > LENGTH_TOL:
        raise InputError(f"the walk does not locate the joints: {what} {d:.3f} m apart (the "
                         f"model's segment: {length:.3f} m)", field="calibration_pose")
    return normalize(line), f"{what} ({d:.3f} m apart)", False


def walking_frames(trial: Recording, rotations: dict[str, np.ndarray], gait, geometry,
                   legs: tuple[str, ...]) -> WalkingFrames:
    """The module docstring's frames of every segment in ``rotations`` (segment -> (N, 3, 3)
    sensor orientations, one y-up world: headings shared or aligned) from ``trial``'s raw
    signals and its ``gait`` (:class:`~pipeline.process.gait.Gait`: strides and the feet's
    rests). Refused without 2 s of strides or without the raw signals of a leg's thigh and
    shank."""
    rows = _walking_rows(trial, gait.strides)
    if rows.size < 2 * trial.rate_hz:
        raise InputError("no walk to calibrate from: fewer than 2 s of strides",
                         field="calibration_pose")
    frames, how, assumed, axes = {}, {}, [], {}
    for side in legs:
        femur, tibia, foot = (f"{side}_{s}" for s in ("femur", "tibia", "foot"))
        if not (_has_signals(trial, femur, rotations) and _has_signals(trial, tibia, rotations)):
            raise InputError(f"the {side} thigh's and shank's raw signals are needed to calibrate "
                             "from the walk", field="calibration_pose")
        axes.update(_leg_axes(trial, rotations, side))
        knee = _centre(trial, rotations, femur, tibia)
        hip = _centre(trial, rotations, "pelvis", femur) if "pelvis" in rotations else None
        ankle = _centre(trial, rotations, tibia, foot) if foot in rotations else None
        geo = geometry.for_side(side)
        lines = {femur: (None if hip is None else hip.o_2 - knee.o_1, geo.thigh_length,
                         "its knee and hip centres"),
                 tibia: (None if ankle is None else knee.o_2 - ankle.o_1, geo.shank_length,
                         "its ankle and knee centres")}
        for seg, (line, length, what) in lines.items():
            y, how[seg], guess = _long_axis(line, length, _mean_vertical(trial, seg, rows), what)
            frames[seg] = _frame(axes[seg], y)
            assumed += [seg] if guess else []
        if foot in axes:
            rests = _rest_rows(gait, side)
            frames[foot] = _frame(axes[foot], _mean_vertical(trial, foot, rests), upright=True)
            how[foot] = f"flat at its rests in stance ({rests.size} samples)"
    if "pelvis" in rotations and _has_signals(trial, "pelvis", rotations):
        frames["pelvis"], how["pelvis"] = _pelvis_frame(trial, rotations, axes, rows, legs)
    return WalkingFrames(frames, how, tuple(assumed))


def _rest_rows(gait, side: str) -> np.ndarray:
    """The samples in which the ``side`` foot rests (its zero-velocity phases in stance, and
    any standing: :mod:`pipeline.analysis.gait_events`): flat on the floor."""
    ev = gait.events.get(side)
    rows = [np.arange(a, b) for a, b in ([] if ev is None else ev.rests)]
    inside = np.concatenate(rows) if rows else np.zeros(0, dtype=int)
    if inside.size < 10:
        raise InputError(f"the {side} foot does not rest", field="calibration_pose")
    return inside


def _pelvis_frame(trial, rotations, axes, rows, legs) -> tuple[np.ndarray, str]:
    """The pelvis's frame (module docstring): its mean vertical over the strides and the thighs'
    flexion axes carried into its sensor's frame."""
    R_p = rotations["pelvis"][rows]
    lines = [np.einsum("nji,njk,k->i", R_p, rotations[f"{s}_femur"][rows], axes[f"{s}_femur"])
             for s in legs if f"{s}_femur" in axes]
    if not lines:
        raise InputError("the pelvis's medio-lateral axis needs a thigh's flexion axis",
                         field="calibration_pose")
    z = normalize(np.sum(lines, axis=0))
    return _frame(z, _mean_vertical(trial, "pelvis", rows), upright=True), (
        f"its mean vertical over the strides, the thighs' flexion axes ({len(lines)})")
