r"""Full sensor-to-segment correction of femur and tibia from IMU orientations alone: one IPOPT
NLP over the whole trial (CasADi ``nlpsol``).

Wang et al. 2023 correct the IMC femur and tibia frames by constant right-multiplied rotations
(eq 13, ``e = ê C``) that carry the knee AoR seen by the IMC onto a reference AoR (eq 9-12). An
axis fixes two of each rotation's three degrees of freedom; the third, the rotation of each
segment about the knee axis, is left where the smallest rotation puts it, and with it the knee's
flexion offset (:mod:`pipeline.calibration.aor_ipopt` shows what the hinge data can and cannot
see). Here both corrections are full rotations (3 DoF each, on the manifold) and the missing
information comes from what an IMU-only user has besides the hinge: the population's knee at
rest and the plane of the motion, with the hip as the common centre.

**Unknowns** (11): ``C_F = R0_F exp(δ_F)``, ``C_T = R0_T exp(δ_T)`` around the closed form
(eq 9-12 towards the prior axes), ``δ_F ⟂ a_F`` (2 DoF, below) and ``δ_T`` free (3 DoF); the
subject's knee axes ``b = exp(β₁t₁ + β₂t₂) a`` around the
prior axes ``a`` (``t ⟂ a``); the normal of the motion plane ``n = exp(ν₁s₁ + ν₂s₂) n₀`` in the
IMC world (``n₀``: plane of the closed-form paths).

**Cost** ``J = J_hinge + J_axis + J_rest + J_plane + J_gauge``:

* hinge (eq 1-8's relative rotations ``M_k = ê_F^kᵀ ê_T^k``, every sample):
  ``J_hinge = Σ w_k ρ(|C_Fᵀ M_k C_T b_T - b_F|²) / (σ_h² Σ w_k)``; ``|·| = 2 sin(ε_k/2)`` for the
  angle ``ε_k`` by which sample ``k`` misses a hinge about ``b``; ``ρ`` a robust loss
  (:mod:`pipeline.calibration.losses`), ``w_k`` the motion weights of
  :func:`~pipeline.calibration.hinge_fit.motion_weights`;
* axis prior: ``J_axis = |β_F|²/σ_F² + |β_T|²/σ_T²``, the squared angles of the subject's axes
  from the population's over the population's spread;
* rest pose: ``J_rest = eᵀ Σ₀⁻¹ e``, ``e = vee(E - Eᵀ)/2`` (``= sin θ · axis``) of
  ``E = K̄₀ᵀ C_Fᵀ M̄₀ C_T``, with ``M̄₀`` the mean relative rotation over the rest samples (the
  subject lying still, knee extended) and ``K̄₀``, ``Σ₀`` the population's anatomical knee
  rotation in that posture and its covariance. With the axes aligned this fixes the knee's
  flexion offset (``C_Fᵀ M̄₀ C_T`` maps ``b_T`` onto ``b_F``, so only the angle about it is left);
  the other two components weigh in on the axes;
* motion plane (the hip as the centre of a sagittal motion): ``J_plane = Σ_j v_j [(nᵀ κ_j)² +
  (nᵀ α_j)²] / (2 σ_p² Σ v_j)`` with ``κ_j = ê_F^j C_F p_KJC`` and ``α_j = κ_j + ê_T^j C_T p_AJC``
  the knee and ankle centres relative to the hip (eq 15-17 with the model's landmark positions),
  i.e. knee and ankle stay in one plane through the hip. It fixes the tibia's out-of-plane
  orientation, which neither the axis nor the rest pose sees well;
* gauge: turning both segments together about the knee axis changes none of the terms above
  for a planar motion (the IMC world's heading and tilt are unknown, so nothing says where the
  femur points within the plane). The femur's rotation about the knee axis is therefore kept
  at the closed form's (the smallest rotation, as eq 10-12 do: ``δ_F ⟂ a_F``); the tibia's,
  relative to it, is the knee's flexion offset, which the rest pose fixes. A small
  ``λ_c [(3 - tr exp δ_F) + (3 - tr exp δ_T)]`` (``≈ λ_c Σ ϑ²``) keeps the remaining flat
  directions at the smallest correction. (With ``δ_F`` free the solver wandered up to 164 deg
  along the flat direction on the Wang data, leaving the trajectories unchanged and the
  orientations meaningless.)

The scales ``σ_h``, ``σ_F``, ``σ_T``, ``Σ₀``, ``σ_p`` are the population's own spreads
(:func:`pipeline.calibration.priors.correction_priors`), so each term counts as the evidence it
is; none is tuned on the result. ``C`` applies as eq 13 does: ``e = ê C``.

**Sizes.** The hinge term uses at most ``max_hinge_samples`` evenly spaced samples and the plane
term ``max_plane_samples``; shorter trials are padded with zero weights, so one solver (built
once per process, ~1 s) serves every trial. Exact Hessian, IPOPT.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from pipeline.calibration.aor import correction_rotations, measured_aor
from pipeline.calibration.hinge_fit import hinge_fit, relative_rotations, sample_weights
from pipeline.calibration.losses import check_loss, hinge_sample_cost
from pipeline.calibration.priors import REST_SAMPLES, CorrectionPriors, rest_error, rest_rotation
from pipeline.errors import InputError
from pipeline.model.casadi_kinematics import exp3_sym
from pipeline.rotations import angle_between, tangent_basis

__all__ = ["FullCorrection", "full_correction_ipopt"]


# --------------------------------------------------------------------------------------------
# the NLP


@dataclass(frozen=True)
class FullCorrection:
    """Result of :func:`full_correction_ipopt`; apply with ``e = ê @ R_co_*`` (eq 13).

    ``femur_axis`` / ``tibia_axis``: the subject's knee axes ``b`` in the corrected frames;
    ``plane_normal``: the motion plane's normal in the IMC world; ``R_start_*``: the closed form
    (eq 9-12) IPOPT started from. ``terms``: the cost's parts at the solution (``hinge``,
    ``axis``, ``rest``, ``plane``, ``gauge``). ``hinge_rms`` (rad): RMS angle by which the
    corrected samples miss the hinge about ``b``; ``rest_deg``: the rest-pose residual
    ``asin|e|`` (deg) after the closed form and after IPOPT; ``plane_rms`` (m): RMS distance of
    knee and ankle centres from the plane, closed form and IPOPT. ``seconds``: wall time of the
    call; ``solver_seconds``: IPOPT alone.
    """

    R_co_femur: np.ndarray
    R_co_tibia: np.ndarray
    femur_axis: np.ndarray
    tibia_axis: np.ndarray
    plane_normal: np.ndarray
    R_start_femur: np.ndarray
    R_start_tibia: np.ndarray
    cost: float
    terms: dict
    hinge_rms: float
    rest_deg: tuple[float, float]
    plane_rms: tuple[float, float]
    iterations: int
    status: str
    success: bool
    seconds: float
    solver_seconds: float
    n_hinge_samples: int
    n_plane_samples: int


# Unknowns x: the femur's correction as a tangent offset ⟂ a_F and the tibia's as a rotation
# vector (around R0_F, R0_T); tangent offsets of b_F, b_T and n.
X_CF, X_CT, X_BF, X_BT, X_N = slice(0, 2), slice(2, 5), slice(5, 7), slice(7, 9), slice(9, 11)
NX = 11
# Parameters p: the fixed geometry, then the term scales, then the hinge and plane samples.
_GEOMETRY = (("R0F", 9), ("R0T", 9), ("aF", 3), ("aT", 3), ("TF", 6), ("TT", 6), ("n0", 3),
             ("TN", 6), ("K0", 9), ("S0inv", 9), ("M0", 9), ("pK", 3), ("pA", 3),
             ("scales", 5))
_OFFSETS = {}
_n = 0
for _name, _size in _GEOMETRY:
    _OFFSETS[_name] = slice(_n, _n + _size)
    _n += _size
NP_GEOMETRY = _n
_OPTS = {"print_time": False, "ipopt": {"print_level": 0, "sb": "yes"}}


def _unknowns_sym(x, p):
    """Symbolic ``C_F, C_T, b_F, b_T, n`` from the unknowns and the geometry parameters
    (``δ_F = T_F x_F``: no rotation about the femoral axis)."""
    g = lambda name, rows=None: (  # noqa: E731
        p[_OFFSETS[name]] if rows is None else ca.reshape(p[_OFFSETS[name]], rows, -1)
    )
    CF = ca.mtimes(g("R0F", 3), exp3_sym(ca.mtimes(g("TF", 3), x[X_CF])))
    CT = ca.mtimes(g("R0T", 3), exp3_sym(x[X_CT]))
    bF = ca.mtimes(exp3_sym(ca.mtimes(g("TF", 3), x[X_BF])), g("aF"))
    bT = ca.mtimes(exp3_sym(ca.mtimes(g("TT", 3), x[X_BT])), g("aT"))
    n = ca.mtimes(exp3_sym(ca.mtimes(g("TN", 3), x[X_N])), g("n0"))
    return CF, CT, bF, bT, n


@lru_cache(maxsize=1)
def _plane_sample_cost() -> ca.Function:
    """``v [(nᵀ F cK)² + (nᵀ (F cK + T cA))²]`` of one sample (``F``, ``T`` column-major)."""
    n, cK, cA = ca.SX.sym("n", 3), ca.SX.sym("cK", 3), ca.SX.sym("cA", 3)
    f, t, v = ca.SX.sym("f", 9), ca.SX.sym("t", 9), ca.SX.sym("v")
    knee = ca.mtimes(ca.reshape(f, 3, 3), cK)
    ankle = knee + ca.mtimes(ca.reshape(t, 3, 3), cA)
    cost = v * (ca.dot(n, knee) ** 2 + ca.dot(n, ankle) ** 2)
    return ca.Function("plane_sample", [n, cK, cA, f, t, v], [cost])


def _vee_asym(E):
    return 0.5 * ca.vertcat(E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1])


def _cost_terms(x, p, nh: int, np_: int, loss: str, scale: float):
    """The five cost terms (module doc) as MX expressions."""
    CF, CT, bF, bT, n = _unknowns_sym(x, p)
    s = p[_OFFSETS["scales"]]  # 1/σ_h², 1/σ_F², 1/σ_T², 1/σ_p², λ_c
    g = NP_GEOMETRY
    m, w = ca.reshape(p[g : g + 9 * nh], 9, nh), p[g + 9 * nh : g + 10 * nh]
    o = g + 10 * nh
    f, t = ca.reshape(p[o : o + 9 * np_], 9, np_), ca.reshape(p[o + 9 * np_ : o + 18 * np_], 9, np_)
    v = p[o + 18 * np_ : o + 19 * np_]
    u_t, v_f = ca.mtimes(CT, bT), ca.mtimes(CF, bF)
    hinge = ca.sum2(hinge_sample_cost(loss, scale).map(nh)(u_t, v_f, m, w.T)) / ca.sum1(w)
    cK = ca.mtimes(CF, p[_OFFSETS["pK"]])
    cA = ca.mtimes(CT, p[_OFFSETS["pA"]])
    plane = ca.sum2(_plane_sample_cost().map(np_)(n, cK, cA, f, t, v.T)) / (2 * ca.sum1(v))
    K0 = ca.reshape(p[_OFFSETS["K0"]], 3, 3)
    M0 = ca.reshape(p[_OFFSETS["M0"]], 3, 3)
    e = _vee_asym(ca.mtimes([K0.T, CF.T, M0, CT]))
    rest = ca.mtimes([e.T, ca.reshape(p[_OFFSETS["S0inv"]], 3, 3), e])
    axis = s[1] * ca.sumsqr(x[X_BF]) + s[2] * ca.sumsqr(x[X_BT])
    R0F = ca.reshape(p[_OFFSETS["R0F"]], 3, 3)
    R0T = ca.reshape(p[_OFFSETS["R0T"]], 3, 3)
    # 3 - tr exp(δ) = 3 - tr(R0ᵀ C)
    gauge = s[4] * ((3 - ca.trace(ca.mtimes(R0F.T, CF))) + (3 - ca.trace(ca.mtimes(R0T.T, CT))))
    return {"hinge": s[0] * hinge, "axis": axis, "rest": rest, "plane": s[3] * plane,
            "gauge": gauge}


def _n_params(nh: int, np_: int) -> int:
    return NP_GEOMETRY + 10 * nh + 19 * np_


@lru_cache(maxsize=4)
def _solver(nh: int, np_: int, loss: str, scale: float, max_iter: int, tol: float):
    x, p = ca.MX.sym("x", NX), ca.MX.sym("p", _n_params(nh, np_))
    terms = _cost_terms(x, p, nh, np_, loss, scale)
    f = sum(terms.values())
    opts = {**_OPTS, "ipopt": {**_OPTS["ipopt"], "max_iter": max_iter, "tol": tol}}
    solver = ca.nlpsol(f"full_{loss}", "ipopt", {"x": x, "p": p, "f": f}, opts)
    parts = ca.Function("parts", [x, p], [*terms.values(), *_unknowns_sym(x, p)])
    return solver, parts


def _even(idx: np.ndarray, n: int) -> np.ndarray:
    """At most ``n`` evenly spaced entries of ``idx``."""
    if len(idx) <= n:
        return idx
    return idx[np.round(np.linspace(0, len(idx) - 1, n)).astype(int)]


def _colmajor(R: np.ndarray, n: int) -> np.ndarray:
    """``(k, 3, 3)`` rotations as ``n`` blocks of 9 column-major entries (CasADi's
    ``reshape(p, 9, n)`` order), padded with the identity."""
    out = np.tile(np.eye(3).ravel(), (n, 1))
    out[: len(R)] = np.swapaxes(R, 1, 2).reshape(len(R), 9)
    return out.ravel()


def _padded(values: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros(n)
    out[: len(values)] = values
    return out


def full_correction_ipopt(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    knee_centre: np.ndarray,
    ankle_centre: np.ndarray,
    priors: CorrectionPriors,
    *,
    loss: str = "huber",
    loss_scale: float = np.deg2rad(3.0),
    rest_samples: int = REST_SAMPLES,
    weights: str | np.ndarray = "motion",
    rate_hz: float = 100.0,
    motion_window: float = 0.5,
    static_speed: float = np.deg2rad(10.0),
    gauge_weight: float = 1e-4,
    max_hinge_samples: int = 1000,
    max_plane_samples: int = 300,
    max_iter: int = 200,
    tol: float = 1e-10,
) -> FullCorrection:
    """Constant full corrections ``(C_F, C_T)`` of IMU femur/tibia frames from the whole trial.

    Args:
        femur_R, tibia_R: segment orientations from the IMUs ``(N, 3, 3)`` in one world (any
            heading); NaN rows are skipped. The trial starts with ``rest_samples`` samples in the
            rest posture of the priors (supine, knee extended, for the Wang 2023 data).
        knee_centre: the knee centre in the femoral frame, hip at the origin (m);
        ankle_centre: the ankle centre in the tibial frame, knee centre at the origin (m): the
            model's landmark positions (e.g.
            :func:`pipeline.model.anthropometry.predict_landmarks`).
        priors: :func:`~pipeline.calibration.priors.correction_priors` of a population the
            subject is not part of.
        loss, loss_scale: robust loss of the hinge term and its scale (rad of hinge miss).
        weights: hinge sample weights, ``'motion'`` (default), ``'uniform'`` or ``(N,)``.
        gauge_weight: ``λ_c`` (module doc).

    The math is in the module docstring.
    """
    t0 = time.perf_counter()
    check_loss(loss)
    F, T = np.asarray(femur_R, dtype=float), np.asarray(tibia_R, dtype=float)
    M, valid = relative_rotations(F, T)
    w = sample_weights(F, T, weights, valid, rate_hz, motion_window, static_speed)
    fit = hinge_fit(F, T, w, rate_hz, motion_window, static_speed)
    start = measured_aor(F, T, (fit.femur_axis, fit.tibia_axis))
    aF, aT = priors.femur_axis, priors.tibia_axis
    R0F, R0T = correction_rotations(start, aF, aT)
    M0 = rest_rotation(F, T, rest_samples)
    pK = np.asarray(knee_centre, dtype=float)
    pA = np.asarray(ankle_centre, dtype=float)
    finite = np.isfinite(pK).all() and np.isfinite(pA).all()
    if pK.shape != (3,) or pA.shape != (3,) or not finite:
        raise InputError(
            f"expected finite 3-vectors, got knee {pK.tolist()}, ankle {pA.tolist()}",
            field="knee_centre/ankle_centre",
        )

    hinge_idx = _even(np.flatnonzero(w > 0), max_hinge_samples)
    plane_idx = _even(np.flatnonzero(valid), max_plane_samples)
    if len(hinge_idx) < 2 or len(plane_idx) < 3:
        raise InputError(
            f"need a moving knee: {len(hinge_idx)} weighted samples, {len(plane_idx)} valid",
            field="orientations",
        )
    # plane of the closed-form paths, through the hip, normal pointing right
    knee = F[plane_idx] @ (R0F @ pK)
    ankle = knee + T[plane_idx] @ (R0T @ pA)
    _, _, vt = np.linalg.svd(np.concatenate([knee, ankle]), full_matrices=False)
    n0 = vt[2] if vt[2] @ np.mean(F[plane_idx][:, :, 2], axis=0) > 0 else -vt[2]

    S0inv = np.linalg.inv(priors.rest_knee_cov)
    scales = np.array([priors.hinge_sd**-2, priors.sd_femur_axis**-2, priors.sd_tibia_axis**-2,
                       priors.plane_sd**-2, gauge_weight])
    geometry = {
        "R0F": R0F.ravel("F"), "R0T": R0T.ravel("F"), "aF": aF, "aT": aT,
        "TF": tangent_basis(aF).ravel("F"), "TT": tangent_basis(aT).ravel("F"), "n0": n0,
        "TN": tangent_basis(n0).ravel("F"), "K0": priors.rest_knee.ravel("F"),
        "S0inv": S0inv.ravel("F"), "M0": M0.ravel("F"), "pK": pK, "pA": pA, "scales": scales,
    }
    nh, np_ = max_hinge_samples, max_plane_samples
    p = np.concatenate(
        [*(geometry[name] for name, _ in _GEOMETRY),
         _colmajor(M[hinge_idx], nh), _padded(w[hinge_idx], nh),
         _colmajor(F[plane_idx], np_), _colmajor(T[plane_idx], np_),
         _padded(np.ones(len(plane_idx)), np_)]
    )
    solver, parts = _solver(nh, np_, loss, float(loss_scale), max_iter, tol)
    t1 = time.perf_counter()
    sol = solver(x0=np.zeros(NX), p=p)
    solver_seconds = time.perf_counter() - t1
    stats = solver.stats()
    x = np.array(sol["x"]).ravel()
    out = [np.array(v) for v in parts(x, p)]
    names = ("hinge", "axis", "rest", "plane", "gauge")
    terms = {k: float(v.item()) for k, v in zip(names, out[:5], strict=True)}
    CF, CT, bF, bT, n = out[5], out[6], out[7].ravel(), out[8].ravel(), out[9].ravel()

    def rest_deg(cf, ct):
        e = rest_error(priors.rest_knee.T @ cf.T @ M0 @ ct)
        return float(np.degrees(np.arcsin(min(1.0, np.linalg.norm(e)))))

    def plane_rms(cf, ct, normal):
        k = F[plane_idx] @ (cf @ pK)
        a = k + T[plane_idx] @ (ct @ pA)
        return float(np.sqrt(np.mean(np.concatenate([k @ normal, a @ normal]) ** 2)))

    miss = angle_between(np.einsum("ij,njk,k->ni", CF.T, M[valid], CT @ bT), bF)
    return FullCorrection(
        R_co_femur=CF, R_co_tibia=CT, femur_axis=bF, tibia_axis=bT, plane_normal=n,
        R_start_femur=R0F, R_start_tibia=R0T, cost=float(sol["f"]), terms=terms,
        hinge_rms=float(np.sqrt(np.mean(miss**2))),
        rest_deg=(rest_deg(R0F, R0T), rest_deg(CF, CT)),
        plane_rms=(plane_rms(R0F, R0T, n0), plane_rms(CF, CT, n)),
        iterations=int(stats["iter_count"]), status=str(stats["return_status"]),
        success=bool(stats["success"]), seconds=time.perf_counter() - t0,
        solver_seconds=solver_seconds, n_hinge_samples=len(hinge_idx),
        n_plane_samples=len(plane_idx),
    )
