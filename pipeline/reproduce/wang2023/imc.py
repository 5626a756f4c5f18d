"""Stage 2 of the Wang 2023 reproduction: landmark trajectories from IMC data vs optical capture.

For each of the 16 IMC subjects and each configuration

* ``tibia_input``: ``stored`` (the dataset's ``RTibiaRotm``, which contains hand-tuned rotations
  for nine subjects) or ``uncorrected`` (``RTibiaRotm · Cᵀ``, as the suit delivered it);
* ``correction``: ``none``; ``average`` (closed form, Wang eq 9-13, towards the mean OMC AoR of the
  subject's sex); ``individual`` (towards the subject's own OMC AoR); ``reference`` (towards the
  *female* mean for everyone: what the reference code did by mistake, kept to explain the paper's
  numbers); ``ipopt`` (the AoR correction as an NLP over the whole trial,
  :mod:`pipeline.calibration.aor_ipopt`); ``hinge_ik`` (no constant correction: orientation IK
  on a model whose knee is a hinge about the sex-average AoR, i.e. the AoR constraint at every
  sample); ``full_ipopt`` (the full sensor-to-segment rotation of femur and tibia from the IMU
  data alone, :mod:`pipeline.calibration.full_correction`: hinge residual, population AoR, rest
  pose and motion plane, with priors fitted on the *other* subjects' optical data
  (leave-one-subject-out, :mod:`~pipeline.reproduce.wang2023.full_ipopt`) and the regression's
  knee and ankle centres; applied as eq 13);

every correction but ``full_ipopt`` computed by the user's path, ``pipeline ik`` on the IMC
femur and tibia as a knee-only recording of segment orientations (:func:`user_path_options`,
:func:`corrected_orientations`);
* ``positions``: ``regression`` (Table I, smallest-SD equation given h, s_L, s_M, k, a) or ``omc``
  (the subject's own landmark positions in the segment frames),

the trajectories follow eq 15-17 (:func:`pipeline.analysis.landmarks.wang_trajectories`, equal to
the free-knee model's forward kinematics), the IMC-OMC lag is estimated from the femur's angular
speed (not the reference's offset table), the frames are unified by eq 18-19 and compared by eq 20,
RMS, Pearson r and ICC(A,1); orientation errors are ZYX angles of R_imcᵀ R_omc (Table V).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from tqdm import tqdm

from pipeline.analysis.landmarks import wang_trajectories
from pipeline.calibration.aor import knee_aor
from pipeline.errors import InputError
from pipeline.ik.solver import IKResult, solve_ik
from pipeline.io.opensim import sensor_to_opensim_matrix
from pipeline.io.recording import Recording
from pipeline.model.anthropometry import predict_landmarks
from pipeline.model.geometry import SubjectGeometry
from pipeline.model.measures import Measures
from pipeline.model.skeleton import Skeleton
from pipeline.process.options import IKOptions
from pipeline.process.run import process_recording
from pipeline.reproduce.wang2023.dataset import IMC_OMC_INDEX_OFFSET
from pipeline.reproduce.wang2023.evaluation import (
    align,
    angular_speed,
    compare_trajectories,
    estimate_lag,
    frame_from_femur,
    points_to_omc,
    rms_orientation_error,
    rotations_to_omc,
    unify_frames,
)
from pipeline.reproduce.wang2023.full_ipopt import (
    FULL_CORRECTION_COLUMNS,
    full_corrected,
    full_rows,
    knee_trial,
    loso_priors,
)
from pipeline.reproduce.wang2023.optical import OmcStage, hip_centred_paths
from pipeline.rotations import quat_from_matrix

if TYPE_CHECKING:
    from pipeline.ik.solver import IKResult
    from pipeline.reproduce.wang2023.dataset import Subject
    from pipeline.reproduce.wang2023.omc import OmcResult
from pipeline.io.tables import csv_text

LANDMARKS = ("EFM", "EFL", "MM", "LM")
TIBIA_INPUTS = ("stored", "uncorrected")
POSITIONS = ("regression", "omc")
TRAJECTORY_COLUMNS = (
    "subject_id", "sex", "tibia_input", "positions", "correction", "landmark", "rms_mm",
    "r_x", "r_y", "r_z", "icc_x", "icc_y", "icc_z", "n_frames",
)
ORIENTATION_COLUMNS = ("subject_id", "tibia_input", "correction", "segment", "z_deg", "y_deg",
                       "x_deg", "error_frame")
MAX_LAG = 250  # samples; the reference offsets reach 169


@dataclass
class ImcStage:
    trajectory_rows: list[dict]
    orientation_rows: list[dict]
    subjects: list[dict]
    corrections: tuple[str, ...]
    seconds: float
    notes: list[str] = field(default_factory=list)
    #: One subject's paired trajectories for the figures: ``subject_id``, ``rate_hz``, ``omc``
    #: (landmark -> (N, 3) mm) and ``imc`` (correction -> landmark -> (N, 3) mm, in the OMC frame
    #: after eq 18-19), uncorrected tibia input, regression positions.
    example: dict = field(default_factory=dict)
    #: Table IV's malleoli with the reference code's choices one at a time
    #: (:func:`pipeline.reproduce.wang2023.factors.factor_rows`); empty until computed.
    factors: list[dict] = field(default_factory=list)
    #: subject -> the stored input's femur and tibia orientations after the ``reference``
    #: correction (IMC world), for the factor study
    reference_orientations: dict = field(default_factory=dict)
    #: ``(subject, tibia input)`` -> the ``full_ipopt`` calibration, and subject -> its
    #: leave-one-subject-out priors
    full_corrections: dict = field(default_factory=dict)
    priors: dict = field(default_factory=dict)
    #: the ``full_ipopt`` correction beside its bounds
    #: (:func:`pipeline.reproduce.wang2023.limits.limit_rows`); empty until computed.
    limits: list[dict] = field(default_factory=list)


def _corrections() -> tuple[str, ...]:
    return ("none", "average", "individual", "reference", "ipopt", "hinge_ik", "full_ipopt")


#: The IMC world is the femur's pose at the first sample with ``r = Rx(+90 deg)`` (dataset
#: README): the supine subject's anterior axis is its x axis. ``Rz(+90 deg)`` (space-fixed XYZ
#: angles ``0 0 pi/2``, ``--sensor-to-model``) makes that axis the model's up, y.
IMC_SENSOR_TO_MODEL = (0.0, 0.0, float(np.pi / 2))


def user_path_options(correction: str, sex_aor, own_aor, female_aor) -> IKOptions:
    """The ``pipeline ik`` options that compute one of the reproduction's corrections.

    Every configuration runs the user's path (:func:`pipeline.process.process_recording`) on the
    IMC femur and tibia as a knee-only recording of segment orientations, supine at the first
    sample, without joint limits (eq 15-17 have none): ``none`` (no correction), ``average`` /
    ``individual`` / ``reference`` (``--correction aor`` towards the sex mean, the subject's own
    OMC AoR, the female mean), ``ipopt`` (``--correction aor-ipopt``, sex mean) and ``hinge_ik``
    (``--knee hinge`` about the sex mean, no constant correction).
    """
    aor = {"individual": own_aor, "reference": female_aor}.get(correction, sex_aor)
    method = {"none": "none", "hinge_ik": "none", "ipopt": "aor-ipopt"}.get(correction, "aor")
    return IKOptions(
        knee="hinge" if correction == "hinge_ik" else "free", correction=method,
        knee_axis_femur=tuple(aor.femur_axis), knee_axis_tibia=tuple(aor.tibia_axis),
        segment_orientations=True, calibration_pose="supine",
        sensor_to_model=IMC_SENSOR_TO_MODEL, joint_limits=False,
    )


def imc_recording(femur_R: np.ndarray, tibia_R: np.ndarray, rate_hz: float = 100.0) -> Recording:
    """The IMC femur and tibia as a user's knee-only recording (``femur_r_imu``,
    ``tibia_r_imu``, quaternions ``w, x, y, z`` in the IMC world)."""
    n = len(femur_R)
    quats = {"femur_r_imu": quat_from_matrix(femur_R), "tibia_r_imu": quat_from_matrix(tibia_R)}
    return Recording.from_orientations(np.arange(n) / rate_hz, rate_hz, quats)


def corrected_orientations(
    correction: str, F: np.ndarray, T: np.ndarray, measures: Measures, sex_aor, own_aor,
    female_aor,
) -> tuple[np.ndarray, np.ndarray]:
    """Femur and tibia orientations (IMC world) after ``correction``, by the user's path
    (:func:`user_path_options`): the solved model's segment frames, rotated back from the model's
    y-up world."""
    options = user_path_options(correction, sex_aor, own_aor, female_aor)
    run = process_recording(imc_recording(F, T), measures, options)
    seg = run.segment_orientations(["right_femur", "right_tibia"])
    W = sensor_to_opensim_matrix(IMC_SENSOR_TO_MODEL)
    return W.T @ seg["right_femur"], W.T @ seg["right_tibia"]


def subject_measures(subject, result) -> Measures:
    """The subject's measures as a user would give them: sex, height and the four lengths
    (s_L, s_M, k, a) from its optical landmarks."""
    d = result.dims
    return Measures(subject.omc.sex, subject.omc.height_m, d.s_L, d.s_M, d.k, d.a)


def landmark_positions(kind: str, subject, result):
    if kind == "omc":
        return result.landmarks_femur, result.landmarks_tibia
    p = predict_landmarks(subject_measures(subject, result))
    return p.femur, p.tibia


def run_imc_stage(
    omc_stage: OmcStage, *, rerun_dir: str | Path | None = None, progress: bool = True
) -> ImcStage:
    """All configurations for every subject with IMC data (see module docstring)."""
    t0 = time.perf_counter()
    corrections = _corrections()
    pop = omc_stage.population
    traj_rows, orient_rows, subjects, notes = [], [], [], []
    reference_orientations = {}
    full_corrections, priors = {}, {}
    example: dict = {}
    trials = {}
    if "full_ipopt" in corrections:
        trials = {s.omc.subject_id: (omc_stage.result(s.omc.subject_id).sex,
                                     knee_trial(s, omc_stage.result(s.omc.subject_id)))
                  for s in omc_stage.subjects}
    imc_subjects = [s for s in omc_stage.subjects if s.imc is not None]
    if not imc_subjects:
        raise InputError("no subject with IMC data (imcData) in the dataset")
    for subject in tqdm(imc_subjects, desc="IMC subjects", unit="subject", disable=not progress):
        sid = subject.omc.subject_id
        r = omc_stage.result(sid)
        omc_traj = hip_centred_paths(subject, r)
        # time lag from the femur's angular speed (frame- and offset-invariant)
        imc_speed = angular_speed(subject.imc.femur_R)
        omc_speed = angular_speed(r.femur_R)
        lag = estimate_lag(omc_speed, imc_speed, MAX_LAG)
        ref_lag = IMC_OMC_INDEX_OFFSET.get(sid, 0)
        subjects.append(dict(subject_id=sid, sex=r.sex, lag=lag, reference_lag=ref_lag))
        omc_F, _ = align(r.femur_R, subject.imc.femur_R, lag)
        omc_T, _ = align(r.tibia_R, subject.imc.femur_R, lag)
        omc_paired = {n: align(v, subject.imc.femur_R, lag)[0] for n, v in omc_traj.items()}
        if trials:
            priors[sid] = loso_priors(trials, sid)
        for tibia_input in TIBIA_INPUTS:
            F = subject.imc.femur_R
            T = subject.imc.tibia_R if tibia_input == "stored" else subject.imc.tibia_R_uncorrected
            try:
                knee_aor(F, T)  # the corrections need the AoR the IMC data show (eq 1-8)
            except InputError as exc:
                notes.append(f"subject {sid} ({tibia_input}): no IMC AoR: {exc}")
                continue
            measures = subject_measures(subject, r)
            for correction in corrections:
                if correction == "full_ipopt":
                    eF, eT, c = full_corrected(F, T, measures, priors[sid])
                    full_corrections[sid, tibia_input] = c
                else:
                    eF, eT = corrected_orientations(correction, F, T, measures, pop[r.sex],
                                                    r.knee_aor, pop["f"])
                if (tibia_input, correction) == ("stored", "reference"):
                    reference_orientations[sid] = (eF, eT)
                _, eF_p = align(r.femur_R, eF, lag)
                _, eT_p = align(r.femur_R, eT, lag)
                R_unify = None
                for positions in POSITIONS:
                    pf, pt = landmark_positions(positions, subject, r)
                    comp, R, imc_traj = unified_comparison(eF_p, eT_p, pf, pt, omc_paired, omc_F)
                    if positions == "regression":
                        R_unify = R
                    if (positions == "regression" and tibia_input == "uncorrected"
                            and (not example or example["subject_id"] == sid)):
                        example.setdefault("subject_id", sid)
                        example["rate_hz"] = subject.omc.rate_hz
                        example["omc"] = {n: 1e3 * omc_paired[n] for n in LANDMARKS}
                        example.setdefault("imc", {})[correction] = {
                            n: 1e3 * points_to_omc(R, imc_traj[n]) for n in LANDMARKS}
                    for name in LANDMARKS:
                        c = comp[name]
                        traj_rows.append(
                            dict(
                                subject_id=sid, sex=r.sex, tibia_input=tibia_input,
                                positions=positions, correction=correction, landmark=name,
                                rms_mm=1e3 * c.rms, r_x=c.r[0], r_y=c.r[1], r_z=c.r[2],
                                icc_x=c.icc[0], icc_y=c.icc[1], icc_z=c.icc[2],
                                n_frames=c.n_frames,
                            )
                        )
                for segment, imc_R, omc_R in (("femur", eF_p, omc_F), ("tibia", eT_p, omc_T)):
                    for error_frame in ("body", "world"):
                        z, y, x = np.degrees(
                            rms_orientation_error(
                                rotations_to_omc(R_unify, imc_R), omc_R, error_frame
                            )
                        )
                        orient_rows.append(
                            dict(subject_id=sid, tibia_input=tibia_input, correction=correction,
                                 segment=segment, z_deg=z, y_deg=y, x_deg=x,
                                 error_frame=error_frame)
                        )
        if rerun_dir is not None:
            _log_subject(Path(rerun_dir), subject, r, omc_paired, lag, pop)
    return ImcStage(traj_rows, orient_rows, subjects, corrections, time.perf_counter() - t0, notes,
                    example, reference_orientations=reference_orientations,
                    full_corrections=full_corrections, priors=priors)


def unified_trajectories(
    femur: np.ndarray, tibia: np.ndarray, femur_positions, tibia_positions, omc_paths,
    omc_femur: np.ndarray, t: int = 0, through_hip: bool = True,
):
    """The landmark trajectories of the paired IMC femur and tibia (eq 15-17) and the rotation
    unifying their frame with the optical one from frame ``t`` (eq 18-19):
    ``(R_imc_to_omc, imc_trajectories)``."""
    imc = wang_trajectories(femur, tibia, femur_positions, tibia_positions)
    R = unify_frames(frame_from_femur(omc_paths["KJC"], omc_femur, t, through_hip),
                     frame_from_femur(imc["KJC"], femur, t, through_hip))
    return R, imc


def unified_comparison(
    femur: np.ndarray, tibia: np.ndarray, femur_positions, tibia_positions, omc_paths,
    omc_femur: np.ndarray, t: int = 0, through_hip: bool = True,
):
    """:func:`unified_trajectories` compared with the optical paths (eq 20):
    ``(comparisons, R_imc_to_omc, imc_trajectories)``."""
    R, imc = unified_trajectories(femur, tibia, femur_positions, tibia_positions, omc_paths,
                                  omc_femur, t, through_hip)
    return compare_trajectories({n: imc[n] for n in LANDMARKS}, omc_paths, R_imc_to_omc=R), R, imc


def subject_motion(
    subject: Subject,
    r: OmcResult,
    eF: np.ndarray,
    eT: np.ndarray,
    G_imc: np.ndarray,
    *,
    positions: str = "regression",
    limits: bool = True,
) -> tuple[Skeleton, IKResult]:
    """The subject's free-knee model and its configurations reproducing the IMC trajectories.

    The model is built from the subject's landmark positions (``positions``); femur and tibia
    targets are the IMC orientations expressed in the initial frame of eq 18 (``G_imc^T e``), in
    which the femur points up at the first paired frame. With ``limits=False`` the model's
    landmark frames reproduce eq 15-17 exactly (tested); with limits the knee cannot hyperextend.
    The model is built in memory. Returns ``(skeleton, ik_result)``.
    """

    pf, pt = landmark_positions(positions, subject, r)
    geometry = SubjectGeometry(
        sex=r.sex, height_m=subject.omc.height_m, femur_landmarks=pf, tibia_landmarks=pt,
        knee_axis_femur=r.knee_aor.femur_axis, knee_axis_tibia=r.knee_aor.tibia_axis,
    )
    sk = Skeleton.build(geometry, knee="free", legs=("right",))
    targets = {"right_femur": G_imc.T @ eF, "right_tibia": G_imc.T @ eT}
    return sk, solve_ik(sk.model, targets, limits=limits)


def _log_subject(rerun_dir: Path, subject, r, omc_paired, lag, pop) -> Path:
    """One .rrd per subject: the moving model (regression geometry, average AoR correction,
    uncorrected tibia), its landmarks beside the optical ones, error arrows and joint angles, all
    in the initial frame of eq 18 (femur up at the first frame)."""
    from pipeline.viz.model import SceneOptions, log_motion  # rerun: only with --rerun

    F, T = subject.imc.femur_R, subject.imc.tibia_R_uncorrected
    cF, cT = corrected_orientations("average", F, T, subject_measures(subject, r), pop[r.sex],
                                    r.knee_aor, pop["f"])
    _, eF = align(r.femur_R, cF, lag)
    _, eT = align(r.femur_R, cT, lag)
    pf, pt = landmark_positions("regression", subject, r)
    traj = wang_trajectories(eF, eT, pf, pt)
    omc_F, _ = align(r.femur_R, F, lag)
    G_omc = frame_from_femur(omc_paired["KJC"], omc_F)
    G_imc = frame_from_femur(traj["KJC"], eF)
    sk, ik = subject_motion(subject, r, eF, eT, G_imc)
    sk.forward(sk.neutral())
    hip = sk.frame_position("right_HJC")
    reference = {f"right_{n}": omc_paired[n] @ G_omc + hip for n in LANDMARKS}
    n = len(eF)
    rerun_dir.mkdir(parents=True, exist_ok=True)
    return log_motion(
        rerun_dir / f"subject{subject.omc.subject_id:02d}.rrd",
        np.arange(n) / subject.omc.rate_hz,
        sk,
        ik.q,
        SceneOptions(reference_landmarks=reference,
                     recording_name=f"wang2023 subject {subject.omc.subject_id}"),
    )


def select_rows(rows: list[dict], **match: object) -> list[dict]:
    """The rows of ``trajectory_rows`` / ``orientation_rows`` whose columns equal ``match``."""
    return [r for r in rows if all(r[k] == v for k, v in match.items())]


def rms_values(rows: list[dict], **match: object) -> np.ndarray:
    """The ``rms_mm`` of :func:`select_rows` (mm)."""
    return np.array([r["rms_mm"] for r in select_rows(rows, **match)], dtype=float)


def imc_tables(stage: ImcStage) -> dict[str, str]:
    return {
        "trajectory_errors.csv": csv_text(stage.trajectory_rows, TRAJECTORY_COLUMNS),
        "orientation_errors.csv": csv_text(stage.orientation_rows, ORIENTATION_COLUMNS),
        "full_correction.csv": csv_text(full_rows(stage), FULL_CORRECTION_COLUMNS),
    }
