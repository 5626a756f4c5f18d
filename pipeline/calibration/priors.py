"""Population priors of a knee for the IMU-only full correction
(:mod:`pipeline.calibration.full_correction`), learned from optical recordings of other subjects:
the mean knee AoR and its spread, the knee's anatomical rotation at rest and its covariance, how
far real knees miss a hinge, and how far knee and ankle leave the motion's plane through the hip.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pipeline.calibration.aor import KneeAoR
from pipeline.calibration.hinge_fit import relative_rotations
from pipeline.calibration.placement import mean_rotation
from pipeline.errors import InputError
from pipeline.rotations import angle_between, normalize

__all__ = [
    "REST_SAMPLES",
    "CorrectionPriors",
    "KneeTrial",
    "correction_priors",
    "rest_error",
    "rest_rotation",
]

#: Samples at the start of a trial taken as the rest posture (0.2 s at 100 Hz).
REST_SAMPLES = 20


@dataclass(frozen=True)
class KneeTrial:
    """One subject's optical knee, for :func:`correction_priors`: anatomical femur and tibia
    orientations ``(N, 3, 3)`` (NaN rows allowed), the subject's knee AoR (eq 1-8) and the knee
    and ankle centres relative to the hip ``(N, 3)`` (m), in the same world. The trial starts at
    rest in the posture the corrected trials start in."""

    femur_R: np.ndarray
    tibia_R: np.ndarray
    knee_aor: KneeAoR
    knee_path: np.ndarray
    ankle_path: np.ndarray


@dataclass(frozen=True)
class CorrectionPriors:
    """What a population says about a knee, for
    :func:`~pipeline.calibration.full_correction.full_correction_ipopt`.

    ``femur_axis`` / ``tibia_axis``: mean knee AoR (unit, pointing right) in the anatomical
    frames; ``sd_femur_axis`` / ``sd_tibia_axis``: RMS angle of the subjects' AoRs from it (rad).
    ``rest_knee``: mean anatomical knee rotation ``E_Fᵀ E_T`` over the first rest samples;
    ``rest_knee_cov``: covariance of ``vee(E - Eᵀ)/2`` of ``rest_knee_meanᵀ K₀`` over subjects
    (rad²). ``hinge_sd``: RMS angle by which the subjects' knees miss a hinge about their own AoR
    (rad). ``plane_sd``: RMS distance of knee and ankle centres from the best plane through the
    hip (m).
    """

    femur_axis: np.ndarray
    tibia_axis: np.ndarray
    sd_femur_axis: float
    sd_tibia_axis: float
    rest_knee: np.ndarray
    rest_knee_cov: np.ndarray
    hinge_sd: float
    plane_sd: float
    n_subjects: int


def rest_error(R: np.ndarray) -> np.ndarray:
    """``vee(R - Rᵀ) / 2 = sin θ · axis`` of a rotation (or stack): the rest-pose residual."""
    R = np.asarray(R, dtype=float)
    return 0.5 * np.stack(
        [R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]],
        axis=-1,
    )


def rest_rotation(femur_R: np.ndarray, tibia_R: np.ndarray, n: int) -> np.ndarray:
    """Mean relative rotation ``E_Fᵀ E_T`` over the first ``n`` samples where both are finite."""
    M, valid = relative_rotations(femur_R, tibia_R)
    idx = np.flatnonzero(valid)[:n]
    if len(idx) == 0:
        raise InputError("no sample with both femur and tibia orientations", field="rest")
    return mean_rotation(M[idx])


def _plane_rms(points: np.ndarray) -> float:
    """RMS distance of ``points`` (hip-centred) from their least-squares plane through the hip."""
    p = points[np.all(np.isfinite(points), axis=1)]
    s = np.linalg.svd(p, compute_uv=False)
    return float(s[2] / np.sqrt(len(p)))


def correction_priors(
    trials: Sequence[KneeTrial], rest_samples: int = REST_SAMPLES
) -> CorrectionPriors:
    """The population priors of
    :func:`~pipeline.calibration.full_correction.full_correction_ipopt` from optical knees.

    Fit them without the subject to be corrected (leave-one-subject-out) so that none of its own
    optical data reaches its correction.
    """
    if len(trials) < 2:
        raise InputError(f"priors need at least two subjects, got {len(trials)}", field="trials")
    aF = np.stack([t.knee_aor.femur_axis for t in trials])
    aT = np.stack([t.knee_aor.tibia_axis for t in trials])
    mF, mT = normalize(aF.mean(axis=0)), normalize(aT.mean(axis=0))
    rest = np.stack([rest_rotation(t.femur_R, t.tibia_R, rest_samples) for t in trials])
    K0 = mean_rotation(rest)
    e = rest_error(np.einsum("ji,njk->nik", K0, rest))
    hinge = []
    for t in trials:
        M, valid = relative_rotations(t.femur_R, t.tibia_R)
        miss = angle_between(M[valid] @ t.knee_aor.tibia_axis, t.knee_aor.femur_axis)
        hinge.append(np.mean(miss**2))
    plane = [_plane_rms(np.concatenate([t.knee_path, t.ankle_path])) for t in trials]
    return CorrectionPriors(
        femur_axis=mF, tibia_axis=mT,
        sd_femur_axis=float(np.sqrt(np.mean(angle_between(aF, mF) ** 2))),
        sd_tibia_axis=float(np.sqrt(np.mean(angle_between(aT, mT) ** 2))),
        rest_knee=K0, rest_knee_cov=np.cov(e.T), hinge_sd=float(np.sqrt(np.mean(hinge))),
        plane_sd=float(np.sqrt(np.mean(np.square(plane)))), n_subjects=len(trials),
    )
