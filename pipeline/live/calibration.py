"""The live capture's calibration: the offline pipeline run on what has been captured so far.

A live capture is calibrated exactly as ``pipeline ik`` calibrates a recording
(:func:`pipeline.process.process_recording` on the samples captured so far: the sensor checks,
the calibration pose in the first still window, the subject's heading from the walk, the knee
correction, the joints' heading alignment), and each frame that follows is solved with that
calibration (:mod:`pipeline.live.tracker`). What the frame-by-frame path needs of it, a
:class:`LiveCalibration`:

* the calibrated model (its IMU frames carry the placements and corrections) and the last
  configuration, to start the next frame's IK from;
* per sensor, the turn about the vertical that puts its live orientation where the calibration
  put its own: the joints' alignment's turn at the end of the capture so far (``heading_turns``),
  and for a sensor filtered here, the heading between the online filter's orientation and the
  offline one's over the last :data:`MATCH_S` (both start with a heading of their own);
* whether it is final (:func:`is_final`): the walk checked the pose and gave the heading, with
  :data:`MIN_STRIDES` strides a leg; until then the capture calibrates again as it goes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pipeline.calibration.heading import heading_rotation
from pipeline.calibration.heading_offset import vertical_turn
from pipeline.errors import InputError
from pipeline.io.opensim import sensor_to_opensim_matrix
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR
from pipeline.model.measures import Measures
from pipeline.model.skeleton import Skeleton
from pipeline.process.options import IKOptions
from pipeline.process.sensors import SensorSet
from pipeline.process.signals import Z_UP_TO_Y_UP
from pipeline.rotations import matrix_from_quat

__all__ = ["MATCH_S", "MIN_STRIDES", "LiveCalibration", "calibrate_capture", "is_final"]

#: The online and the offline filter's headings are matched over this last stretch (s).
MATCH_S = 2.0
#: Strides a leg the walk needs for the calibration to be final (the sides check's).
MIN_STRIDES = 3


@dataclass
class LiveCalibration:
    """What the frame-by-frame path takes from a calibration (module docstring)."""

    skeleton: Skeleton
    sensors: SensorSet
    placements: dict[str, np.ndarray]
    H: np.ndarray
    q: np.ndarray
    turns: dict[str, float]
    nine_d: frozenset[str]
    how: str
    final: bool
    at_s: float
    notes: list[str] = field(default_factory=list)
    flags: list[str] = field(default_factory=list)


def calibrate_capture(rec: Recording, measures: Measures, opts: IKOptions,
                      live: dict[str, dict[str, np.ndarray]]) -> LiveCalibration:
    """The calibration of the capture so far ``rec`` (module docstring); ``live``: kind ->
    sensor -> (N, 3, 3) the live orientations of its frames (y-up world;
    :class:`~pipeline.live.orientation.LiveOrientations`), to match the offline ones."""
    from pipeline.process import process_recording
    from pipeline.process.signals import orientations_from_signals

    run = process_recording(rec, measures, opts)
    if not run.sensors.pelvis:
        raise InputError("pipeline live needs a pelvis sensor (pelvis_imu) for now; pipeline ik "
                         "processes a recording without one", field="sensor_map")
    rows = slice(max(0, rec.n_samples - int(MATCH_S * rec.rate_hz)), None)
    turns, offline = {}, None
    nine_d = frozenset(n for n, f in run.magnetometers.items() if f.trusted) if run.filtered \
        else frozenset()
    if run.filtered:
        offline = orientations_from_signals(rec, opts.filter, []).recording
    for seg in run.sensors.segments:
        name = SEGMENT_SENSOR[seg]
        turn = _last_known(run.heading_turns.get(seg))
        mine = live.get("9-D" if name in nine_d else "6-D", {}).get(name)
        if offline is not None and mine is not None:  # the filter's output the frames will use
            turn += _heading_between(offline, name, mine[rows], rows)
        turns[name] = turn
    H = heading_rotation(run.heading_right)
    return LiveCalibration(run.skeleton, run.sensors, run.placements, H, np.array(run.q[-1]),
                           turns, nine_d,
                           run.calibration, is_final(run), float(rec.time[-1]), list(run.notes),
                           list(run.flags))


def _last_known(turns: np.ndarray | None) -> float:
    """The alignment's last known turn (rad; 0 without one): held from the calibration on."""
    if turns is None or not np.isfinite(turns).any():
        return 0.0
    return float(turns[np.isfinite(turns)][-1])


def _heading_between(offline: Recording, name: str, live: np.ndarray, rows: slice) -> float:
    """The turn (rad) about the vertical from the live orientations to the offline filter's
    (both y up), its circular mean over ``rows``."""
    world = sensor_to_opensim_matrix(Z_UP_TO_Y_UP)  # the filter's z up, as live
    q = offline.sensors[name].quat[rows]
    ok = np.all(np.isfinite(q), axis=1) & np.all(np.isfinite(live), axis=(1, 2))
    if not ok.any():
        return 0.0
    psi = vertical_turn(world @ matrix_from_quat(q[ok]), live[ok])
    return float(np.arctan2(np.mean(np.sin(psi)), np.mean(np.cos(psi))))


def is_final(run) -> bool:
    """Whether a calibration is final: the pose checked by the walk (or read from it) and the
    heading from the walk's motion, with :data:`MIN_STRIDES` strides on each leg."""
    sides = [s.side for s in run.gait.strides]
    walked = all(sides.count(side) >= MIN_STRIDES for side in run.sensors.legs)
    unseen = any("heading is not observed" in n for n in run.notes)
    return walked and not unseen and "no walk to check it by" not in run.calibration
