"""Which sensors a recording has, and so which joints it observes.

A joint is observed when both its segments carry a sensor: the hip (pelvis + femur), the knee
(femur + tibia), the ankle (tibia + foot). Only observed joints are solved for and written; a leg is
in the model when one of its joints is observed. A segment's landmarks are written when it and
every segment between it and the hip carry a sensor (the femur for the femoral landmarks; femur
and tibia for the malleoli; femur, tibia and foot for the foot's), relative to the pelvis when the
pelvis carries one and to the leg's own hip centre otherwise.

Sensor names are OpenSense's (``pelvis_imu``, ``femur_r_imu``, ``tibia_r_imu``, ``calcn_r_imu``,
...; ``foot_r_imu`` is accepted for ``calcn_r_imu``). :func:`apply_sensor_map` renames a
recording's own sensor names (a lab's labels, an Xsens id) to those.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

from pipeline.errors import InputError
from pipeline.io.opensim import SENSOR_TO_SEGMENT
from pipeline.io.recording import Recording

__all__ = [
    "JOINT_SEGMENTS",
    "SENSOR_ALIASES",
    "SensorSet",
    "apply_sensor_map",
    "known_segments",
    "sensor_set",
]

#: Joint -> (proximal, distal) segment of one leg (the pelvis has no side).
JOINT_SEGMENTS = {"hip": ("pelvis", "femur"), "knee": ("femur", "tibia"),
                  "ankle": ("tibia", "foot")}  # fmt: skip
SENSOR_ALIASES = {"foot_r_imu": "calcn_r_imu", "foot_l_imu": "calcn_l_imu"}
_LANDMARK_CHAIN = {"femur": ("femur",), "tibia": ("femur", "tibia"),
                   "foot": ("femur", "tibia", "foot")}  # fmt: skip


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


def apply_sensor_map(trial: Recording, sensor_map: Mapping[str, str]) -> Recording:
    """The recording with its sensors renamed to ours.

    ``sensor_map``: our name -> the recording's sensor name, or a part of it that only one sensor
    name contains (a device id such as ``00B421AF``). Aliases (``foot_r_imu``) become
    OpenSense's names. A name that matches no sensor, or several, is refused naming the key.
    """
    sensors = dict(trial.sensors)
    renamed: dict[str, object] = {}
    taken: set[str] = set()
    for ours, theirs in sensor_map.items():
        if theirs in sensors:
            match = theirs
        else:
            hits = [s for s in sensors if theirs in s]
            if len(hits) != 1:
                what = "no sensor" if not hits else f"several sensors ({hits})"
                raise InputError(
                    f"{what} of the recording matches {theirs!r}; its sensors: {sorted(sensors)}",
                    file=trial.source, field=f"sensors.{ours}",
                )  # fmt: skip
            match = hits[0]
        if match in taken:
            raise InputError(f"sensor {match!r} is mapped twice", file=trial.source,
                             field=f"sensors.{ours}")  # fmt: skip
        taken.add(match)
        renamed[ours] = sensors[match]
    out: dict[str, object] = {}
    items = [(n, s) for n, s in sensors.items() if n not in taken] + list(renamed.items())
    for name, signals in items:
        key = SENSOR_ALIASES.get(name, name)
        if key in out:
            raise InputError(f"two sensors for {key} (is {name!r} the same as {key!r}?)",
                             file=trial.source, field=f"sensors.{key}")  # fmt: skip
        out[key] = signals
    if set(out) == set(sensors) and not renamed:
        return trial
    return trial.with_sensors(out)


def known_segments(trial: Recording) -> dict[str, str]:
    """Sensor name -> segment for the recording's sensors that have one in the model."""
    return {s: SENSOR_TO_SEGMENT[s] for s in trial.sensor_names
            if SENSOR_TO_SEGMENT.get(s, "torso") != "torso"}  # fmt: skip
