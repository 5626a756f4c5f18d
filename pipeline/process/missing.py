"""A sensor's missing samples: bridged for the estimators, blank in what the run writes.

A sensor misses samples where its radio dropped out (rows missing from its file, empty cells) or
where it started late or stopped early (:mod:`pipeline.io.clocks`). The readers fill a short gap
(:data:`~pipeline.io.gaps.DEFAULT_MAX_GAP_S`) and leave a longer one missing (NaN). The run never
bridges such a gap in its outputs:

* the estimators (the sensor checks, the attitude filter, the calibrations, the IK) get finite
  signals: each missing span filled (vectors linearly, orientations by slerp, the ends held;
  :func:`bridged`), so that one sensor's gap costs the rest of the recording nothing;
* whatever needs the sensor there is blank (NaN; :func:`blank_angles`, :func:`blank_landmarks`,
  :func:`without_strides_over`): the joints its segment takes part in, the landmarks of its
  segment and of those hanging from it, the strides of its side whose events it gives;
* the sensor check names the sensor and its spans (``dropout``, a flag), and the summary's sensor
  table lists them.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pipeline.io.gaps import Missing, fill_gaps, true_runs
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SEGMENT_SENSOR, SENSOR_TO_SEGMENT

__all__ = ["blank_after_restart", "blank_angles", "blank_landmarks", "blank_path",
           "blank_rotations", "bridged", "missing_of", "unknown_in", "without_strides_over"]

#: A segment -> the joints it takes part in.
_JOINTS = {"pelvis": ("hip",), "femur": ("hip", "knee"), "tibia": ("knee", "ankle"),
           "foot": ("ankle",)}
#: A segment -> the segments whose position hangs from it (the landmarks are the pelvis's).
_BELOW = {"pelvis": ("femur", "tibia", "foot"), "femur": ("femur", "tibia", "foot"),
          "tibia": ("tibia", "foot"), "foot": ("foot",)}


def _channels(s: SensorSignals) -> list[np.ndarray]:
    return [v for v in (s.quat, s.gyr, s.acc, s.mag) if v is not None]


def missing_of(rec: Recording) -> Missing:
    """Every sensor's missing spans (module docstring)."""
    spans = {}
    for name, s in rec.sensors.items():
        gone = np.zeros(rec.n_samples, dtype=bool)
        for v in _channels(s):
            gone |= ~np.all(np.isfinite(v), axis=1)
        if gone.any():
            spans[name] = tuple(true_runs(gone))
    return Missing(spans)


def bridged(rec: Recording, missing: Missing) -> Recording:
    """``rec`` with every missing span filled for the estimators (module docstring) and
    ``rec.missing`` saying where (the statistics and fits take :meth:`Recording.present` rows
    only); a sensor missing every sample is left as it is (its check excludes it)."""
    if not missing.spans:
        return rec
    sensors = dict(rec.sensors)
    for name in missing.spans:
        s = rec.sensors[name]
        if all(not np.isfinite(v).any() for v in _channels(s)):
            continue
        filled = {}
        for key in ("quat", "gyr", "acc", "mag"):
            v = getattr(s, key)
            if v is not None and not np.all(np.isfinite(v)) and np.isfinite(v).any():
                filled[key] = fill_gaps(rec.time, v, kind="quaternion" if key == "quat" else
                                        "vector", max_gap_s=np.inf)
        sensors[name] = s.replace(**filled)
    return dataclasses.replace(rec.with_sensors(sensors), missing=missing)


def _segment(sensor: str) -> tuple[str, str]:
    """``(side, segment kind)`` of a sensor (``('', 'pelvis')`` for the pelvis's)."""
    seg = SENSOR_TO_SEGMENT.get(sensor, "")
    side, _, kind = seg.partition("_")
    return (side, kind) if kind else ("", seg)


def blank_rotations(rotations: dict[str, np.ndarray], missing: Missing) -> dict[str, np.ndarray]:
    """Segment -> (N, 3, 3) orientations NaN where its sensor misses samples: what is fitted to
    them (headings, centres, the knee's axis) takes the sensor's own samples only, and the IK
    leaves that sensor's frame out there."""
    out = dict(rotations)
    for sensor in missing.spans:
        seg = SENSOR_TO_SEGMENT.get(sensor)
        if seg in out:
            R = np.array(out[seg], dtype=float)
            R[missing.mask(sensor, len(R))] = np.nan
            out[seg] = R
    return out


def unknown_in(rotations: dict[str, np.ndarray]) -> Missing:
    """Sensor -> the spans where its segment's orientation is NaN (its missing samples, or a
    heading the joints did not observe after its filter started again): what the run blanks."""
    spans = {}
    for seg, R in rotations.items():
        gone = ~np.all(np.isfinite(R), axis=(1, 2))
        if gone.any():
            spans[SEGMENT_SENSOR[seg]] = tuple(true_runs(gone))
    return Missing(spans)


def blank_after_restart(angles: dict[str, np.ndarray], keys, sensor: str, missing: Missing,
                        notes: list[str]) -> dict[str, np.ndarray]:
    """The angles ``keys`` NaN from ``sensor``'s first missing sample on: a sensor whose heading
    is its filter's own (6-D) has after a gap, where its filter started again, a heading no one
    observes (the pelvis's: the subject's heading its angles are taken in)."""
    spans = missing.spans.get(sensor)
    if not spans or not any(k in angles for k in keys):
        return angles
    out = dict(angles)
    for k in keys:
        if k in out:
            out[k] = np.array(out[k], dtype=float)
            out[k][spans[0][0]:] = np.nan
    notes.append(f"{sensor}'s heading is its filter's own (6-D) and its filter started again "
                 f"after its gap: {', '.join(k for k in keys if k in angles)} blank from there on")
    return out


def blank_angles(angles: dict[str, np.ndarray], missing: Missing) -> dict[str, np.ndarray]:
    """The joint angles NaN where a sensor their joint needs is missing; the pelvis's angles
    where the pelvis's sensor is."""
    out = {k: np.array(v, dtype=float) for k, v in angles.items()}
    for sensor in missing.spans:
        side, kind = _segment(sensor)
        for key, v in out.items():
            joint = key.split("_")[1] if key.startswith(("right_", "left_")) else "pelvis"
            same_side = not side or key.startswith(f"{side}_")
            if (joint in _JOINTS.get(kind, ()) and same_side) or (kind == joint == "pelvis"):
                v[missing.mask(sensor, len(v))] = np.nan
    return out


def blank_landmarks(landmarks: dict[str, np.ndarray], missing: Missing,
                    segment_of) -> dict[str, np.ndarray]:
    """The landmarks NaN where a sensor their segment's position needs is missing;
    ``segment_of``: landmark name -> its segment (``right_tibia``)."""
    out = {k: np.array(v, dtype=float) for k, v in landmarks.items()}
    for sensor in missing.spans:
        side, kind = _segment(sensor)
        for key, v in out.items():
            seg_side, _, seg_kind = segment_of(key).partition("_")
            if seg_kind in _BELOW.get(kind, ()) and (not side or seg_side == side):
                v[missing.mask(sensor, len(v))] = np.nan
    return out


def blank_path(path: np.ndarray, missing: Missing) -> np.ndarray:
    """The pelvis's path (n, 3) NaN wherever any sensor misses samples (it is carried by both
    feet through the whole chain)."""
    out = np.array(path, dtype=float)
    for sensor in missing.spans:
        out[missing.mask(sensor, len(out))] = np.nan
    return out


def without_strides_over(strides: list, sources: dict[str, str], time: np.ndarray,
                         missing: Missing, notes: list[str]) -> list:
    """The strides but those overlapping a missing span of the sensor that gave their side's
    events (``sources``: side -> ``'foot sensor <name>'``); what was left out goes to
    ``notes``."""
    kept, dropped = [], 0
    for s in strides:
        sensor = sources.get(s.side, "").rsplit(" ", 1)[-1]
        spans = missing.spans.get(sensor, ())
        if any(time[a] <= s.end_s and time[b - 1] >= s.start_s for a, b in spans):
            dropped += 1
        else:
            kept.append(s)
    if dropped:
        notes.append(f"{dropped} stride(s) over a sensor's missing samples left out")
    return kept
