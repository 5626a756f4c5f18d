"""Steps 1-2 of a pass of :func:`pipeline.process.run.process_recording`: the recording checked
and in the model's world.

:func:`prepared` runs the sensor checks once (:mod:`pipeline.process.sensor_checks`; a sensor's
missing samples bridged for them and the estimators, :mod:`pipeline.process.missing`), keeps the
strides, still windows and findings they computed, estimates orientations from raw signals where
asked or needed (:mod:`pipeline.process.signals`), turns every orientation into the model's y-up
world and maps the sensors to the segments whose joints they observe (:class:`Prepared`).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from pipeline.calibration.heading import check_vertical
from pipeline.errors import InputError
from pipeline.io.opensim import map_sensors, rotate_world, sensor_to_opensim_matrix
from pipeline.io.recording import Recording
from pipeline.process.check_context import CheckContext
from pipeline.process.findings import Action, Finding
from pipeline.process.gait import Gait, too_short
from pipeline.process.missing import blank_rotations, without_strides_over
from pipeline.process.options import IKOptions
from pipeline.process.pose import static_orientations
from pipeline.process.sensor_checks import run_checks
from pipeline.process.sensors import SensorSet, known_segments, sensor_set
from pipeline.process.signals import Z_UP_TO_Y_UP, orientations_from_signals, world_to_model
from pipeline.process.still import StillWindow
from pipeline.rotations import matrix_from_quat

__all__ = ["Prepared", "model_world", "prepared"]


@dataclass
class Prepared:
    """Steps 1-2 of a pass: the checked recording in the model's world and what it holds."""

    trial: Recording
    oriented: object
    rotations: dict[str, np.ndarray]
    sensors: SensorSet
    findings: list[Finding]
    gait: Gait
    windows: list[StillWindow]
    static_pose: dict[str, np.ndarray] | None
    notes: list[str]
    flags: list[str] = field(default_factory=list)


def prepared(trial: Recording, static, opts: IKOptions) -> Prepared:
    """Step 1-2: the sensor check, the strides and the still windows (computed once), the
    orientations in the model's y-up world, and the static trial's mean pose."""
    notes = list(trial.notes)
    ctx, findings = run_checks(CheckContext.of_recording(trial))
    missing = ctx.missing.of(ctx.rec.sensor_names)  # an excluded sensor's gaps are no one's
    trial, gait, windows = ctx.rec, ctx.gait, ctx.windows
    notes += ctx.gait_notes
    gait = replace(gait, strides=without_strides_over(gait.strides, gait.sources, trial.time,
                                                      missing, notes))
    notes += [short] if (short := too_short(gait.strides)) else []
    rejected = frozenset(f.sensor for f in findings if f.action == Action.ORIENTATION_FROM_SIGNALS)
    trial, static, oriented, world = _in_model_world(trial, static, opts, notes, rejected)
    rotations, sensors = _segment_rotations(trial, notes)
    rotations = blank_rotations(rotations, missing)
    if sensors.pelvis and not oriented.filtered:  # the filter's world is vertical by construction
        check_vertical(rotations["pelvis"], notes=notes, applied=world)
    elif not sensors.pelvis:
        notes.append("no pelvis sensor: hip and pelvis angles are not observed; landmarks are "
                     "relative to each leg's hip centre")
    if opts.heading != "anatomical" and not sensors.pelvis:
        raise InputError(f"heading {opts.heading!r} needs a pelvis sensor (pelvis_imu)",
                         file=trial.source, field="heading")
    static_pose = None
    if static is not None:
        static_pose = static_orientations(static, list(rotations), notes,
                                          opts.calibration_pose)
    return Prepared(trial, oriented, rotations, sensors, findings, gait, windows, static_pose,
                     notes)


def _in_model_world(trial, static, opts: IKOptions, notes: list[str], rejected=frozenset()):
    """Step 2: ``(trial, static, oriented, world)``: orientations estimated from raw signals
    where asked or needed (:class:`~pipeline.process.signals.Orientations`; ``rejected``: the
    sensors whose own a check left out), and every orientation in the model's y-up world."""
    oriented = orientations_from_signals(trial, opts.filter, notes, rejected=rejected)
    trial, filtered = oriented.recording, oriented.filtered
    if static is not None:
        notes += [f"static trial: {n}" for n in static.notes]
        static = orientations_from_signals(static, opts.filter if filtered else None,
                                           []).recording
    world, note = model_world(trial, opts, bool(filtered))
    notes += [note] if note else []
    if not np.allclose(world, np.eye(3)):
        trial = rotate_world(trial, world)
        static = rotate_world(static, world) if static is not None else None
    return trial, static, oriented, world


def model_world(trial: Recording, opts: IKOptions, filtered: bool) -> tuple[np.ndarray, str | None]:
    """The fixed rotation that puts the orientations of ``trial`` (``filtered``: from the
    attitude filter, z up) in the model's y-up world, and what decided it (a note, or None):
    ``--sensor-to-model``, else the filter's z up, else the vendor's world or the measured up
    axis (:func:`~pipeline.process.signals.world_to_model`)."""
    to_model, note = opts.sensor_to_model, None
    if filtered:
        if to_model is not None:
            raise InputError("--sensor-to-model applies to a recording's own orientations; the "
                             "filter's world is z up and is turned to y up already",
                             file=trial.source, field="sensor_to_model")
        to_model = Z_UP_TO_Y_UP
    elif to_model is None:
        to_model, note = world_to_model(trial)
    return (np.eye(3) if to_model is None else sensor_to_opensim_matrix(to_model)), note


def _segment_rotations(trial: Recording, notes: list[str]):
    """Step 1: segment -> (N, 3, 3) sensor orientations of the segments whose sensors observe a
    joint, and the :class:`SensorSet`; the others noted."""
    rotations = {seg: matrix_from_quat(q) for seg, q in map_sensors(trial).items()
                 if seg != "torso"}
    sensors = sensor_set(set(rotations), source=trial.source)
    ignored = sorted(set(trial.sensor_names) - set(known_segments(trial)))
    if ignored:
        notes.append(f"sensors without a segment in this lower-limb model, ignored: {ignored}")
    unused = sorted(s for s in rotations if _side(s) not in sensors.legs and s != "pelvis")
    if unused:
        notes.append(f"segments whose sensor observes no joint, ignored: {unused}")
    rotations = {s: R for s, R in rotations.items() if s == "pelvis" or _side(s) in sensors.legs}
    return rotations, sensors


def _side(segment: str) -> str:
    return segment.split("_", 1)[0]
