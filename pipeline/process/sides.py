"""The legs' sensors named for the wrong side (a sensor map's left and right exchanged, or the set
strapped on the wrong legs): the hip centres tell.

Left-right mirrored names leave every sagittal angle as it was and mirror the others (each hip's
ab/adduction and rotation come out as the other leg's, sign flipped): nothing in the angles says
so. The hips do. Each thigh's hip centre in the pelvis sensor's frame, ``o_right`` and
``o_left``, follows from the two sensors' signals (Hu 2021 eq 1-3, the spherical calibration, as
the heading alignment fits it: :func:`~pipeline.process.joint_headings.centre_fit`), whatever
the names; the subject's right at the calibration pose (``right``, world) follows from the way
hips and knees flex (:func:`~pipeline.calibration.heading.subject_right`), whatever the names too.
With ``R_p`` the pelvis sensor's orientation at the pose and ``h`` the horizontal part,

    m = h(R_p d) . right / |h(R_p d)|,   d = o_right - o_left                            (1)

is near +1 when the names are right and near -1 when they are mirrored: the legs are read with
left and right exchanged when ``m < -MIN_MARGIN`` (the run says so, a flag: ``--strict`` stops
on it). Measured (``m``, ``|d|``): S02 +0.97-1.00 (vendor, VQF 9-D and 6-D, PI; 0.182 m, Vicon's
hip centres 0.184 m apart), the x-IMU3 walk +0.99 (9-D) and +0.80 (6-D), the simulated walk
+0.43-1.00 (seeds 0-7, 9-D and 6-D; below 0.7 on one seed of eight): :data:`MIN_MARGIN` lies
below the smallest. Only a walk decides (:data:`~pipeline.process.gait.MIN_STRIDES` strides a
leg) and only with the centres a plausible distance apart (within :data:`DISTANCE_FACTOR` of
the model's): lying with one hip flexing, the still hip's centre is free and eq (1) read -0.77
and +0.64 on one simulated trial (0.55 m apart), with a still thigh +0.25 (0.09 m); the
simulated walk's fits that ended 0.53 and 0.69 m apart kept the right sign but are not used
either; and only with the headings in one world (:func:`in_one_heading`). The fits take 0.04 s
(S02). Whether the shanks and feet go with the mirrored thighs, the stride's rhythm tells
(:mod:`pipeline.process.swap` eq 4, :func:`exchange_of`): the whole legs are read back, or the
thighs alone (their names exchanged by themselves: S02 -2.03, the simulated walk -3.05, against
+2.03 and +3.05 for the whole legs); where it tells neither the run is refused.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass, replace

import numpy as np

from pipeline.analysis.strides import Stride
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR, SENSOR_TO_SEGMENT
from pipeline.model.conventions import other_side
from pipeline.model.geometry import SubjectGeometry
from pipeline.process.gait import walked

__all__ = ["DISTANCE_FACTOR", "MIN_MARGIN", "Sides", "exchange_of", "in_one_heading", "mirrored",
           "side_evidence"]

#: Eq (1): the cosine below ``-MIN_MARGIN`` reads the legs as mirrored.
MIN_MARGIN = 0.3
#: The hip centres' fitted distance must lie within this factor of the model's (its pelvis).
DISTANCE_FACTOR = 2.0
_UP = np.array([0.0, 1.0, 0.0])


@dataclass(frozen=True)
class Sides:
    """Eq (1)'s cosine ``margin``, the hip centres' fitted distance ``separation_m`` and the
    model's ``model_m``."""

    margin: float
    separation_m: float
    model_m: float

    @property
    def plausible(self) -> bool:
        return self.model_m / DISTANCE_FACTOR <= self.separation_m <= self.model_m * DISTANCE_FACTOR

    @property
    def mirrored(self) -> bool:
        return self.plausible and self.margin < -MIN_MARGIN

    def evidence(self) -> str:
        return (f"its hip centre lies on the subject's left of femur_l_imu's "
                f"({self.separation_m:.2f} m apart, cosine {self.margin:+.2f} with the subject's "
                "right, from the way hips and knees flex)")


def exchange_of(sides: Sides, rec: Recording) -> tuple[tuple[str, ...], str]:
    """What a mirrored reading exchanges between the legs (``('femur', 'tibia', 'foot')``: the
    whole legs; ``('femur',)``: the thighs alone) and what the finding says, by the thighs'
    rhythm with their named legs (:mod:`pipeline.process.swap` eq 4: ``W``); an
    :class:`InputError` where ``W`` tells neither. Without it (a leg sensor's gyroscope missing):
    the whole legs, the sensor map's usual mistake."""
    from pipeline.process.check_context import CheckContext
    from pipeline.process.swap import MIN_THIGH_GAIN, crossing_evidence

    c = crossing_evidence(CheckContext(rec))
    w = None if c is None else c.with_legs
    if w is None or w >= MIN_THIGH_GAIN:
        said = "" if w is None else f"; each thigh swings with its named leg (swap eq 4: {w:+.2f})"
        return ("femur", "tibia", "foot"), (f"{sides.evidence()}{said}: the legs' sensors are "
                                            "named left for right (check the sensor map or the "
                                            "straps)")
    if w <= -MIN_THIGH_GAIN:
        return ("femur",), (f"{sides.evidence()}; each thigh swings with the other leg's shank "
                            f"and foot (swap eq 4: {w:+.2f}): the thighs' sensors are named left "
                            "for right, the shanks' and feet's rightly (check the sensor map or "
                            "the straps)")
    raise InputError(f"sensor femur_r_imu: {sides.evidence()}, and the stride's rhythm does not "
                     f"tell whether the shanks and feet go with the thighs (swap eq 4: {w:+.2f}, "
                     f"beyond +-{MIN_THIGH_GAIN:g} needed): name the legs' sensors for their "
                     "sides", file=rec.source, field="sensor_map")


def side_evidence(trial: Recording, rotations: dict[str, np.ndarray], cal, method: str,
                  geometry: SubjectGeometry, strides: list[Stride]) -> Sides | None:
    """Eq (1) on a recording in the model's world: ``rotations`` segment -> (N, 3, 3) sensor
    orientations (the pelvis's own; each thigh's inclination is what the fit's start uses),
    ``cal`` the calibration (:class:`~pipeline.process.pose.CalibrationPose`: the subject's
    right and the pelvis sensor's orientation at the pose, wherever in the recording it was
    read), ``geometry`` the model (its hip centres), ``strides`` the walk's; None without raw
    signals of the pelvis's and both thighs' sensors or fewer than
    :data:`~pipeline.process.gait.MIN_STRIDES` on a leg."""
    from pipeline.process.joint_headings import centre_fit

    segments = ("pelvis", "right_femur", "left_femur")
    if any(s not in rotations or not _complete(trial, SEGMENT_SENSOR[s]) for s in segments):
        return None
    if not walked(strides):
        return None
    o = {}
    for side in ("right", "left"):
        fit, _, _ = centre_fit(trial, rotations["pelvis"], rotations[f"{side}_femur"], "pelvis",
                               f"{side}_femur", method)
        o[side] = fit.position_1_m
    d = cal.at_pose["pelvis"] @ (o["right"] - o["left"])
    d_h = d - (d @ _UP) * _UP
    margin = float(d_h @ cal.right) / max(float(np.linalg.norm(d_h)), 1e-9)
    model_m = float(np.linalg.norm(geometry.right_hip - geometry.left_hip))
    return Sides(margin, float(np.linalg.norm(o["right"] - o["left"])), model_m)


def in_one_heading(shared: Collection[str], aligned: Collection[str]) -> bool:
    """Whether the pelvis's, thighs' and shanks' sensors see one world, so that eq (1)'s
    ``right`` (from their relative rotations) and ``R_p d`` mean one thing: down each leg every
    sensor shares its proximal neighbour's heading, both by their own (``shared``: the sensors
    whose headings are the common world) or turned into it at the joint between them
    (``aligned``: the heading alignment's ``'<side>_<joint>'``). A 6-D run whose headings stay
    apart (``--drift none``) read S02 as mirrored (cosine -1.00)."""
    for side in ("right", "left"):
        for prox, dist, joint in (("pelvis", "femur", "hip"), ("femur", "tibia", "knee")):
            pair = {SEGMENT_SENSOR[prox if prox == "pelvis" else f"{side}_{prox}"],
                    SEGMENT_SENSOR[f"{side}_{dist}"]}
            if f"{side}_{joint}" not in aligned and not pair <= set(shared):
                return False
    return True


def _complete(trial: Recording, name: str) -> bool:
    s = trial.sensors.get(name)
    return s is not None and s.complete


def mirrored(rec: Recording | None, parts: Collection[str] = ("femur", "tibia", "foot")
             ) -> Recording | None:
    """The recording with every leg sensor's name given to its namesake on the other leg
    (``femur_r_imu`` <-> ``femur_l_imu``, ...), the readers' notes on them too; ``parts``: the
    segments whose sensors are exchanged (default: all)."""
    if rec is None:
        return None

    def other(name: str) -> str:
        seg = SENSOR_TO_SEGMENT.get(name, "")
        side, _, part = seg.partition("_")
        if side not in ("right", "left") or part not in parts:
            return name
        return SEGMENT_SENSOR.get(f"{other_side(side)}_{part}", name)

    return replace(rec, sensors={other(n): s for n, s in rec.sensors.items()},
                   sensor_notes={other(n): v for n, v in rec.sensor_notes.items()})
