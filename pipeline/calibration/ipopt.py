"""Joint-constraint calibration as one CasADi/IPOPT NLP (beyond Hu et al. 2021, DESIGN.md §6-7).

Variables (hinge): both axes ``j_1, j_2`` as 3-vectors and both joint positions ``o_1, o_2``
(sensor -> joint, sensor frames); spherical: the positions only. The NLP

    min  (1/N) sum_t rho(e_hinge(t); d_h) / d_h^2 + (1/N) sum_t rho(e_sph(t); d_s) / d_s^2
         + w sum_S |j_S - p_S|^2                                      (optional axis priors)
    s.t. |j_1|^2 = 1, |j_2|^2 = 1, j_1.o_1 + j_2.o_2 = 0               (hinge only)

uses eq 6 (``|w x j|^2 = |w|^2 |j|^2 - (w.j)^2``) and eq 3 (``|a + K o|^2`` as a quadratic form,
``K = [w]x^2 + [dw]x``), unit-norm equality constraints instead of the spherical coordinates of
eq 5 (no singularities), and eq 16 as the gauge constraint fixing the free shift along the hinge
axis. ``rho`` is ``'l2'`` (``e^2``), ``'huber'`` (pseudo-Huber ``2 d^2 (sqrt(1 + (e/d)^2) - 1)``)
or ``'cauchy'`` (``d^2 log(1 + (e/d)^2)``). A prior (e.g. the population knee axis expressed in
a sensor frame) keeps the problem well posed when a segment barely moves (still thigh); it also
fixes the axis signs. Derivatives (gradient, exact Hessian) come from CasADi's AD. The start is
a few Gauss-Newton steps (:mod:`pipeline.calibration.solvers`) on a decimated copy of the data.
"""

from __future__ import annotations

import dataclasses
import time as _time

import casadi as ca
import numpy as np

from pipeline.calibration.joint_constraints import (
    JointData,
    axis_from_spherical,
    consistent_axis_signs,
    gamma_matrix,
    project_hinge_positions,
)
from pipeline.calibration.losses import robust_loss
from pipeline.calibration.observability import diagnose
from pipeline.calibration.solvers import CalibrationResult, solve_subproblem
from pipeline.errors import InputError
from pipeline.rotations import normalize

__all__ = ["calibrate_ipopt"]

_EPS = 1e-12


def _decimate(d: JointData, step: int) -> JointData:
    return JointData(
        *(a[::step] for a in (d.gyr_1, d.gyr_2, d.acc_1, d.acc_2, d.gyr_dot_1, d.gyr_dot_2))
    )


def _position_norm(acc: np.ndarray, K: np.ndarray, o: ca.MX) -> ca.MX:
    """``|a + K o|`` per sample (N,1) from the quadratic form."""
    Kt = np.swapaxes(K, 1, 2)
    c = ca.DM(np.sum(acc * acc, axis=1))
    b = ca.DM(np.einsum("nij,nj->ni", Kt, acc))
    M = ca.DM((Kt @ K).reshape(-1, 9))
    sq = c + 2 * ca.mtimes(b, o) + ca.mtimes(M, ca.reshape(ca.mtimes(o, o.T), 9, 1))
    return ca.sqrt(ca.fmax(sq, 0) + _EPS)


def _axis_norm(gyr: np.ndarray, j: ca.MX) -> ca.MX:
    """``|w x j|`` per sample (N,1) as ``sqrt(|w|^2 |j|^2 - (w.j)^2)``."""
    w2 = ca.DM(np.sum(gyr * gyr, axis=1))
    wj = ca.mtimes(ca.DM(gyr), j)
    return ca.sqrt(ca.fmax(w2 * ca.dot(j, j) - wj**2, 0) + _EPS)


def calibrate_ipopt(
    data: JointData,
    joint: str = "hinge",
    *,
    loss: str = "l2",
    scale_hinge: float = 0.05,
    scale_position: float = 0.5,
    prior_axis_1: np.ndarray | None = None,
    prior_axis_2: np.ndarray | None = None,
    prior_weight: float = 1.0,
    quat_1: np.ndarray | None = None,
    quat_2: np.ndarray | None = None,
    reference_1: np.ndarray | None = None,
    position_bound: float = 0.3,
    seed: int = 0,
    max_iter: int = 100,
) -> CalibrationResult:
    """Calibrate a 'hinge' (axes + positions) or 'spherical' (positions) joint with IPOPT.

    ``scale_hinge`` (rad/s) and ``scale_position`` (m/s^2) normalise the two residuals and are the
    robust losses' transition points. ``prior_axis_*`` (sensor frames) with ``prior_weight``
    add ``w |j - p|^2``. Signs: from the priors, else :func:`consistent_axis_signs`. Position
    components are bounded by ``position_bound`` (m), which keeps an unobservable position finite.
    """
    if joint not in ("hinge", "spherical"):
        raise InputError(f"expected joint 'hinge' or 'spherical', got {joint!r}", field="joint")
    t0 = _time.perf_counter()
    n = data.gyr_1.shape[0]
    coarse = _decimate(data, max(1, n // 400))
    opts = {"restarts": 2, "max_iter": 15}
    xo, _, it0 = solve_subproblem(coarse, "positions", "gn", seed, {"restarts": 1, "max_iter": 15})
    o1, o2 = xo[:3], xo[3:]
    K1 = gamma_matrix(data.gyr_1, data.gyr_dot_1)
    K2 = gamma_matrix(data.gyr_2, data.gyr_dot_2)
    o = ca.MX.sym("o", 6)
    e_s = _position_norm(data.acc_1, K1, o[:3]) - _position_norm(data.acc_2, K2, o[3:])
    f = ca.sum1(robust_loss(e_s**2, loss, scale_position)) / (n * scale_position**2)
    g = []
    x = o
    x0 = np.concatenate([o1, o2])
    if joint == "hinge":
        xa, _, it1 = solve_subproblem(coarse, "axes", "gn", seed + 1, opts)
        it0 += it1
        j1, j2 = axis_from_spherical(xa[0], xa[1]), axis_from_spherical(xa[2], xa[3])
        p1 = None if prior_axis_1 is None else normalize(np.asarray(prior_axis_1, float))
        p2 = None if prior_axis_2 is None else normalize(np.asarray(prior_axis_2, float))
        if p1 is not None:  # start on the prior: a still segment leaves j1 to it
            j1 = p1
        ref = p1 if p1 is not None else reference_1
        j1, j2 = consistent_axis_signs(
            j1, j2, quat_1=quat_1, quat_2=quat_2, data=coarse, o1=o1, o2=o2, reference_1=ref
        )
        if p1 is None and p2 is not None and np.dot(j2, p2) < 0:
            j1, j2 = -j1, -j2
        o1, o2 = project_hinge_positions(o1, o2, j1, j2)
        j = ca.MX.sym("j", 6)
        e_h = _axis_norm(data.gyr_1, j[:3]) - _axis_norm(data.gyr_2, j[3:])
        f = f + ca.sum1(robust_loss(e_h**2, loss, scale_hinge)) / (n * scale_hinge**2)
        for p, jj in ((p1, j[:3]), (p2, j[3:])):
            if p is not None:
                f = f + prior_weight * ca.sumsqr(jj - ca.DM(p))
        g = [
            ca.dot(j[:3], j[:3]) - 1,
            ca.dot(j[3:], j[3:]) - 1,
            ca.dot(j[:3], o[:3]) + ca.dot(j[3:], o[3:]),
        ]
        x = ca.vertcat(j, o)
        x0 = np.concatenate([j1, j2, o1, o2])
    nlp = {"x": x, "f": f, "g": ca.vertcat(*g) if g else ca.MX(0, 1)}
    solver = ca.nlpsol(
        "hu_calibration",
        "ipopt",
        nlp,
        {
            "ipopt.print_level": 0,
            "print_time": False,
            "ipopt.sb": "yes",
            "ipopt.max_iter": max_iter,
            "ipopt.tol": 1e-10,
        },
    )
    ng = len(g)
    nj = x0.size - 6
    lbx = np.concatenate([np.full(nj, -2.0), np.full(6, -position_bound)])
    x0 = np.clip(x0, lbx, -lbx)
    sol = solver(x0=x0, lbx=lbx, ubx=-lbx, lbg=np.zeros(ng), ubg=np.zeros(ng))
    stats = solver.stats()
    xs = np.asarray(sol["x"]).ravel()
    if joint == "hinge":
        j1, j2 = normalize(xs[:3]), normalize(xs[3:6])
        o1, o2 = xs[6:9], xs[9:12]
    else:
        j1 = j2 = None
        o1, o2 = xs[:3], xs[3:]
    seconds = _time.perf_counter() - t0
    obs = diagnose(data, j1, j2, o1, o2)
    message = obs.message
    if prior_axis_1 is not None or prior_axis_2 is not None:
        message += f" | axis prior used (weight {prior_weight})"
    obs = dataclasses.replace(obs, message=message,
                              solver_status=str(stats.get("return_status", "")))  # fmt: skip
    return CalibrationResult(
        axis_1=j1,
        axis_2=j2,
        position_1_m=o1,
        position_2_m=o2,
        cost=float(sol["f"]),
        iterations=int(stats.get("iter_count", 0)) + int(it0),
        seconds=seconds,
        method="ipopt" + ("" if loss == "l2" else f"-{loss}"),
        observability=obs,
    )
