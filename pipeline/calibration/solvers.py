"""Solvers for the joint-constraint calibration (Hu et al. 2021 §3): Gauss-Newton, DWPSO, GWO.

All three minimise the same costs of :mod:`pipeline.calibration.joint_constraints`:

* axes (hinge, eq 12/18/26): ``x = [p_1, y_1, p_2, y_2]`` spherical coordinates (eq 5), pitch in
  ``[0, pi]``, yaw in ``[0, 2 pi]``, cost ``sum_t e_hinge(t)^2`` (eq 6);
* positions (eq 7/17/25): ``x = [o_1, o_2]`` in the box ``[-0.2, 0.2]^6`` m, cost
  ``sum_t e_sph(t)^2`` (eq 3). For a hinge the positions are then moved along the axis (eq 16).

Gauss-Newton (eq 7-15): ``x <- x - pinv(J) e`` from random starts in the box; the step is halved
while it increases the cost (a safeguard the paper does not state); the best of ``restarts`` runs
is kept. DWPSO (eq 17-24): velocity ``F <- mu F + 2 r_1 (eta - x) + 2 r_2 (p - x)``; eq 24 is
garbled in print, so the dynamic weight decays exponentially from ``mu_max = 0.8`` to
``mu_min = 0.2`` over the iterations, ``mu = mu_max (mu_min/mu_max)^(g/g_max)``, with random jumps
(probability ``jump``) to a uniform value in ``[mu_min, mu_max]``. GWO (eq 25-29, Mirjalili 2014):
``D = |C x_lead - x|``, ``x_lead - A D`` averaged over the three leaders, ``A = 2 psi r - psi``,
``C = 2 r``, ``psi`` 2 -> 0 (eq 27 omits the absolute value of the original GWO; it is kept).
All randomness comes from ``np.random.default_rng(seed)``.
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pipeline.calibration.joint_constraints import (
    JointData,
    axis_from_spherical,
    consistent_axis_signs,
    gamma_matrix,
    hinge_jacobian_spherical,
    hinge_residual,
    project_hinge_positions,
    spherical_jacobian,
    spherical_residual,
)
from pipeline.calibration.observability import Observability, diagnose
from pipeline.errors import InputError

__all__ = [
    "CLASSIC_SOLVERS",
    "CalibrationResult",
    "Subproblem",
    "calibrate_classic",
    "dwpso",
    "gauss_newton",
    "gwo",
    "solve_subproblem",
    "subproblem",
]

BOX = 0.2  # m, Hu eq 7
AXIS_LO = np.array([0.0, 0.0, 0.0, 0.0])
AXIS_HI = np.array([np.pi, 2 * np.pi, np.pi, 2 * np.pi])


@dataclass(frozen=True)
class CalibrationResult:
    """Joint axes (unit, sensor frames, same physical direction) and joint-centre positions
    (sensor -> joint, m, sensor frames); ``None`` where not estimated. ``cost``: mean squared
    residual(s) at the solution, hinge (rad/s)^2 plus positions (m/s^2)^2."""

    axis_1: np.ndarray | None
    axis_2: np.ndarray | None
    position_1_m: np.ndarray | None
    position_2_m: np.ndarray | None
    cost: float
    iterations: int
    seconds: float
    method: str
    observability: Observability


# ------------------------------------------------------------------------------- cost functions


def _axis_costs(X: np.ndarray, d: JointData) -> np.ndarray:
    """Mean squared eq-6 residual for a population ``X (P,4)`` of spherical coordinates, using
    ``|w x j|^2 = |w|^2 - (w.j)^2`` for unit ``j``."""
    j1 = axis_from_spherical(X[:, 0], X[:, 1])
    j2 = axis_from_spherical(X[:, 2], X[:, 3])
    w1 = np.sum(d.gyr_1**2, axis=1)[:, None]
    w2 = np.sum(d.gyr_2**2, axis=1)[:, None]
    n1 = np.sqrt(np.maximum(w1 - (d.gyr_1 @ j1.T) ** 2, 0.0))
    n2 = np.sqrt(np.maximum(w2 - (d.gyr_2 @ j2.T) ** 2, 0.0))
    return np.mean((n1 - n2) ** 2, axis=0)


def _quadratic_norms(d: JointData) -> tuple[tuple, tuple]:
    """``|a + K o|^2 = |a|^2 + 2 (K^T a).o + (o o^T) : K^T K`` per sample, for both sensors."""
    out = []
    for a, K in (
        (d.acc_1, gamma_matrix(d.gyr_1, d.gyr_dot_1)),
        (d.acc_2, gamma_matrix(d.gyr_2, d.gyr_dot_2)),
    ):
        Kt = np.swapaxes(K, 1, 2)
        out.append(
            (
                np.sum(a * a, axis=1)[:, None],
                np.einsum("nij,nj->ni", Kt, a),
                (Kt @ K).reshape(-1, 9),
            )
        )
    return tuple(out)


def _position_costs(X: np.ndarray, Q: tuple) -> np.ndarray:
    """Mean squared eq-3 residual for a population ``X (P,6)`` of positions."""
    norms = []
    for (c, b, M), o in zip(Q, (X[:, :3], X[:, 3:]), strict=True):
        oo = (o[:, :, None] * o[:, None, :]).reshape(-1, 9)
        norms.append(np.sqrt(np.maximum(c + 2.0 * (b @ o.T) + M @ oo.T, 0.0)))
    return np.mean((norms[0] - norms[1]) ** 2, axis=0)


@dataclass(frozen=True)
class Subproblem:
    """One of the two least-squares problems of a calibration, in the optimisers' terms.

    ``population_cost(X (P, n)) -> (P,)`` for the swarms; ``residual(x)`` and ``jacobian(x)``
    for Gauss-Newton; the box ``lo``, ``hi`` (n,) and the ``wrap`` mask of periodic coordinates
    (the azimuths of the spherical axis coordinates)."""

    population_cost: Callable[[np.ndarray], np.ndarray]
    residual: Callable[[np.ndarray], np.ndarray]
    jacobian: Callable[[np.ndarray], np.ndarray]
    lo: np.ndarray
    hi: np.ndarray
    wrap: np.ndarray


def subproblem(d: JointData, which: str) -> Subproblem:
    """The ``'axes'`` (eq 4-6, spherical coordinates) or ``'positions'`` (eq 1-3) problem."""
    if which == "axes":
        return Subproblem(
            lambda X: _axis_costs(X, d),
            lambda x: hinge_residual(
                axis_from_spherical(x[0], x[1]), axis_from_spherical(x[2], x[3]), d.gyr_1, d.gyr_2
            ),
            lambda x: hinge_jacobian_spherical(x, d.gyr_1, d.gyr_2),
            AXIS_LO,
            AXIS_HI,
            np.array([False, True, False, True]),
        )
    Q = _quadratic_norms(d)
    return Subproblem(
        lambda X: _position_costs(X, Q),
        lambda x: spherical_residual(x[:3], x[3:], d),
        lambda x: spherical_jacobian(x[:3], x[3:], d),
        np.full(6, -BOX),
        np.full(6, BOX),
        np.zeros(6, bool),
    )


# ------------------------------------------------------------------------------------ optimisers


def gauss_newton(
    residual: Callable[[np.ndarray], np.ndarray],
    jacobian: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    *,
    max_iter: int = 50,
    tol: float = 1e-10,
) -> tuple[np.ndarray, float, int]:
    """Eq 11/15: ``x <- x - pinv(J) e`` until the step is below ``tol``; (x, cost, iters)."""
    x = np.asarray(x0, float).copy()
    e = residual(x)
    cost = float(np.mean(e**2))
    it = 0
    for it in range(1, max_iter + 1):  # noqa: B007
        step = np.linalg.pinv(jacobian(x)) @ e
        for _ in range(30):
            xn = x - step
            en = residual(xn)
            cn = float(np.mean(en**2))
            if cn <= cost:
                break
            step = 0.5 * step
        else:
            break
        x, e, cost = xn, en, cn
        if np.linalg.norm(step) < tol:
            break
    return x, cost, it


def dwpso(
    cost: Callable[[np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    *,
    wrap: np.ndarray | None = None,
    particles: int = 40,
    iterations: int = 150,
    mu_min: float = 0.2,
    mu_max: float = 0.8,
    jump: float = 0.05,
    seed: int = 0,
) -> tuple[np.ndarray, float, int]:
    """Dynamic-weight PSO (eq 19-24) on a population cost ``cost(X (P,D)) -> (P,)``."""
    rng = np.random.default_rng(seed)
    span = hi - lo
    wrap = np.zeros(lo.size, bool) if wrap is None else wrap
    X = lo + span * rng.random((particles, lo.size))
    F = 0.1 * span * rng.uniform(-1, 1, X.shape)
    eta, eta_c = X.copy(), cost(X)
    g = int(np.argmin(eta_c))
    for k in range(iterations):
        mu = mu_max * (mu_min / mu_max) ** (k / max(iterations - 1, 1))
        if rng.random() < jump:
            mu = rng.uniform(mu_min, mu_max)
        r1, r2 = rng.random(X.shape), rng.random(X.shape)
        F = mu * F + 2.0 * r1 * (eta - X) + 2.0 * r2 * (eta[g] - X)  # eq 22
        F = np.clip(F, -0.2 * span, 0.2 * span)
        X = _bound(X + F, lo, hi, wrap)  # eq 23
        c = cost(X)
        better = c < eta_c  # eq 19
        eta[better], eta_c[better] = X[better], c[better]
        g = int(np.argmin(eta_c))  # eq 20
    return eta[g], float(eta_c[g]), iterations


def gwo(
    cost: Callable[[np.ndarray], np.ndarray],
    lo: np.ndarray,
    hi: np.ndarray,
    *,
    wrap: np.ndarray | None = None,
    wolves: int = 40,
    iterations: int = 150,
    seed: int = 0,
) -> tuple[np.ndarray, float, int]:
    """Grey wolf optimiser (eq 27-29) on a population cost ``cost(X (P,D)) -> (P,)``."""
    rng = np.random.default_rng(seed)
    wrap = np.zeros(lo.size, bool) if wrap is None else wrap
    X = lo + (hi - lo) * rng.random((wolves, lo.size))
    c = cost(X)
    order = np.argsort(c)[:3]
    leaders, leaders_c = X[order].copy(), c[order].copy()
    for k in range(iterations):
        psi = 2.0 - 2.0 * k / iterations
        new = np.zeros_like(X)
        for L in leaders:
            h = 2.0 * rng.random(X.shape)  # eq 27
            kk = 2.0 * psi * rng.random(X.shape) - psi  # eq 28
            new += L - kk * np.abs(h * L - X)
        X = _bound(new / 3.0, lo, hi, wrap)  # eq 29
        c = cost(X)
        pool = np.vstack([leaders, X])
        pool_c = np.concatenate([leaders_c, c])
        order = np.argsort(pool_c)[:3]
        leaders, leaders_c = pool[order].copy(), pool_c[order].copy()
    return leaders[0], float(leaders_c[0]), iterations


def _bound(X: np.ndarray, lo: np.ndarray, hi: np.ndarray, wrap: np.ndarray) -> np.ndarray:
    Y = np.clip(X, lo, hi)
    Y[:, wrap] = lo[wrap] + np.mod(X[:, wrap] - lo[wrap], (hi - lo)[wrap])
    return Y


# ----------------------------------------------------------------------------------- calibration


def solve_subproblem(
    d: JointData, which: str, method: str, seed: int, opts: dict
) -> tuple[np.ndarray, float, int]:
    """``(x, cost, iterations)`` of :func:`subproblem` ``which`` by ``method`` (gn/dwpso/gwo)."""
    p = subproblem(d, which)
    solve = CLASSIC_SOLVERS.get(method)
    if solve is None:
        raise InputError(f"expected method in {list(CLASSIC_SOLVERS)}, got {method!r}",
                         field="method")
    return solve(p, which, seed, opts)


def _gn_restarts(p, which: str, seed: int, opts: dict) -> tuple[np.ndarray, float, int]:
    """Gauss-Newton (eq 7-15) from random starts in the bounds; the best."""
    rng = np.random.default_rng(seed)
    best = None
    total = 0
    for _ in range(opts.get("restarts", 4 if which == "axes" else 2)):
        x0 = p.lo + (p.hi - p.lo) * rng.random(p.lo.size)
        x, c, it = gauss_newton(p.residual, p.jacobian, x0, max_iter=opts.get("max_iter", 50))
        total += it
        if best is None or c < best[1]:
            best = (x, c)
    return best[0], best[1], total


def _dwpso(p, which: str, seed: int, opts: dict) -> tuple[np.ndarray, float, int]:
    kw = {k: opts[k] for k in ("particles", "iterations", "jump") if k in opts}
    return dwpso(p.population_cost, p.lo, p.hi, wrap=p.wrap, seed=seed, **kw)


def _gwo(p, which: str, seed: int, opts: dict) -> tuple[np.ndarray, float, int]:
    kw = {k: opts[k] for k in ("wolves", "iterations") if k in opts}
    return gwo(p.population_cost, p.lo, p.hi, wrap=p.wrap, seed=seed, **kw)


#: The paper's solvers of one subproblem (Hu eq 7-15, 17-24, 25-29): method name -> function of
#: ``(subproblem, which, seed, options)`` returning ``(x, cost, iterations)``.
CLASSIC_SOLVERS = {"gn": _gn_restarts, "dwpso": _dwpso, "gwo": _gwo}


def calibrate_classic(
    data: JointData,
    joint: str = "hinge",
    method: str = "gn",
    *,
    seed: int = 0,
    quat_1: np.ndarray | None = None,
    quat_2: np.ndarray | None = None,
    reference_1: np.ndarray | None = None,
    **options,
) -> CalibrationResult:
    """Calibrate a joint from two sensors' signals with 'gn', 'dwpso' or 'gwo'.

    ``joint='hinge'``: axes (eq 4-6), positions (eq 1-3) moved along the axis (eq 16), axis signs
    made consistent (:func:`consistent_axis_signs`, with the orientations if given) and ``axis_1``
    along ``reference_1`` if given. ``joint='spherical'``: positions only. ``options`` go to the
    optimiser (``restarts``, ``max_iter``, ``particles``, ``wolves``, ``iterations``).
    """
    if joint not in ("hinge", "spherical"):
        raise InputError(f"expected joint 'hinge' or 'spherical', got {joint!r}", field="joint")
    t0 = _time.perf_counter()
    xo, co, it = solve_subproblem(data, "positions", method, seed, options)
    o1, o2 = xo[:3], xo[3:]
    j1 = j2 = None
    cost = co
    if joint == "hinge":
        xa, ca, ita = solve_subproblem(data, "axes", method, seed + 1, options)
        j1, j2 = axis_from_spherical(xa[0], xa[1]), axis_from_spherical(xa[2], xa[3])
        j1, j2 = consistent_axis_signs(
            j1, j2, quat_1=quat_1, quat_2=quat_2, data=data, o1=o1, o2=o2, reference_1=reference_1
        )
        o1, o2 = project_hinge_positions(o1, o2, j1, j2)
        cost, it = ca + co, it + ita
    seconds = _time.perf_counter() - t0
    return CalibrationResult(
        axis_1=j1,
        axis_2=j2,
        position_1_m=o1,
        position_2_m=o2,
        cost=float(cost),
        iterations=int(it),
        seconds=seconds,
        method=method,
        observability=diagnose(data, j1, j2, o1, o2),
    )
