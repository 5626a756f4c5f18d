r"""Knee-AoR orientation correction over the whole trial as an IPOPT NLP (CasADi ``nlpsol``).

Wang et al. 2023 correct the IMC femur and tibia frames by right-multiplied constant rotations
(eq 13, ``e = ê R_co``) that carry the knee axis seen by the IMC onto a reference axis (eq 9-12,
:func:`pipeline.calibration.aor.correction_rotations`). That closed form sees the axis only through
the frame pairs of eq 2 and their angle-weighted mean. Here the same correction is the solution of
one smooth NLP over every sample.

**Hinge residual.** With ``M_k = ê_F^kᵀ ê_T^k`` the measured relative rotation (eq 1), a hinge knee
with axis ``b_F`` in the (corrected) femoral frame and ``b_T`` in the tibial frame satisfies, at
every sample, ``C_Fᵀ M_k C_T b_T = b_F``. This is the model's hinge (``pipeline.model``, knee
``'hinge'``: ``R_Fᵀ R_T = R0(b) Rot(-b_T, θ)`` with ``R0(b) b_T = b_F``) with the knee angle
``θ_k`` eliminated: a rotation maps ``b_T`` to ``b_F`` iff it is ``R0(b) Rot(b_T, ·)``. Residual
``r_k = C_Fᵀ M_k C_T b_T - b_F``, ``|r_k| = 2 sin(ε_k / 2)`` for the angle ``ε_k`` by which the
sample misses the hinge.

**What the data can see.** ``|r_k| = |M_k u - v|`` depends on the correction only through
``u = C_T b_T`` and ``v = C_F b_F``, the knee axis as seen in the *uncorrected* IMC tibia and
femur frames. For ``M_k = M_0 Rot(u*, θ_k)`` with a varying ``θ_k`` the residual vanishes iff
``u = ±u*`` and ``v = M_0 u``: the trial determines 4 numbers (two directions). The 6 + 4
unknowns ``C_F, C_T, b_F, b_T`` are fixed by two more terms:

* population prior (weight ``λ_p``): ``|β_F|² + |β_T|²``, the squared angles between the individual
  axes ``b = exp(β) a`` (``β ⟂ a``) and the reference axes ``a_F, a_T`` (population or individual
  OMC AoR);
* minimal correction (weight ``λ_c``): ``(3 - tr C_F) + (3 - tr C_T) = Σ 2 (1 - cos ϑ) ≈ ϑ²``, the
  squared correction angles. It fixes the rotation of each ``C`` about its axis, which the data
  cannot see (the smallest rotation carrying ``a`` onto ``u`` wins, as in eq 10-12), and says how
  a discrepancy between data and reference is shared: to first order a fraction
  ``λ_p / (λ_p + λ_c)`` of it is blamed on the sensors (corrected) and the rest on the subject's
  anatomy (kept in ``b``), the ratio of the variances ``σ_sensor² / σ_anatomy²``.

So ``prior_weight = inf`` (or ≫ ``λ_c``) gives corrected axes equal to the reference exactly
(Wang's assumption, estimated from all samples); ``prior_weight = 0`` leaves the data's axes and
no correction (``C = I``). The default ``λ_p = 1``, ``λ_c = 1e-6`` is Wang's assumption softened by
1e-6; ``λ_c`` must stay small against the data term's curvature (≈ 2 × the excitation below) so
the regulariser does not bias the observable part (the bias is ≈ ``λ_c / (2 excitation)`` times
the correction angle).

**Cost.** ``J = Σ_k w_k ρ(|r_k|²) / Σ_k w_k + λ_p Σ|β|² + λ_c Σ(3 - tr C)`` with
``ρ(e) = e`` (``'l2'``), ``2s² (sqrt(1 + e/s²) - 1)`` (``'huber'``, pseudo-Huber) or
``s² log(1 + e/s²)`` (``'cauchy'``), ``s = loss_scale``. For ``'l2'`` the data term is
exactly ``2 - 2 vᵀ S u`` with ``S = Σ w_k M_k / Σ w_k`` (``|u| = |v| = 1``), so the NLP does not
grow with the trial. ``S``'s singular values give the excitation ``1 - σ₂/σ₁`` (0 for a still
knee: the axis is then undetermined and only the prior and the regulariser define the result).

**Sample weights** (``weights='motion'``, :func:`~pipeline.calibration.hinge_fit.motion_weights`):
``w_k = φ_k / (φ_k + φ_0)`` with ``φ_k`` the knee rotation over ``motion_window`` s around sample
``k`` (a still knee adds no axis information); ``'uniform'`` or an array can be given instead.
The data term alone, in closed form, is :func:`~pipeline.calibration.hinge_fit.hinge_fit`.

**Parameterisation** (DESIGN.md §4, on-manifold): ``C = R0 exp(δ)`` around the closed-form start
``R0`` (:func:`~pipeline.calibration.aor.correction_rotations` from
:func:`~pipeline.calibration.aor.knee_aor` on the IMC frames, eq 9-12); ``b = exp(β₁t₁ + β₂t₂) a``
with ``t₁, t₂`` an orthonormal basis ⟂ ``a``. Ten unknowns, exact Hessian (CasADi: SX for
``'l2'``; a per-sample SX function mapped over the trial inside MX for the robust losses), IPOPT.
Measured on a 3000-sample trial: ``'l2'`` ~0.01 s in IPOPT (~0.03 s per call), robust losses
~0.3 s (~0.9 s on the first call for a trial length, which builds the solver).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from pipeline.calibration.aor import KneeAoR, correction_rotations, measured_aor
from pipeline.calibration.hinge_fit import (
    hinge_fit,
    relative_rotations,
    sample_weights,
)
from pipeline.calibration.losses import check_loss, hinge_sample_cost
from pipeline.errors import InputError
from pipeline.model.casadi_kinematics import exp3_sym
from pipeline.rotations import angle_between, normalize, tangent_basis

__all__ = [
    "AorCorrection",
    "aor_correction_ipopt",
]



@dataclass(frozen=True)
class AorCorrection:
    """Result of :func:`aor_correction_ipopt`; apply with ``e = ê @ R_co_*`` (eq 13).

    ``femur_axis`` / ``tibia_axis``: the individual knee axes ``b`` in the corrected frames.
    ``R_start_*``: the closed-form corrections (eq 9-12) IPOPT started from.
    ``residual_rms_*`` (rad): RMS over the valid samples of the angle between
    ``C_Fᵀ M_k C_T a_T`` and ``a_F`` (reference axes) with no correction (``before``), the
    closed form, and the IPOPT correction (``after``); ``residual_rms_fit`` the same with the
    estimated axes ``b``. ``seconds``: wall time of the call; ``solver_seconds``: IPOPT alone.
    """

    R_co_femur: np.ndarray
    R_co_tibia: np.ndarray
    femur_axis: np.ndarray
    tibia_axis: np.ndarray
    R_start_femur: np.ndarray
    R_start_tibia: np.ndarray
    cost: float
    iterations: int
    seconds: float
    solver_seconds: float
    status: str
    success: bool
    residual_rms_before: float
    residual_rms_closed_form: float
    residual_rms_after: float
    residual_rms_fit: float
    excitation: float
    n_samples: int
    weights: np.ndarray


# --------------------------------------------------------------------------------------------
# inputs


# --------------------------------------------------------------------------------------------
# the NLP


# Layout of the unknowns x: the rotation vectors of the femur and tibia corrections (around their
# starting values R0F, R0T) and the 2-D tangent offsets of the femoral and tibial AoRs.
X_CORRECTION_FEMUR, X_CORRECTION_TIBIA = slice(0, 3), slice(3, 6)
X_AXIS_FEMUR, X_AXIS_TIBIA, X_AXES = slice(6, 8), slice(8, 10), slice(6, 10)
NX = 10
# Layout of the geometry parameters p: R0F, R0T (3x3, column-major), the reference AoRs aF, aT and
# their tangent bases TF, TT (3x2, column-major). Each solver appends its data after them.
P_R0F, P_R0T, P_AF, P_AT = slice(0, 9), slice(9, 18), slice(18, 21), slice(21, 24)
P_TF, P_TT = slice(24, 30), slice(30, 36)
NP_GEOMETRY = 36
N_REGULARISER_WEIGHTS = 2


def _axes_sym(x, p):
    """Symbolic C_F, C_T, b_F, b_T from the unknowns x (:data:`NX`) and the geometry parameters."""
    R0F, R0T = ca.reshape(p[P_R0F], 3, 3), ca.reshape(p[P_R0T], 3, 3)
    aF, aT = p[P_AF], p[P_AT]
    TF, TT = ca.reshape(p[P_TF], 3, 2), ca.reshape(p[P_TT], 3, 2)
    CF = ca.mtimes(R0F, exp3_sym(x[X_CORRECTION_FEMUR]))
    CT = ca.mtimes(R0T, exp3_sym(x[X_CORRECTION_TIBIA]))
    bF = ca.mtimes(exp3_sym(ca.mtimes(TF, x[X_AXIS_FEMUR])), aF)
    bT = ca.mtimes(exp3_sym(ca.mtimes(TT, x[X_AXIS_TIBIA])), aT)
    return CF, CT, bF, bT


def _regularisers(x, CF, CT, weights):
    prior = weights[0] * ca.sumsqr(x[X_AXES])
    corr = weights[1] * ((3 - ca.trace(CF)) + (3 - ca.trace(CT)))
    return prior + corr


_OPTS = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}}


@lru_cache(maxsize=4)
def _l2_solver(max_iter: int, tol: float) -> ca.Function:
    """Data term ``2 - 2 vᵀ S u``: parameters = (geometry, 9 S, 2 weights)."""
    g = NP_GEOMETRY
    x, p = ca.SX.sym("x", NX), ca.SX.sym("p", g + 9 + N_REGULARISER_WEIGHTS)
    CF, CT, bF, bT = _axes_sym(x, p)
    S = ca.reshape(p[g : g + 9], 3, 3)
    u, v = ca.mtimes(CT, bT), ca.mtimes(CF, bF)
    f = 2 - 2 * ca.mtimes(v.T, ca.mtimes(S, u)) + _regularisers(x, CF, CT, p[g + 9 :])
    opts = {**_OPTS, "ipopt": {**_OPTS["ipopt"], "max_iter": max_iter, "tol": tol}}
    return ca.nlpsol("aor_l2", "ipopt", {"x": x, "p": p, "f": f}, opts)


@lru_cache(maxsize=4)
def _robust_solver(n: int, kind: str, scale: float, max_iter: int, tol: float) -> ca.Function:
    """Per-sample data term (MX, mapped): parameters = (geometry, 9n M_k, n weights, 2)."""
    g = NP_GEOMETRY
    x, p = ca.MX.sym("x", NX), ca.MX.sym("p", g + 10 * n + N_REGULARISER_WEIGHTS)
    CF, CT, bF, bT = _axes_sym(x, p)
    u, v = ca.mtimes(CT, bT), ca.mtimes(CF, bF)
    m = ca.reshape(p[g : g + 9 * n], 9, n)
    w = p[g + 9 * n : g + 10 * n]
    terms = hinge_sample_cost(kind, scale).map(n)(u, v, m, w.T)
    f = ca.sum2(terms) / ca.sum1(w) + _regularisers(x, CF, CT, p[g + 10 * n :])
    opts = {**_OPTS, "ipopt": {**_OPTS["ipopt"], "max_iter": max_iter, "tol": tol}}
    return ca.nlpsol(f"aor_{kind}", "ipopt", {"x": x, "p": p, "f": f}, opts)


def _residual_angles(M, CF, CT, aF, aT) -> np.ndarray:
    pred = np.einsum("ij,njk,k->ni", CF.T, M, CT @ aT)
    return angle_between(pred, aF)


def aor_correction_ipopt(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    reference_femur_axis: np.ndarray,
    reference_tibia_axis: np.ndarray,
    *,
    prior_weight: float = 1.0,
    correction_weight: float = 1e-6,
    loss: str = "l2",
    loss_scale: float = np.deg2rad(3.0),
    weights: str | np.ndarray = "motion",
    rate_hz: float = 100.0,
    motion_window: float = 0.5,
    static_speed: float = np.deg2rad(10.0),
    start: KneeAoR | None = None,
    max_iter: int = 200,
    tol: float = 1e-12,
    **aor_kwargs: object,
) -> AorCorrection:
    """Constant corrections ``(C_F, C_T)`` of IMC femur/tibia frames from the whole trial.

    Args:
        femur_R, tibia_R: IMC segment orientations ``(N, 3, 3)``; NaN rows are skipped.
        reference_femur_axis, reference_tibia_axis: reference knee AoR (population or
            individual, e.g. :func:`pipeline.model.skeleton.knee_axis` of the subject's model);
            pointing right.
        prior_weight: ``λ_p`` (``np.inf`` fixes ``b = a``); correction_weight: ``λ_c``.
        loss: ``'l2'``, ``'huber'`` or ``'cauchy'``; loss_scale: ``s`` (rad of hinge miss).
        weights: ``'motion'`` (default), ``'uniform'`` or an array ``(N,)``.
        start: the IMC AoR for the closed-form start (default :func:`knee_aor` on the inputs
            with ``aor_kwargs``; if that finds no usable pair the SVD axes of ``S`` are used).

    The math, and what it can and cannot observe, is in the module docstring.
    """
    t0 = time.perf_counter()
    check_loss(loss)
    if not (prior_weight >= 0 and correction_weight >= 0):
        raise InputError(
            f"expected weights >= 0, got prior {prior_weight}, correction {correction_weight}"
        )
    M, valid = relative_rotations(femur_R, tibia_R)
    aF = normalize(np.asarray(reference_femur_axis, float))
    aT = normalize(np.asarray(reference_tibia_axis, float))
    w = sample_weights(femur_R, tibia_R, weights, valid, rate_hz, motion_window, static_speed)
    fit = hinge_fit(femur_R, tibia_R, w, rate_hz, motion_window, static_speed)
    S, excitation = fit.mean_relative_rotation, fit.excitation

    if start is None:
        start = measured_aor(femur_R, tibia_R, (fit.femur_axis, fit.tibia_axis), **aor_kwargs)
    R0F, R0T = correction_rotations(start, aF, aT)

    TF, TT = tangent_basis(aF), tangent_basis(aT)
    geom = np.concatenate([R0F.ravel("F"), R0T.ravel("F"), aF, aT, TF.ravel("F"), TT.ravel("F")])
    fixed_prior = np.isinf(prior_weight)
    lam = np.array([0.0 if fixed_prior else prior_weight, correction_weight])
    keep = w > 0
    if loss == "l2":
        solver = _l2_solver(max_iter, tol)
        p = np.concatenate([geom, S.ravel("F"), lam])
    else:
        n = int(keep.sum())
        solver = _robust_solver(n, loss, float(loss_scale), max_iter, tol)
        m = np.swapaxes(M[keep], 1, 2).reshape(n, 9)  # column-major entries of each M_k
        p = np.concatenate([geom, m.ravel(), w[keep], lam])
    lbx, ubx = -np.inf * np.ones(NX), np.inf * np.ones(NX)
    if fixed_prior:
        lbx[X_AXES], ubx[X_AXES] = 0.0, 0.0
    t1 = time.perf_counter()
    sol = solver(x0=np.zeros(NX), p=p, lbx=lbx, ubx=ubx)
    solver_seconds = time.perf_counter() - t1
    stats = solver.stats()
    x = np.array(sol["x"]).ravel()
    CF, CT, bF, bT = _evaluate(x, geom)

    res = lambda cf, ct, af, at: float(  # noqa: E731
        np.sqrt(np.mean(_residual_angles(M[valid], cf, ct, af, at) ** 2))
    )
    I3 = np.eye(3)
    return AorCorrection(
        R_co_femur=CF,
        R_co_tibia=CT,
        femur_axis=bF,
        tibia_axis=bT,
        R_start_femur=R0F,
        R_start_tibia=R0T,
        cost=float(sol["f"]),
        iterations=int(stats["iter_count"]),
        seconds=time.perf_counter() - t0,
        solver_seconds=solver_seconds,
        status=str(stats["return_status"]),
        success=bool(stats["success"]),
        residual_rms_before=res(I3, I3, aF, aT),
        residual_rms_closed_form=res(R0F, R0T, aF, aT),
        residual_rms_after=res(CF, CT, aF, aT),
        residual_rms_fit=res(CF, CT, bF, bT),
        excitation=excitation,
        n_samples=int(keep.sum()),
        weights=w,
    )


@lru_cache(maxsize=1)
def _evaluator() -> ca.Function:
    x, p = ca.SX.sym("x", NX), ca.SX.sym("p", NP_GEOMETRY)
    return ca.Function("axes", [x, p], list(_axes_sym(x, p)))


def _evaluate(x: np.ndarray, geom: np.ndarray) -> tuple[np.ndarray, ...]:
    CF, CT, bF, bT = (np.array(v) for v in _evaluator()(x, geom))
    return CF, CT, bF.ravel(), bT.ravel()
