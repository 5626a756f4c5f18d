"""The gait step of :func:`pipeline.process.process_recording`: events and strides of each leg
from its foot sensor, else its shank sensor.

Per side, the foot sensor's raw signals (after the sensor check: a faulty foot sensor is already
excluded) give the events (:mod:`pipeline.analysis.gait_events`), its path
(:mod:`pipeline.analysis.foot_trajectory`) and the strides (:mod:`pipeline.analysis.strides`).
Without a usable foot sensor the shank's give the events only (stride time, stance share,
cadence; no length, speed, clearance or turn), with a note. A recording without raw signals, or
with no walking (no swing: supine, seated, standing), has no strides, and the notes say so.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pipeline.analysis.foot_trajectory import FootTrajectory, foot_trajectory
from pipeline.analysis.gait_events import GaitEvents, gait_events
from pipeline.analysis.strides import Stride, foot_strides
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT

__all__ = ["Gait", "gait_of"]


@dataclass(frozen=True)
class Gait:
    """``strides`` of both legs in time order; per side the ``events``, the foot's ``paths``
    and the ``sources`` (``'foot sensor <name>'`` or ``'shank sensor <name>'``)."""

    strides: list[Stride] = field(default_factory=list)
    events: dict[str, GaitEvents] = field(default_factory=dict)
    paths: dict[str, FootTrajectory] = field(default_factory=dict)
    sources: dict[str, str] = field(default_factory=dict)


def _sensor_of(rec: Recording, segment: str) -> str | None:
    """The sensor on ``segment`` with a gyroscope and an accelerometer, if any."""
    for name, s in rec.sensors.items():
        if SENSOR_TO_SEGMENT.get(name) == segment and s.gyr is not None and s.acc is not None:
            return name
    return None


def gait_of(rec: Recording, notes: list[str]) -> Gait:
    """Events and strides of each side (module docstring); what was used and why not goes to
    ``notes``."""
    strides, events, paths, sources = [], {}, {}, {}
    for side in ("right", "left"):
        foot, shank = _sensor_of(rec, f"{side}_foot"), _sensor_of(rec, f"{side}_tibia")
        name = foot or shank
        if name is None:
            continue
        s = rec.sensors[name]
        ev = gait_events(s.gyr, s.acc, rec.rate_hz, "foot" if foot else "shank")
        path = foot_trajectory(s.gyr, s.acc, rec.rate_hz, ev.rests) if foot else None
        found = foot_strides(side, rec.time, ev, path)
        events[side], sources[side] = ev, f"{'foot' if foot else 'shank'} sensor {name}"
        if path is not None:
            paths[side] = path
        elif found:
            notes.append(f"{side} strides from the shank sensor {name} (no usable foot sensor): "
                         "times only, no length, speed, clearance or turn")  # fmt: skip
        strides += found
    if not sources:
        notes.append("no strides: no foot or shank sensor with raw signals")
    elif not strides:
        notes.append("no strides: no walking found (no swing of a foot or shank)")
    return Gait(sorted(strides, key=lambda s: s.start_s), events, paths, sources)

