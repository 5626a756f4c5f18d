"""Which sensors a recording has, and so which joints it observes.

A joint is observed when both its segments carry a sensor: the hip (pelvis + femur), the knee
(femur + tibia), the ankle (tibia + foot). Only observed joints are solved for and written; a leg is
in the model when one of its joints is observed. A segment's landmarks are written when it and
every segment between it and the hip carry a sensor (the femur for the femoral landmarks; femur
and tibia for the malleoli; femur, tibia and foot for the foot's), relative to the pelvis when the
pelvis carries one and to the leg's own hip centre otherwise.

Sensor names are ours (OpenSense's, :mod:`pipeline.io.sensor_names`); the readers give them
(:func:`pipeline.io.formats.read_recording`).
"""

from __future__ import annotations

from dataclasses import dataclass

from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.model.conventions import JOINT_SEGMENTS

__all__ = ["SensorSet", "known_segments", "sensor_set"]
_LANDMARK_CHAIN = {"femur": ("femur",), "tibia": ("femur", "tibia"),
                   "foot": ("femur", "tibia", "foot")}


@dataclass(frozen=True)
class SensorSet:
    """The segments that carry a sensor and what follows from them (module docstring).

    ``segments``: segment names (``pelvis``, ``right_femur``, ...); ``joints``: observed joints
    as ``'<side>_<joint>'``; ``legs``: sides with an observed joint (right first);
    ``landmark_segments``: segments whose landmarks are written.
    """

    segments: frozenset[str]
    joints: tuple[str, ...]
    legs: tuple[str, ...]
    landmark_segments: tuple[str, ...]

    @property
    def pelvis(self) -> bool:
        return "pelvis" in self.segments

    def observes(self, side: str, joint: str) -> bool:
        return f"{side}_{joint}" in self.joints


def sensor_set(segments: set[str] | frozenset[str], source: object = None) -> SensorSet:
    """The :class:`SensorSet` of segments that carry a sensor; refused when no joint is observed,
    with a message that lists the pairs that would observe one."""
    segs = frozenset(segments)
    joints = []
    for side in ("right", "left"):
        for joint, (prox, dist) in JOINT_SEGMENTS.items():
            p = prox if prox == "pelvis" else f"{side}_{prox}"
            if p in segs and f"{side}_{dist}" in segs:
                joints.append(f"{side}_{joint}")
    legs = tuple(s for s in ("right", "left") if any(j.startswith(f"{s}_") for j in joints))
    if not legs:
        found = sorted(segs) or "none"
        raise InputError(
            f"these sensors observe no joint (segments with a sensor: {found}); a joint needs a "
            "sensor on both its segments: knee = femur_r_imu + tibia_r_imu (or the _l_ pair), "
            "hip = pelvis_imu + femur_r_imu, ankle = tibia_r_imu + calcn_r_imu",
            file=source,
        )
    landmarks = tuple(
        f"{side}_{seg}"
        for side in legs
        for seg, chain in _LANDMARK_CHAIN.items()
        if all(f"{side}_{c}" in segs for c in chain)
    )
    return SensorSet(segs, tuple(joints), legs, landmarks)


def known_segments(trial: Recording) -> dict[str, str]:
    """Sensor name -> segment for the recording's sensors that have one in the model."""
    return {s: SENSOR_TO_SEGMENT[s] for s in trial.sensor_names
            if SENSOR_TO_SEGMENT.get(s, "torso") != "torso"}
