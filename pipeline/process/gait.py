"""The gait step of :func:`pipeline.process.process_recording`: events and strides of each leg
from its foot sensor, else its shank sensor.

Per side, the foot sensor's raw signals (after the sensor check: a faulty foot sensor is already
excluded) give the events (:mod:`pipeline.analysis.gait_events`), its path
(:mod:`pipeline.analysis.foot_trajectory`) and the strides (:mod:`pipeline.analysis.strides`).
Without a usable foot sensor (or with one missing most of the recording's samples, where the
shank's has more) the shank's give the events only (stride time, stance share, cadence; no
length, speed, clearance or turn), with a note. A recording without raw signals, or
with no walking (no swing: supine, seated, standing), has no strides, and the notes say so.

**The pelvis's path** (:func:`with_pelvis_path`, after the IK): each foot sensor's path is
integrated again with the IK's orientation of its frame (the model's y-up world, so both feet
share one world), anchored where the model puts the foot at the foot's first rest; each foot
then carries the pelvis, ``pelvis = foot's world position - foot's position relative to the
pelvis`` (the IK's chain), and the two estimates' velocities are blended by each foot's stance
weight (1 from IC to FC and at rest, 0 in swing, smoothed over :data:`BLEND_S`) and integrated:
the stance foot where it rests carries the body, and the hand-over from one foot to the other
moves it by no more than the feet move (the two estimates differ by the model's error). The
floor (``y = 0``) is the lowest foot landmark at the first rest; before the feet's first rest
and after their last the body stands where it was. Both feet, each with strides and in the
IK's model (a leg whose joints are not observed has none), are needed; without them the
path is not written and a note says why.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from pipeline.analysis.foot_trajectory import FootTrajectory, foot_trajectory
from pipeline.analysis.gait_events import GaitEvents, gait_events
from pipeline.analysis.strides import MAX_STRIDE_S, Stride, foot_strides
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR

__all__ = ["BLEND_S", "MIN_STRIDES", "Gait", "gait_of", "too_short", "walked",
           "with_pelvis_path"]

#: Strides each leg walks for a check that needs a walk (the legs' sides and their sensors'
#: pairings, :mod:`pipeline.process.sides` and :mod:`pipeline.process.swap`).
MIN_STRIDES = 3
#: The stance weights' smoothing window (s): the blend from one foot to the other.
BLEND_S = 0.1


@dataclass(frozen=True)
class Gait:
    """``strides`` of both legs in time order; per side the ``events``, the foot's ``paths``
    and the ``sources`` (``'foot sensor <name>'`` or ``'shank sensor <name>'``)."""

    strides: list[Stride] = field(default_factory=list)
    events: dict[str, GaitEvents] = field(default_factory=dict)
    paths: dict[str, FootTrajectory] = field(default_factory=dict)
    sources: dict[str, str] = field(default_factory=dict)
    pelvis_path: np.ndarray | None = None


def _sensor_of(rec: Recording, segment: str) -> str | None:
    """The sensor on ``segment`` if it has a gyroscope and an accelerometer."""
    name = SEGMENT_SENSOR[segment]
    s = rec.sensors.get(name)
    return name if s is not None and s.gyr is not None and s.acc is not None else None


def _covers_less(rec: Recording, foot: str, shank: str) -> bool:
    """Whether the foot sensor misses most of the recording and the shank's has more of it (a
    battery that died: the strides come from where the samples are)."""
    have = rec.present(foot).mean()
    return have < 0.5 and rec.present(shank).mean() > have


def gait_of(rec: Recording, notes: list[str]) -> Gait:
    """Events and strides of each side (module docstring); what was used and why not goes to
    ``notes``."""
    strides, events, paths, sources = [], {}, {}, {}
    for side in ("right", "left"):
        foot, shank = _sensor_of(rec, f"{side}_foot"), _sensor_of(rec, f"{side}_tibia")
        why = "no usable foot sensor"
        if foot and shank and _covers_less(rec, foot, shank):
            why = (f"the foot sensor {foot} has {100 * rec.present(foot).mean():.0f}% of the "
                   f"recording's samples, the shank's {100 * rec.present(shank).mean():.0f}%")
            foot = None
        name = foot or shank
        if name is None:
            continue
        s = rec.sensors[name]
        ev = gait_events(s.gyr, s.acc, rec.rate_hz, "foot" if foot else "shank")
        path = None if not foot else (ev.trajectory if ev.trajectory is not None
                                      else foot_trajectory(s.gyr, s.acc, rec.rate_hz, ev.rests))
        found = foot_strides(side, rec.time, ev, path)
        events[side], sources[side] = ev, f"{'foot' if foot else 'shank'} sensor {name}"
        if path is not None:
            paths[side] = path
        elif found:
            notes.append(f"{side} strides from the shank sensor {name} ({why}): times only, no "
                         "length, speed, clearance or turn")
        strides += found
    if not sources:
        notes.append("no strides: no foot or shank sensor with raw signals")
    elif not strides:
        swings = {side: len(ev.swing) for side, ev in events.items() if len(ev.swing)}
        notes.append("no strides: " + ("no walking found (no swing of a foot or shank)" if not
                                       swings else "swings found (" + ", ".join(
                                           f"{side} {n}" for side, n in swings.items())
                                       + f") but no two contacts of one foot within "
                                       f"{MAX_STRIDE_S:g} s of each other"))
    return Gait(sorted(strides, key=lambda s: s.start_s), events, paths, sources)



def _stance_weight(ev: GaitEvents, n: int, rate_hz: float) -> np.ndarray:
    """1 at rest and from each IC to the next FC, 0 in swing; smoothed over :data:`BLEND_S`."""
    w = np.zeros(n)
    for a, b in ev.rests:
        w[a:b] = 1.0
    for ic in ev.ic:
        later = ev.fc[ev.fc > ic]
        stop = int(np.ceil(later[0])) if len(later) else n
        w[int(np.floor(ic)):stop] = 1.0
    before = ev.fc[0] if len(ev.fc) else n  # standing until the first toe-off
    w[: int(np.floor(before))] = 1.0
    k = max(1, int(round(BLEND_S * rate_hz)))
    return np.convolve(np.pad(w, k // 2, mode="edge"), np.ones(k) / k, mode="valid")[:n]


def with_pelvis_path(gait: Gait, rec: Recording, skeleton, Q: np.ndarray,
                     notes: list[str]) -> Gait:
    """``gait`` with its ``pelvis_path`` (module docstring); ``rec``: the recording in the
    model's world, ``Q`` the IK's configurations of ``skeleton`` (pelvis at the origin)."""
    from pipeline.analysis.landmarks import frame_trajectories
    from pipeline.model.conventions import LANDMARK_SEGMENT

    if set(gait.paths) != {"right", "left"}:
        if gait.strides:
            notes.append("the pelvis's path needs a foot sensor on each foot: not written")
        return gait
    if {s.side for s in gait.strides if np.isfinite(s.stride_length_m)} != {"right", "left"}:
        if gait.strides:
            notes.append("the pelvis's path needs strides of both feet: not written")
        return gait
    n, sides = len(rec.time), ("right", "left")
    feet = [f"{side}_foot_imu" for side in sides]
    unsolved = [side for side, f in zip(sides, feet, strict=True) if not skeleton.has_frame(f)]
    if unsolved:  # e.g. a foot sensor without its shank's and no pelvis sensor
        notes.append(f"the pelvis's path needs both feet's orientations from the IK, and the "
                     f"model has no {' or '.join(unsolved)} foot (its leg's joints are not "
                     "observed): not written")
        return gait
    soles = [f for f in skeleton.landmark_frames
             if LANDMARK_SEGMENT.get(f.split("_", 1)[1]) == "foot"]
    traj = frame_trajectories(skeleton, Q, feet + soles)
    first = {side: int(gait.events[side].rests[0][0]) for side in sides}
    order = sorted(sides, key=first.get)
    estimate, weight = {}, {}
    for side in order:
        s = rec.sensors[gait.sources[side].split()[-1]]
        R, p = traj[f"{side}_foot_imu"]
        path = foot_trajectory(s.gyr, s.acc, rec.rate_hz, gait.events[side].rests, rotation=R,
                               up=1).position
        k = first[side]
        pelvis_then = np.zeros(3) if not estimate else estimate[order[0]][k]
        estimate[side] = pelvis_then + p[k] + path - path[k] - p
        weight[side] = _stance_weight(gait.events[side], n, rec.rate_hz)
    w = np.stack([weight[s] for s in sides])[:, :, None]
    est = np.stack([estimate[s] for s in sides])
    velocity = np.gradient(est, axis=1)  # per sample: each estimate's motion, without the jump
    w = np.where(np.isfinite(velocity), w + 1e-6, 0.0)  # between two feet's estimates
    step = np.sum(np.nan_to_num(velocity) * w, axis=0) / np.maximum(np.sum(w, axis=0), 1e-12)
    k = min(first.values())
    pelvis = np.cumsum(step, axis=0)
    pelvis += estimate[order[0]][k] - pelvis[k]
    pelvis = _held(pelvis, np.any(w > 0, axis=(0, 2)))
    if soles:
        pelvis[:, 1] -= min(traj[f][1][k, 1] for f in soles) + pelvis[k, 1]
    notes.append("the pelvis's path: the stance foot carries the body (both foot sensors' paths "
                 "with the IK's orientations; pelvis_tx/ty/tz in the .mot)")
    return replace(gait, pelvis_path=pelvis)


def _held(path: np.ndarray, known: np.ndarray) -> np.ndarray:
    """``path`` where ``known``; before the first known sample the first value, after the last
    the last (the feet rest there: the body stands)."""
    idx = np.flatnonzero(known)
    if len(idx) == 0:
        return np.full_like(path, np.nan)
    nearest = np.clip(np.searchsorted(idx, np.arange(len(path)), side="right") - 1, 0, None)
    out = path[idx[nearest]]
    out[: idx[0]] = path[idx[0]]
    return out


def walked(strides: list[Stride]) -> bool:
    """Whether each leg walked :data:`MIN_STRIDES` of ``strides``."""
    return min(sum(s.side == side for s in strides) for side in ("right", "left")) >= MIN_STRIDES


def too_short(strides: list[Stride]) -> str | None:
    """What the checks that need a walk (the legs' sides, the shanks' and feet's pairings across
    the legs) could not check on a walk of fewer than :data:`MIN_STRIDES` strides a leg; None
    for a walk long enough, or none at all."""
    if not strides or walked(strides):
        return None
    counts = ", ".join(f"{side} {sum(s.side == side for s in strides)}"
                       for side in ("right", "left"))
    return (f"a short walk ({counts} strides, {MIN_STRIDES} a leg needed): whether the legs' "
            "sensors are named for their sides, and the shanks' and feet's for their legs, was "
            "not checked")
