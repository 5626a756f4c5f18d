"""From a recording of orientations to joint angles and landmark trajectories.

:func:`process_recording` is the pipeline that the Python API, ``pipeline ik``, the demo and the
Wang reproduction share; it writes nothing (outputs are the commands' job). On our scaled Pinocchio
model, the workflow of OpenSim's OpenSense, with the knee-AoR correction of Wang et al. 2023:

1. **Sensors** (:mod:`pipeline.process.sensors`): each sensor's raw signals checked first
   (:mod:`pipeline.process.sensor_checks`: a faulty sensor excluded and named); the joints the
   sensors observe (hip, knee, ankle of each leg; the recording carries our sensor names,
   :mod:`pipeline.io.formats`); any set observing one joint works.
2. **World.** Orientations ``R_s(t)`` are pre-multiplied by a fixed ``sensor_to_model`` rotation
   (OpenSense's ``sensor_to_opensim_rotations``, space-fixed XYZ angles; ``-pi/2 0 0`` for Xsens'
   z-up world) so that the world's y axis points up; a vendor's file whose world the reader knows
   (``header['world']``, Movella DOT, Xsens MT, x-IMU3: z up) is turned without being asked.
3. **Heading** (:mod:`pipeline.calibration.heading`): the subject's right at the calibration pose,
   from hip and knee flexion by default or from an axis of the pelvis sensor (OpenSense's way).
   Orientations from a 6-D filter (each sensor's heading its own, drifting) are first put in one
   heading by the joint constraints (``drift``, :mod:`pipeline.process.heading_alignment`: hip
   and ankle centres, the knee's hinge axis), and the calibration pose is read from them.
4. **Calibration pose** (:mod:`pipeline.calibration.placement`): the first sample (or the mean of a
   static trial) shows a standing, supine or seated pose; each sensor's rotation on its segment
   follows from it. With ``segment_orientations`` the recording holds segment frames and the
   placements are the identity.
5. **Correction** (:mod:`pipeline.process.knee_correction`): per leg with a knee, the segment
   orientations implied by step 4 are corrected towards the reference knee AoR (Wang eq 9-13 or
   the IPOPT version); the correction becomes part of the sensor placements. Where the knee's
   sensors have gyroscopes and accelerometers, the joint-constraint calibration
   (:mod:`pipeline.process.functional`, Hu 2021) runs first; with ``correction='functional'`` a
   knee whose calibration is trusted is corrected to its hinge axis instead of the one the
   orientations show (eq 1-8); the others fall back to eq 1-8 and the notes say why.
6. **IK.** Weighted orientation IK of all sensor frames (:func:`pipeline.ik.solve_ik`) with a
   spherical pelvis root. Without a pelvis sensor the pelvis is held in its calibration-pose
   orientation and the hips are free of limits (their angles are then not observed and not
   reported). ISB joint angles of the observed joints and the landmark trajectories follow (pelvis
   at the origin; each leg's hip centre at the origin when there is no pelvis sensor: translations
   are not observable from orientations).
"""

from __future__ import annotations

import time as _time
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from pipeline.analysis.landmarks import frame_trajectories
from pipeline.analysis.quality import quality_flags
from pipeline.calibration.conventions import DEFAULT_METHOD
from pipeline.calibration.correction import KneeCorrection
from pipeline.calibration.heading import heading_rotation
from pipeline.calibration.heading_offset import HeadingDrift, vertical_turn
from pipeline.calibration.magnetometer import FieldTrust
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.model.conventions import landmark_segment
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.process.findings import Action, Finding
from pipeline.process.functional import KneeCalibration, calibrate_knees, with_placements
from pipeline.process.gait import Gait, with_pelvis_path
from pipeline.process.heading_alignment import align_headings, sensors_to_align
from pipeline.process.knee_correction import correct_knees
from pipeline.process.missing import (
    blank_after_restart,
    blank_angles,
    blank_landmarks,
    blank_path,
    unknown_in,
)
from pipeline.process.options import IKOptions, InputOptions
from pipeline.process.pose import CalibrationPose, PoseInputs
from pipeline.process.pose_source import PoseSource, calibrate, source_of
from pipeline.process.posture import Posture, lean_pose, standing_posture
from pipeline.process.prepare import Prepared, prepared
from pipeline.process.sensors import SensorSet
from pipeline.process.sides import Sides, exchange_of, in_one_heading, mirrored, side_evidence
from pipeline.process.solve import PELVIS_ANGLES, joint_angles_of, landmarks_of, observed, solve
from pipeline.progress import step

__all__ = ["MOT_NAMES", "IKRun", "mot_columns", "process_recording"]

#: OpenSim coordinate names (Rajagopal 2015: knee flexion and ankle dorsiflexion positive,
#: subtalar inversion positive) for our ISB angles.
MOT_NAMES = {
    "hip_flexion": "hip_flexion",
    "hip_adduction": "hip_adduction",
    "hip_rotation": "hip_rotation",
    "knee_flexion": "knee_angle",
    "knee_adduction": "knee_adduction",
    "knee_rotation": "knee_rotation",
    "ankle_flexion": "ankle_angle",
    "ankle_inversion": "subtalar_angle",
}


@dataclass
class IKRun:
    """Everything :func:`process_recording` produced (SI units, radians).

    ``joint_angles``: ISB angles of the observed joints (``right_knee_flexion``, ...; ankle:
    ``_flexion`` = dorsiflexion, ``_inversion``) and, with a pelvis sensor, the pelvis' ZXY angles,
    each continuous (unwrapped: no jump of 2 pi between samples). ``landmarks``: name -> (N, 3) m
    of the observed segments (pelvis at the origin, or each leg's hip centre without a pelvis
    sensor). ``skeleton``: the calibrated subject model (spherical pelvis root; its IMU frames
    carry the placements and corrections applied), ``q`` its configurations. ``placements``: IMU
    frame -> 4x4 placement in its segment (the calibration applied); ``corrections``: side ->
    :class:`~pipeline.calibration.correction.KneeCorrection`; ``heading_drifts``:
    ``'<side>_<joint>'`` -> the :class:`~pipeline.calibration.heading_offset.HeadingDrift`
    applied (:mod:`pipeline.process.heading_alignment`); ``heading_turns``: segment -> (N,) rad,
    the whole turn about the vertical that alignment gave its sensor's orientations (its own
    drift and those above it; the segments it aligned); ``sensors``: what the sensors observe;
    ``heading_right``: the subject's right at the calibration pose (world); ``residual_rms``
    (N,) rad; ``flags``: implausible results (:mod:`pipeline.analysis.quality`); ``options``: the
    options used; ``filtered``: ``'6-D'``/``'9-D'`` when the orientations were estimated from raw
    signals here, else None; ``measures``: the subject; ``source``: the recording's file or
    folder; ``inputs``: what ``pipeline ik`` read (None from the Python API);
    ``sensor_findings``: the sensor check's :class:`~pipeline.process.sensor_checks.Finding` s
    (each also a flag); ``gait``: events and strides (:class:`~pipeline.process.gait.Gait`);
    ``calibration``: where and how the sensors were calibrated
    (:mod:`pipeline.process.pose_source`)."""

    time: np.ndarray
    q: np.ndarray
    joint_angles: dict[str, np.ndarray]
    landmarks: dict[str, np.ndarray]
    heading_right: np.ndarray
    heading_method: str
    residual_rms: np.ndarray
    skeleton: Skeleton
    seconds_ik: float
    notes: list[str] = field(default_factory=list)
    flags: list[str] = field(default_factory=list)
    options: IKOptions = field(default_factory=IKOptions)
    sensors: SensorSet | None = None
    placements: dict[str, np.ndarray] = field(default_factory=dict)
    corrections: dict[str, KneeCorrection] = field(default_factory=dict)
    knee_calibrations: list[KneeCalibration] = field(default_factory=list)
    heading_drifts: dict[str, HeadingDrift] = field(default_factory=dict)
    heading_turns: dict[str, np.ndarray] = field(default_factory=dict)
    filtered: str | None = None
    magnetometers: dict[str, FieldTrust] = field(default_factory=dict)
    posture: Posture | None = None
    measures: Measures | None = None
    source: Path | None = None
    inputs: InputOptions | None = None
    sensor_findings: list[Finding] = field(default_factory=list)
    gait: Gait = field(default_factory=Gait)
    calibration: str = ""

    def segment_orientations(self, names: list[str] | None = None) -> dict[str, np.ndarray]:
        """Segment name -> (N, 3, 3) world orientation of the solved model (default: the
        segments that carry a sensor)."""
        names = sorted(self.sensors.segments) if names is None else names
        return {n: R for n, (R, _) in frame_trajectories(self.skeleton, self.q, names).items()}


def process_recording(
    trial: Recording,
    measures: Measures,
    options: IKOptions | None = None,
    *,
    static: Recording | None = None,
    **changes: object,
) -> IKRun:
    """Steps 1-6 of the module docstring on a read recording (our sensor names); nothing is
    written.

    ``options`` (default :class:`IKOptions`) with any of its fields overridden by keyword, e.g.
    ``process_recording(rec, Measures("m", 1.8), correction="none", knee="hinge")``. ``static``:
    the static recording that gives the calibration pose. Where the legs' sensors turn out named
    left for right (:mod:`pipeline.process.sides`), a second pass runs on the names read back.
    """
    if not isinstance(trial, Recording):
        raise InputError(f"expected a read Recording (pipeline.read_recording), got "
                         f"{type(trial).__name__}", field="trial")
    opts = (options or IKOptions()).replace(**changes) if changes else (options or IKOptions())
    run = _one_pass(trial, measures, opts, static, check_sides=True)
    if not isinstance(run, Sides):
        return run
    parts, evidence = exchange_of(run, trial)  # the second pass: the legs' names read back
    again = _one_pass(mirrored(trial, parts), measures, opts, mirrored(static, parts),
                      check_sides=False)
    finding = Finding("femur_r_imu", "sides", Action.SWAPPED_BACK, evidence)
    again.sensor_findings.insert(0, finding)
    again.flags.insert(0, finding.line())
    return again


def _one_pass(trial, measures, opts: IKOptions, static, *, check_sides: bool) -> IKRun | Sides:
    """One pass of steps 1-6; the :class:`Sides` evidence instead of a run where ``check_sides``
    and the legs' sensors read as named left for right."""
    step("sensor checks, strides and orientations")
    s = prepared(trial, static, opts)
    geometry = _geometry(measures, opts)
    legs, method = s.sensors.legs, _method(opts)
    inputs = PoseInputs(Skeleton.build(geometry, knee=opts.knee, legs=legs), geometry, legs,
                        opts)
    knee_axes = {side: (geometry.for_side(side).knee_axis_femur,
                        geometry.for_side(side).knee_axis_tibia)
                 for side in legs if s.sensors.observes(side, "knee")}
    align = sensors_to_align(opts.drift, list(s.rotations), s.oriented.shared)
    knee_cal = []
    step("functional calibration and headings")
    if opts.calibration_method != "none":
        thighs_shanks = {f"{side}_{seg}" for side in legs for seg in ("femur", "tibia")}
        knee_cal = calibrate_knees(s.trial, None, knee_axes, opts.calibration_method,
                                   shared_world=not align & thighs_shanks)
    rotations, drifts = s.rotations, {}
    if align:
        rotations, drifts = align_headings(s.trial, rotations, legs, align, knee_cal, method,
                                           s.notes)
    turns = {seg: vertical_turn(rotations[seg], s.rotations[seg]) for seg in align}
    step("calibration pose")
    cal = _calibration(s, rotations, inputs)
    knee_cal = with_placements(knee_cal, cal.placements, knee_axes)
    if check_sides and in_one_heading(s.oriented.shared, drifts):
        sides = side_evidence(s.trial, rotations, cal, method, geometry, s.gait.strides)
        if sides is not None and sides.mirrored:
            return sides
    posture = None
    if opts.posture == "measured" and opts.calibration_pose == "standing" and not cal.walked:
        posture = _measured_posture(s.trial, rotations, cal, geometry, legs, s.notes)
        cal = cal.with_pose(lean_pose(cal.pose, posture), geometry, legs)
        knee_cal = with_placements(knee_cal, cal.placements, knee_axes)
    unaligned = {f"{side}_tibia" for side in legs
                 if f"{side}_tibia" in align and f"{side}_knee" not in drifts}
    placements, corrections = correct_knees(rotations, cal, knee_axes, knee_cal, opts.correction,
                                            unaligned, s.trial.rate_hz, s.notes)
    step("inverse kinematics")
    run = _solved(s, geometry, opts, placements, rotations, cal)
    run.measures, run.posture, run.corrections = measures, posture, corrections
    run.knee_calibrations, run.heading_drifts, run.heading_turns = knee_cal, drifts, turns
    return run


def _calibration(s: Prepared, rotations, inputs: PoseInputs) -> CalibrationPose:
    """Steps 3-4: the calibration pose where the recording shows it, else from the walk
    (:mod:`pipeline.process.pose_source`); ``cal.how`` says which."""
    if s.static_pose is not None:
        source = PoseSource(tuple(s.windows), None, static=s.static_pose)
    else:
        source = source_of(s.trial, rotations, s.windows, s.gait, inputs)
    return calibrate(s.trial, rotations, source, inputs, s.notes, s.flags)


def _method(opts: IKOptions) -> str:
    return DEFAULT_METHOD if opts.calibration_method == "none" else opts.calibration_method


def _solved(s: Prepared, geometry, opts: IKOptions, placements, rotations, cal) -> IKRun:
    """Step 6 and what follows it: the IK, the angles, the pelvis's path, the landmarks and the
    flags, as an :class:`IKRun` (its calibration's fields filled by the caller)."""
    t0 = _time.perf_counter()
    sk, Q, result = solve(geometry, opts, s.sensors.legs, placements, rotations, cal,
                           s.sensors.pelvis)
    seconds = _time.perf_counter() - t0
    notes = s.notes
    if not np.all(result.converged):
        notes.append(f"IK did not converge on {int(np.sum(~result.converged))} frames")
    missing = unknown_in(rotations)
    angles = blank_angles(joint_angles_of(sk, Q, s.sensors, rotations, placements, cal.H),
                          missing)
    if "pelvis_imu" in s.trial.missing.restarted:
        angles = blank_after_restart(angles, PELVIS_ANGLES, "pelvis_imu", s.trial.missing, notes)
    gait = with_pelvis_path(s.gait, s.trial, sk, Q, notes)
    if gait.pelvis_path is not None:
        gait = replace(gait, pelvis_path=blank_path(gait.pelvis_path, missing))
    still = np.zeros(len(Q), dtype=bool)
    for w in s.windows:
        still[w.rows] = True
    flags = [f.line() for f in s.findings if f.flagged] + s.flags + quality_flags(
        sk, Q, result.residual_rms, notes, [j for j in sk.joint_names if observed(j, s.sensors)],
        still)
    landmarks = blank_landmarks(landmarks_of(sk, Q, s.sensors), missing, landmark_segment)
    return IKRun(s.trial.time, Q, angles, landmarks, cal.right, opts.heading,
                 result.residual_rms, sk, seconds, notes, flags, opts, s.sensors, placements,
                 filtered=s.oriented.filtered, magnetometers=s.oriented.magnetometers,
                 source=s.trial.source, sensor_findings=s.findings, gait=gait,
                 calibration=cal.how)


def _measured_posture(trial, rotations, cal: CalibrationPose, geometry, legs, notes) -> Posture:
    """The standing lean of each leg (:mod:`pipeline.process.posture`)."""
    lengths = {f"{side}_tibia": geometry.for_side(side).shank_length for side in legs}
    forward = cal.H[:, 0]
    return standing_posture(trial, rotations, cal.at_pose, cal.pose, forward, lengths, legs, notes)


def _geometry(measures: Measures, opts: IKOptions):
    axes = {}
    if opts.knee_axis_femur is not None:
        axes = dict(knee_axis_femur=np.array(opts.knee_axis_femur),
                    knee_axis_tibia=np.array(opts.knee_axis_tibia))
    geometry, _ = geometry_from_measures(measures, foot_length_m=opts.foot_length_m, **axes)
    return geometry


def mot_columns(run: IKRun) -> dict[str, np.ndarray]:
    """OpenSim-style coordinate columns (radians; :func:`write_mot` converts to degrees; the
    pelvis's path ``pelvis_t[xyz]`` in metres, in the heading frame of the calibration pose: the
    ground of the pelvis's angles and of the ``.osim``)."""
    cols = {k: run.joint_angles[k] for k in PELVIS_ANGLES if k in run.joint_angles}
    for side, suffix in (("right", "r"), ("left", "l")):
        for ours, theirs in MOT_NAMES.items():
            key = f"{side}_{ours}"
            if key in run.joint_angles:
                cols[f"{theirs}_{suffix}"] = run.joint_angles[key]
    if run.gait.pelvis_path is not None:  # metres: write_mot leaves *_t[xyz] as they are
        # in the heading frame of the calibration pose, as the pelvis's angles
        path = run.gait.pelvis_path @ heading_rotation(run.heading_right)
        cols.update({f"pelvis_t{a}": path[:, i] for i, a in enumerate("xyz")})
    return cols
