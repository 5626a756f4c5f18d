"""From a recording of orientations to joint angles and landmark trajectories.

:func:`process_recording` is the pipeline that the Python API, ``pipeline ik``, the demo and the
Wang reproduction share; it writes nothing (outputs are the commands' job). On our scaled Pinocchio
model, the workflow of OpenSim's OpenSense, with the knee-AoR correction of Wang et al. 2023:

1. **Sensors** (:mod:`pipeline.process.sensors`): the recording's names mapped to ours; the
   joints the sensors observe (hip, knee, ankle of each leg); any set observing one joint works.
2. **World.** Orientations ``R_s(t)`` are pre-multiplied by a fixed ``sensor_to_model`` rotation
   (OpenSense's ``sensor_to_opensim_rotations``, space-fixed XYZ angles; ``-pi/2 0 0`` for Xsens'
   z-up world) so that the world's y axis points up.
3. **Heading** (:mod:`pipeline.calibration.heading`): the subject's right at the calibration pose,
   from hip and knee flexion by default or from an axis of the pelvis sensor (OpenSense's way).
   Orientations from a 6-D filter (each sensor's heading its own, drifting) are first put in one
   heading by the joint constraints (``drift``, :mod:`pipeline.process.drift`: hip and ankle
   centres, the knee's hinge axis), and the calibration pose is read from them.
4. **Calibration pose** (:mod:`pipeline.calibration.placement`): the first sample (or the mean of a
   static trial) shows a standing, supine or seated pose; each sensor's rotation on its segment
   follows from it. With ``segment_orientations`` the recording holds segment frames and the
   placements are the identity.
5. **Correction** (:mod:`pipeline.calibration.correction`): per leg with a knee, the segment
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
from dataclasses import dataclass, field

import numpy as np

from pipeline.analysis.landmarks import frame_trajectories, joint_angles, landmark_trajectories
from pipeline.analysis.quality import quality_flags
from pipeline.calibration.conventions import DEFAULT_METHOD
from pipeline.calibration.correction import (
    KneeCorrection,
    carried_correction,
    correct_knee,
    correct_knee_to_axes,
    corrected_placement,
    population_correction,
)
from pipeline.calibration.drift import HeadingDrift
from pipeline.calibration.heading import check_vertical, heading_rotation, subject_right
from pipeline.calibration.placement import (
    mean_rotation,
    placements_from_pose,
    pose_configuration,
    pose_rotations,
)
from pipeline.errors import InputError
from pipeline.ik.bounds import remove_limits
from pipeline.ik.solver import solve_ik
from pipeline.io.opensim import map_sensors, rotate_world, sensor_to_opensim_matrix
from pipeline.io.recording import Recording
from pipeline.model.anthropometry import Measures
from pipeline.model.conventions import LANDMARK_SEGMENT
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.process.drift import align_headings, uses_drift_correction
from pipeline.process.functional import KneeCalibration, calibrate_knees, with_placements
from pipeline.process.options import IKOptions
from pipeline.process.sensors import SensorSet, apply_sensor_map, known_segments, sensor_set
from pipeline.process.signals import Z_UP_TO_Y_UP, orientations_from_signals
from pipeline.rotations import (
    euler_zxy_from_matrix,
    matrix_from_quat,
    quat_xyzw_from_matrix,
    unwrap_angles,
)

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
_PELVIS_ANGLES = ("pelvis_tilt", "pelvis_list", "pelvis_rotation")


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
    ``'<side>_<joint>'`` -> the :class:`~pipeline.calibration.drift.HeadingDrift` applied
    (:mod:`pipeline.process.drift`); ``sensors``: what the sensors
    observe; ``heading_right``: the subject's right at the calibration pose (world);
    ``residual_rms`` (N,) rad; ``flags``: implausible results (:mod:`pipeline.analysis.quality`);
    ``options``: the options used; ``filtered``: ``'6-D'``/``'9-D'`` when the orientations were
    estimated from raw signals here, else None.
    """

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
    filtered: str | None = None

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
    """Steps 1-6 of the module docstring on a read recording; nothing is written.

    ``options`` (default :class:`IKOptions`) with any of its fields overridden by keyword, e.g.
    ``process_recording(rec, Measures("m", 1.8), correction="none", knee="hinge")``. ``static``:
    the static recording that gives the calibration pose (read by the caller; the options'
    ``static_trial`` only names it).
    """
    opts = (options or IKOptions()).replace(**changes) if changes else (options or IKOptions())
    notes = list(trial.notes)
    world = np.eye(3)
    trial = apply_sensor_map(trial, opts.sensor_map)
    trial, filtered = orientations_from_signals(trial, opts.filter, notes)
    if static is not None:
        static = apply_sensor_map(static, opts.sensor_map)
        notes += [f"static trial: {n}" for n in static.notes]
        static, _ = orientations_from_signals(static, opts.filter if filtered else None, [])
    to_model = opts.sensor_to_model
    if filtered:
        if to_model is not None:
            raise InputError("--sensor-to-model applies to a recording's own orientations; the "
                             "filter's world is z up and is turned to y up already",
                             file=trial.source, field="sensor_to_model")  # fmt: skip
        to_model = Z_UP_TO_Y_UP
    if to_model is not None:
        world = sensor_to_opensim_matrix(to_model)
        trial = rotate_world(trial, world)
        static = rotate_world(static, world) if static is not None else None
    rotations = {seg: matrix_from_quat(q) for seg, q in map_sensors(trial).items()
                 if seg != "torso"}  # fmt: skip
    sensors = sensor_set(set(rotations), source=trial.source)
    ignored = sorted(set(trial.sensor_names) - set(known_segments(trial)))
    if ignored:
        notes.append(f"sensors without a segment in this lower-limb model, ignored: {ignored}")
    unused = sorted(s for s in rotations if _side(s) not in sensors.legs and s != "pelvis")
    if unused:
        notes.append(f"segments whose sensor observes no joint, ignored: {unused}")
    rotations = {s: R for s, R in rotations.items() if s == "pelvis" or _side(s) in sensors.legs}
    if sensors.pelvis and not filtered:  # the filter's world is vertical by construction
        check_vertical(rotations["pelvis"], notes=notes, applied=world)
    elif not sensors.pelvis:
        notes.append("no pelvis sensor: hip and pelvis angles are not observed; landmarks are "
                     "relative to each leg's hip centre")  # fmt: skip
    if opts.heading != "anatomical" and not sensors.pelvis:
        raise InputError(f"heading {opts.heading!r} needs a pelvis sensor (pelvis_imu)",
                         file=trial.source, field="heading")  # fmt: skip
    static_pose = None
    if static is not None:
        static_pose = _static_orientations(static, rotations, notes, opts.calibration_pose)
    axes = {}
    if opts.knee_axis_femur is not None:
        axes = dict(knee_axis_femur=np.array(opts.knee_axis_femur),
                    knee_axis_tibia=np.array(opts.knee_axis_tibia))  # fmt: skip
    geometry, _ = geometry_from_measures(measures, foot_length_m=opts.foot_length_m, **axes)
    legs = sensors.legs
    # the model's segment orientations in the calibration pose (free knee: the heading; a hinge
    # about a tilted AoR turns the tibia and foot by the aligning rotation)
    pose_model = Skeleton.build(geometry, knee=opts.knee, legs=legs)

    def read_pose(rotations, notes):
        return _calibration_pose(rotations, static_pose, opts, pose_model, geometry, legs, notes)

    right, H, pose, placements = read_pose(rotations, notes)

    knee_cal = []
    axes_by_side = {s: (geometry.for_side(s).knee_axis_femur, geometry.for_side(s).knee_axis_tibia)
                    for s in legs if sensors.observes(s, "knee")}  # fmt: skip
    if opts.calibration_method != "none":
        knee_cal = calibrate_knees(trial, placements, axes_by_side, opts.calibration_method,
                                   shared_world=filtered != "6-D")  # fmt: skip
    drifts = {}
    if uses_drift_correction(opts.drift, filtered):
        method = DEFAULT_METHOD if opts.calibration_method == "none" else opts.calibration_method
        rotations, drifts = align_headings(trial, rotations, knee_cal, legs, method, notes)
        if drifts:  # the calibration pose read again from the aligned orientations
            right, H, pose, placements = read_pose(rotations, None)
            knee_cal = with_placements(knee_cal, placements, axes_by_side)
    functional = {c.side: c for c in knee_cal if c.trusted}

    corrections = {}
    if opts.correction != "none":
        for side in legs:
            if not sensors.observes(side, "knee"):
                continue
            fem, tib = f"{side}_femur", f"{side}_tibia"
            S_F = rotations[fem] @ placements[f"{fem}_imu"][:3, :3].T
            S_T = rotations[tib] @ placements[f"{tib}_imu"][:3, :3].T
            g = geometry.for_side(side)
            c, method, unseen = None, opts.correction, None
            if uses_drift_correction(opts.drift, filtered) and f"{side}_knee" not in drifts:
                unseen = ("its thigh and shank sensors' headings were not aligned: the AoR seen "
                          "across two worlds is turned by their heading difference")
            elif method == "functional":
                if side in functional:
                    # the gyroscopes' hinge axis (Hu eq 4-6) instead of the one the orientations
                    # show (eq 1-8): the sensor placement is right, but the filter's heading
                    # errors stay (eq 1-8 absorbs their constant part; pipeline.process.functional)
                    f = functional[side]
                    v_F = placements[f"{fem}_imu"][:3, :3] @ f.axis_thigh
                    v_T = placements[f"{tib}_imu"][:3, :3] @ f.axis_shank
                    c = correct_knee_to_axes(S_F, S_T, v_F, v_T, g.knee_axis_femur,
                                             g.knee_axis_tibia, side=side)  # fmt: skip
                    why = f"its functional axis is not used: {c.reason}"
                elif any(k.side == side for k in knee_cal):
                    why = "its functional calibration is not trusted"
                else:
                    why = ("no functional calibration (raw gyroscope and accelerometer signals "
                           "of both sensors are needed)")
                if c is None or not c.applied:
                    notes.append(f"{side} knee: {why}; corrected by eq 1-8 ('aor') instead")
                    c, method = None, "aor"
            if c is None and unseen is None:
                c = correct_knee(S_F, S_T, g.knee_axis_femur, g.knee_axis_tibia,
                                 method=method, side=side, rate_hz=trial.rate_hz)  # fmt: skip
            if unseen is not None or not c.applied:  # as the reference population's knee
                R_ft = pose[fem].T @ pose[tib]  # the tibia in the femur in the calibration pose
                c = population_correction(S_F, S_T, g.knee_axis_femur, g.knee_axis_tibia, R_ft,
                                          side=side, reason=unseen or c.reason)  # fmt: skip
                notes.append(f"{side} knee: its AoR is not seen ({c.reason}); corrected as the "
                             "reference population's knee")  # fmt: skip
            corrections[side] = c
            placements[f"{fem}_imu"] = corrected_placement(placements[f"{fem}_imu"],
                                                           c.femur_rotation)  # fmt: skip
            placements[f"{tib}_imu"] = corrected_placement(placements[f"{tib}_imu"],
                                                           c.tibia_rotation)  # fmt: skip
            if f"{side}_foot_imu" in placements:  # placed with the ankle at neutral
                R_c = pose[tib].T @ pose[f"{side}_foot"]
                placements[f"{side}_foot_imu"] = corrected_placement(
                    placements[f"{side}_foot_imu"], carried_correction(c.tibia_rotation, R_c))

    targets = {f"{seg}_imu": R for seg, R in rotations.items()}
    t0 = _time.perf_counter()
    if sensors.pelvis:
        sk = Skeleton.build(geometry, knee=opts.knee, legs=legs, imu_placements=placements,
                            root="spherical")  # fmt: skip
        q0 = _pose_q(sk, opts.calibration_pose, pose["pelvis"])
        result = solve_ik(sk.model, targets, q0=q0, limits=opts.joint_limits)
        Q = result.q
    else:
        # the pelvis held in its calibration-pose orientation; the hips absorb the thighs'
        # whole orientation, so they must not be limited
        fixed = Skeleton.build(geometry, knee=opts.knee, legs=legs, imu_placements=placements)
        remove_limits(fixed.model, [f"{s}_hip_{a}" for s in legs for a in "ZXY"])
        q0 = _pose_q(fixed, opts.calibration_pose, None)
        result = solve_ik(fixed.model, targets, q0=q0, root=pose["pelvis"],
                          limits=opts.joint_limits)  # fmt: skip
        sk = fixed.with_root("spherical")
        root = np.tile(quat_xyzw_from_matrix(pose["pelvis"]), (len(result.q), 1))
        Q = np.hstack([root, result.q])
    seconds = _time.perf_counter() - t0
    if not np.all(result.converged):
        notes.append(f"IK did not converge on {int(np.sum(~result.converged))} frames")
    angles = {k: v for k, v in joint_angles(sk, Q).items() if _observed(k, sensors)}
    if sensors.pelvis:
        pelvis_world = rotations["pelvis"] @ placements["pelvis_imu"][:3, :3].T
        zxy = euler_zxy_from_matrix(np.einsum("ij,njk->nik", H.T, pelvis_world))
        angles.update(zip(_PELVIS_ANGLES, zxy.T, strict=True))
    # continuous angles: a subject turning round must not make pelvis_rotation jump by 360 deg
    angles = {name: unwrap_angles(a) for name, a in angles.items()}
    landmarks = _landmarks(sk, Q, sensors)
    flags = quality_flags(sk, Q, result.residual_rms, notes,
                          joints=[j for j in sk.joint_names if _observed(j, sensors)])  # fmt: skip
    return IKRun(trial.time, Q, angles, landmarks, right, opts.heading, result.residual_rms,
                 sk, seconds, notes, flags, opts, sensors, placements, corrections,
                 knee_cal, drifts, filtered)  # fmt: skip


def _side(segment: str) -> str:
    return segment.split("_", 1)[0]


def _observed(name: str, sensors: SensorSet) -> bool:
    """Whether an angle (``right_knee_flexion``) or joint (``right_knee_Z``) is observed."""
    side, rest = name.split("_", 1)
    return sensors.observes(side, rest.split("_", 1)[0])


def _pose_q(sk: Skeleton, pose: str, pelvis: np.ndarray | None) -> np.ndarray:
    q = pose_configuration(sk, pose)
    if pelvis is not None:
        q[:4] = quat_xyzw_from_matrix(pelvis)
    return q


def _calibration_pose(rotations, static_pose, opts, pose_model, geometry, legs, notes):
    """``(right, H, pose, placements)`` from the calibration pose: the first sample, or the
    static trial's mean orientations ``static_pose`` put in front of the motion so that the
    heading is found from the motion relative to that pose (steps 3-4)."""
    if static_pose is not None:
        at_pose = dict(static_pose)
        cue = {seg: np.concatenate([at_pose[seg][None], R]) for seg, R in rotations.items()}
    else:
        at_pose = {seg: R[0] for seg, R in rotations.items()}
        cue = rotations
    start = (np.pi / 2, np.pi / 2) if opts.calibration_pose == "seated" else (0.0, 0.0)
    pose0 = pose_rotations(pose_model, opts.calibration_pose, np.eye(3))  # zero heading
    knee_axes = {s: pose0[f"{s}_femur"] @ geometry.for_side(s).knee_axis_femur for s in legs}
    right = subject_right(cue, opts.heading, notes=notes, start_flexion=start,
                          knee_axes=knee_axes)  # fmt: skip
    H = heading_rotation(right)
    pose = pose_rotations(pose_model, opts.calibration_pose, H)
    if opts.segment_orientations:
        at_pose = {seg: pose[seg] for seg in rotations}  # placements: the identity
    return right, H, pose, placements_from_pose(pose, geometry, at_pose, legs)


def _static_orientations(static, rotations, notes, pose_name):
    """Each sensor's mean orientation over the static trial (:func:`mean_rotation`)."""
    still = {seg: matrix_from_quat(q) for seg, q in map_sensors(static).items()}
    missing = sorted(set(rotations) - set(still))
    if missing:
        raise InputError(f"the static trial lacks sensors for {missing}", file=static.source,
                         field="static_trial")  # fmt: skip
    notes.append(f"calibration pose ({pose_name}) from the static trial: mean of "
                 f"{static.n_samples} samples")  # fmt: skip
    return {seg: mean_rotation(still[seg]) for seg in rotations}


def _landmarks(sk: Skeleton, Q: np.ndarray, sensors: SensorSet) -> dict[str, np.ndarray]:
    def segment(frame: str) -> str:
        side, landmark = frame.split("_", 1)
        return f"{side}_{LANDMARK_SEGMENT[landmark]}"

    names = [f for f in sk.landmark_frames if segment(f) in sensors.landmark_segments]
    if not names:
        return {}
    hips = [f"{s}_HJC" for s in sensors.legs]
    traj = landmark_trajectories(sk, Q, names + [h for h in hips if h not in names])
    if not sensors.pelvis:
        traj = {n: traj[n] - traj[f"{_side(n)}_HJC"] for n in names}
    return {n: traj[n] for n in names}


def mot_columns(run: IKRun) -> dict[str, np.ndarray]:
    """OpenSim-style coordinate columns (radians; :func:`write_mot` converts to degrees)."""
    cols = {k: run.joint_angles[k] for k in _PELVIS_ANGLES if k in run.joint_angles}
    for side, suffix in (("right", "r"), ("left", "l")):
        for ours, theirs in MOT_NAMES.items():
            key = f"{side}_{ours}"
            if key in run.joint_angles:
                cols[f"{theirs}_{suffix}"] = run.joint_angles[key]
    return cols
