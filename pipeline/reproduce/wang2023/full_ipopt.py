"""The ``full_ipopt`` correction of the IMC stage (issue 13, item 1): the full sensor-to-segment
rotation of femur and tibia from the IMU data alone
(:func:`pipeline.calibration.full_correction.full_correction_ipopt`), with population priors
fitted leave-one-subject-out on the other subjects' optical knees (:func:`loso_priors`) and the
regression's knee and ankle centres (what an IMU-only user has), applied as eq 13."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from pipeline.calibration.full_correction import full_correction_ipopt
from pipeline.calibration.priors import CorrectionPriors, KneeTrial, correction_priors
from pipeline.model.anthropometry import predict_landmarks
from pipeline.model.measures import Measures
from pipeline.reproduce.wang2023.optical import hip_centred_paths
from pipeline.rotations import log3

__all__ = ["FULL_CORRECTION_COLUMNS", "full_corrected", "full_rows", "knee_trial", "loso_priors"]

FULL_CORRECTION_COLUMNS = (
    "subject_id", "sex", "tibia_input", "status", "iterations", "seconds", "hinge_rms_deg",
    "rest_closed_form_deg", "rest_deg", "plane_closed_form_mm", "plane_mm", "femur_deg",
    "tibia_deg",
)


def knee_trial(subject, r) -> KneeTrial:
    """The subject's optical knee for the priors of ``full_ipopt`` (anatomical frames, own AoR,
    hip-centred knee and ankle centres)."""
    paths = hip_centred_paths(subject, r)
    return KneeTrial(r.femur_R, r.tibia_R, r.knee_aor, paths["KJC"],
                     0.5 * (paths["MM"] + paths["LM"]))


def loso_priors(trials: dict[int, tuple[str, KneeTrial]], subject_id: int) -> CorrectionPriors:
    """:func:`correction_priors` of every subject but ``subject_id``; the AoR prior from those
    of the subject's sex (as the paper's average AoR)."""
    sex = trials[subject_id][0]
    others = [t for sid, (_, t) in trials.items() if sid != subject_id]
    same = [t for sid, (sx, t) in trials.items() if sid != subject_id and sx == sex]
    p, ps = correction_priors(others), correction_priors(same)
    return replace(p, femur_axis=ps.femur_axis, tibia_axis=ps.tibia_axis,
                   sd_femur_axis=ps.sd_femur_axis, sd_tibia_axis=ps.sd_tibia_axis)


def full_corrected(F: np.ndarray, T: np.ndarray, measures: Measures, priors: CorrectionPriors):
    """``full_ipopt``: femur and tibia after :func:`full_correction_ipopt` (eq 13) with the
    regression's knee and ankle centres (what an IMU-only user has); ``(eF, eT, result)``."""
    p = predict_landmarks(measures)
    knee = 0.5 * (p.femur["EFM"] + p.femur["EFL"])
    ankle = 0.5 * (p.tibia["MM"] + p.tibia["LM"])
    c = full_correction_ipopt(F, T, knee, ankle, priors)
    return F @ c.R_co_femur, T @ c.R_co_tibia, c


def full_rows(stage) -> list[dict]:
    """The rows of ``full_correction.csv`` (:data:`FULL_CORRECTION_COLUMNS`): each
    ``full_ipopt`` calibration of an :class:`~pipeline.reproduce.wang2023.imc.ImcStage`."""
    sex = {s["subject_id"]: s["sex"] for s in stage.subjects}
    angle = lambda A, B: float(np.degrees(np.linalg.norm(log3(A.T @ B))))  # noqa: E731
    return [
        dict(
            subject_id=sid, sex=sex[sid], tibia_input=tibia_input, status=c.status,
            iterations=c.iterations, seconds=c.seconds, hinge_rms_deg=np.degrees(c.hinge_rms),
            rest_closed_form_deg=c.rest_deg[0], rest_deg=c.rest_deg[1],
            plane_closed_form_mm=1e3 * c.plane_rms[0], plane_mm=1e3 * c.plane_rms[1],
            femur_deg=angle(c.R_start_femur, c.R_co_femur),
            tibia_deg=angle(c.R_start_tibia, c.R_co_tibia),
        )
        for (sid, tibia_input), c in stage.full_corrections.items()
    ]
