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
The data enter the NLP as a parameter, so one solver per (joint, sample count, loss) is built and
reused (a trial's two knees, both starts of :func:`~pipeline.calibration.calibrate.calibrate`):
with the split halves solved from one start, both knees' calibrations of a 17 s trial took 0.47
s instead of 0.91 s (one profile).
"""

from __future__ import annotations

import dataclasses
import time as _time
from functools import lru_cache

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


def _position_norm(p: ca.MX, o: ca.MX) -> ca.MX:
    """``|a + K o|`` per sample (N,1) from the quadratic form, its data ``p = [c, b, M]`` (N, 13):
    ``c = |a|^2``, ``b = K^T a``, ``M = K^T K`` (row-major 9) (:func:`_position_data`)."""
    sq = p[:, 0] + 2 * ca.mtimes(p[:, 1:4], o) + ca.mtimes(p[:, 4:13],
                                                           ca.reshape(ca.mtimes(o, o.T), 9, 1))
    return ca.sqrt(ca.fmax(sq, 0) + _EPS)


def _position_data(acc: np.ndarray, K: np.ndarray) -> np.ndarray:
    Kt = np.swapaxes(K, 1, 2)
    return np.hstack([np.sum(acc * acc, axis=1)[:, None], np.einsum("nij,nj->ni", Kt, acc),
                      (Kt @ K).reshape(-1, 9)])


def _axis_norm(p: ca.MX, j: ca.MX) -> ca.MX:
    """``|w x j|`` per sample (N,1) as ``sqrt(|w|^2 |j|^2 - (w.j)^2)``, ``p = [|w|^2, w]``
    (N, 4)."""
    wj = ca.mtimes(p[:, 1:4], j)
    return ca.sqrt(ca.fmax(p[:, 0] * ca.dot(j, j) - wj**2, 0) + _EPS)


@lru_cache(maxsize=16)
def _solver(joint: str, n: int, loss: str, scale_hinge: float, scale_position: float,
            max_iter: int) -> ca.Function:
    """The NLP of the module docstring for ``n`` samples, its data a parameter: built once per
    shape and reused by every calibration of that size (a trial's two knees, both starts).
    Parameter layout: the two sensors' position data (:func:`_position_data`, 13 columns each),
    then for a hinge the two gyroscopes' ``[|w|^2, w]`` (4 each), both axis priors and their
    weights ``[p_1, w_1, p_2, w_2]`` (8)."""
    cols = 26 + (8 if joint == "hinge" else 0)
    P = ca.MX.sym("p", n * cols + (8 if joint == "hinge" else 0))
    D = ca.reshape(P[: n * cols], n, cols)
    o = ca.MX.sym("o", 6)
    e_s = _position_norm(D[:, 0:13], o[:3]) - _position_norm(D[:, 13:26], o[3:])
    f = ca.sum1(robust_loss(e_s**2, loss, scale_position)) / (n * scale_position**2)
    g, x = [], o
    if joint == "hinge":
        j = ca.MX.sym("j", 6)
        e_h = _axis_norm(D[:, 26:30], j[:3]) - _axis_norm(D[:, 30:34], j[3:])
        f = f + ca.sum1(robust_loss(e_h**2, loss, scale_hinge)) / (n * scale_hinge**2)
        pri = P[n * cols :]  # [p_1, w_1, p_2, w_2]: w_S = 0 without that prior
        f = f + pri[3] * ca.sumsqr(j[:3] - pri[0:3]) + pri[7] * ca.sumsqr(j[3:] - pri[4:7])
        g = [ca.dot(j[:3], j[:3]) - 1, ca.dot(j[3:], j[3:]) - 1,
             ca.dot(j[:3], o[:3]) + ca.dot(j[3:], o[3:])]
        x = ca.vertcat(j, o)
    nlp = {"x": x, "p": P, "f": f, "g": ca.vertcat(*g) if g else ca.MX(0, 1)}
    return ca.nlpsol("hu_calibration", "ipopt", nlp, {
        "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
        "ipopt.max_iter": max_iter, "ipopt.tol": 1e-10})


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
    start: tuple[np.ndarray, np.ndarray] | None = None,
    seed: int = 0,
    max_iter: int = 100,
) -> CalibrationResult:
    """Calibrate a 'hinge' (axes + positions) or 'spherical' (positions) joint with IPOPT.

    ``scale_hinge`` (rad/s) and ``scale_position`` (m/s^2) normalise the two residuals and are the
    robust losses' transition points. ``prior_axis_*`` (sensor frames) with ``prior_weight``
    add ``w |j - p|^2``. Signs: from the priors, else :func:`consistent_axis_signs`. Position
    components are bounded by ``position_bound`` (m), which keeps an unobservable position finite.
    ``start``: the positions ``(o_1, o_2)`` to start from instead of the Gauss-Newton steps'
    (which start at random points of the bounds' box, so their minimum depends on how the
    sensors sit; a start computed from the signals alike in any sensor frame does not).
    """
    if joint not in ("hinge", "spherical"):
        raise InputError(f"expected joint 'hinge' or 'spherical', got {joint!r}", field="joint")
    t0 = _time.perf_counter()
    n = data.gyr_1.shape[0]
    coarse = _decimate(data, max(1, n // 400))
    opts = {"restarts": 2, "max_iter": 15}
    if start is None:
        xo, _, it0 = solve_subproblem(coarse, "positions", "gn", seed,
                                      {"restarts": 1, "max_iter": 15})
        o1, o2 = xo[:3], xo[3:]
    else:
        o1, o2 = (np.asarray(o, float) for o in start)
        it0 = 0
    K1 = gamma_matrix(data.gyr_1, data.gyr_dot_1)
    K2 = gamma_matrix(data.gyr_2, data.gyr_dot_2)
    blocks = [_position_data(data.acc_1, K1), _position_data(data.acc_2, K2)]
    x0 = np.concatenate([o1, o2])
    extra = np.zeros(0)
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
        for w in (data.gyr_1, data.gyr_2):
            blocks.append(np.hstack([np.sum(w * w, axis=1)[:, None], w]))
        extra = np.concatenate([np.zeros(4) if p is None else [*p, prior_weight]
                                for p in (p1, p2)])
        x0 = np.concatenate([j1, j2, o1, o2])
    params = np.concatenate([np.hstack(blocks).ravel(order="F"), extra])
    solver = _solver(joint, n, loss, float(scale_hinge), float(scale_position), int(max_iter))
    ng = 3 if joint == "hinge" else 0
    nj = x0.size - 6
    lbx = np.concatenate([np.full(nj, -2.0), np.full(6, -position_bound)])
    x0 = np.clip(x0, lbx, -lbx)
    sol = solver(x0=x0, p=params, lbx=lbx, ubx=-lbx, lbg=np.zeros(ng), ubg=np.zeros(ng))
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
                              solver_status=str(stats.get("return_status", "")))
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
