r"""Whole-trial hinge axes of the knee in closed form, and motion-based sample weights.

With ``M_k = ê_F^kᵀ ê_T^k`` the measured relative rotation of femur and tibia (Wang et al. 2023,
eq 1), a hinge knee with axis ``u`` in the tibial frame and ``v`` in the femoral frame satisfies
``M_k u = v`` at every sample. The least-squares axes minimise ``Σ_k w_k |M_k u - v|²`` over unit
``u``, ``v``; since ``|M u - v|² = 2 - 2 vᵀ M u``, they are the top singular pair of
``S = Σ_k w_k M_k / Σ_k w_k`` (``S u = σ₁ v``). ``S``'s singular values give the excitation
``1 - σ₂/σ₁`` (0 for a still knee: the axis is then undetermined). A whole-trial alternative to
Wang eq 1-8 (use the same estimator for a reference AoR and for the IMC data); it is the data term
of :func:`pipeline.calibration.aor_ipopt.aor_correction_ipopt`.

**Sample weights** (``weights='motion'``): a still knee adds no axis information (and in real data
rests are where posture-specific errors sit), so ``w_k = φ_k / (φ_k + φ_0)`` with ``φ_k`` the knee
rotation angle between samples ``k - h`` and ``k + h`` (``h = motion_window / 2`` s) and ``φ_0 =
static_speed · motion_window``. ``'uniform'`` or an array of weights can be given instead.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import log3

__all__ = ["HingeFit", "hinge_fit", "motion_weights", "relative_rotations", "sample_weights"]


def relative_rotations(femur_R: np.ndarray, tibia_R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``M_k = F_kᵀ T_k`` (eq 1), identity where a sample is missing, and the validity mask."""
    F = np.asarray(femur_R, dtype=float)
    T = np.asarray(tibia_R, dtype=float)
    if F.ndim != 3 or F.shape[1:] != (3, 3) or F.shape != T.shape:
        raise InputError(
            f"expected femur and tibia orientations of shape (N, 3, 3), got {F.shape}, {T.shape}"
        )
    valid = np.all(np.isfinite(F), axis=(1, 2)) & np.all(np.isfinite(T), axis=(1, 2))
    M = np.where(valid[:, None, None], np.swapaxes(F, 1, 2) @ T, np.eye(3))
    return M, valid


def motion_weights(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    rate_hz: float = 100.0,
    motion_window: float = 0.5,
    static_speed: float = np.deg2rad(10.0),
) -> np.ndarray:
    """``w_k = φ_k / (φ_k + φ_0)``: knee rotation ``φ_k`` between samples ``k ∓ h`` (module doc).

    ``h = round(motion_window * rate_hz / 2)`` samples (clipped at the ends), ``φ_0 =
    static_speed * motion_window`` rad. Zero where a sample is missing.
    """
    M, valid = relative_rotations(femur_R, tibia_R)
    n = len(M)
    h = max(1, int(round(motion_window * rate_hz / 2)))
    k = np.arange(n)
    lo, hi = np.clip(k - h, 0, n - 1), np.clip(k + h, 0, n - 1)
    phi = np.linalg.norm(log3(np.swapaxes(M[lo], 1, 2) @ M[hi]), axis=1)
    phi0 = static_speed * motion_window
    w = phi / (phi + phi0)
    return np.where(valid & valid[lo] & valid[hi], w, 0.0)


@dataclass(frozen=True)
class HingeFit:
    """Whole-trial least-squares hinge axes (unit, pointing right) and the excitation."""

    femur_axis: np.ndarray
    tibia_axis: np.ndarray
    excitation: float
    mean_relative_rotation: np.ndarray


def sample_weights(femur_R, tibia_R, weights, valid, rate_hz, motion_window, static_speed):
    """Sample weights from ``'motion'``, ``'uniform'`` or an array; zero where not ``valid``."""
    n = len(valid)
    if isinstance(weights, str):
        if weights == "motion":
            return motion_weights(femur_R, tibia_R, rate_hz, motion_window, static_speed)
        if weights == "uniform":
            return valid.astype(float)
        raise InputError(f"expected weights 'motion', 'uniform' or an array, got {weights!r}")
    w = np.asarray(weights, dtype=float)
    if w.shape != (n,) or np.any(~np.isfinite(w)) or np.any(w < 0):
        raise InputError(f"expected {n} finite weights >= 0", field="weights")
    return np.where(valid, w, 0.0)


def hinge_fit(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    weights: str | np.ndarray = "motion",
    rate_hz: float = 100.0,
    motion_window: float = 0.5,
    static_speed: float = np.deg2rad(10.0),
) -> HingeFit:
    """Knee axes minimising ``Σ w_k |M_k u - v|²`` over unit ``u`` (tibia), ``v`` (femur).

    The data term of :func:`~pipeline.calibration.aor_ipopt.aor_correction_ipopt` alone: since
    ``|M u - v|² = 2 - 2 vᵀ M u``, the minimiser is the top singular pair of
    ``S = Σ w_k M_k / Σ w_k`` (``S u = σ₁ v``); the excitation ``1 - σ₂/σ₁`` is 0 when the knee
    does not move. A whole-trial alternative to Wang eq 1-8 (use the same estimator for a
    reference AoR and for the IMC data).
    """
    M, valid = relative_rotations(femur_R, tibia_R)
    w = sample_weights(femur_R, tibia_R, weights, valid, rate_hz, motion_window, static_speed)
    if w.sum() <= 0:
        raise InputError("no valid sample with a positive weight (knee never moves?)")
    S = np.einsum("n,nij->ij", w, M) / w.sum()
    U, sv, Vt = np.linalg.svd(S)
    sign = 1.0 if U[2, 0] >= 0 else -1.0
    return HingeFit(sign * U[:, 0], sign * Vt[0], float(1 - sv[1] / sv[0]), S)
