"""Box-constrained Gauss-Newton step for joint limits (private helper of :mod:`pipeline.ik.solver`).

Position limits of 1-DoF joints (revolute, prismatic; there ``q`` and the tangent ``v`` coincide)
bound each coordinate, ``lo_q <= q_a <= hi_q``. A Gauss-Newton step ``d`` from ``q`` then has to
stay in the box ``lo_q - q <= d <= hi_q - q``, so the step is the box-constrained quadratic
program

    d* = argmin 1/2 d^T H d + g^T d   s.t.   lo <= d <= hi      (H symmetric positive definite),

solved exactly by a small primal-dual active-set method: fix the violated bounds, solve the free
coordinates from ``H_ff d_f = -g_f - H_fx d_x``, add newly violated bounds, and release a fixed
coordinate whose multiplier has the wrong sign (KKT: ``(H d + g)_a >= 0`` at a lower bound,
``<= 0`` at an upper bound, ``= 0`` when free). Iterating such steps is projected Gauss-Newton:
configurations never leave the box.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["UNBOUNDED", "box_margin", "box_step", "joint_box", "remove_limits", "solve_linear"]

UNBOUNDED = 1e30
"""Limits at or beyond this magnitude mean "no limit" (pinocchio's default is +-DBL_MAX)."""


def dof_joints(model: pin.Model) -> np.ndarray:
    """The joint that owns each tangent index, (nv,) ints: one pass over the joints (each
    ``model.joints[j]`` builds a new Python object, so searching them per DoF is slow)."""
    out = np.zeros(model.nv, dtype=int)
    for j in range(1, model.njoints):
        out[model.idx_vs[j] : model.idx_vs[j] + model.nvs[j]] = j
    return out


def joint_box(
    model: pin.Model, cols: np.ndarray, limits: bool = True
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position limits of the tangent DoFs ``cols`` that belong to 1-DoF joints.

    Returns ``lo``, ``hi`` (len(cols),) with +-inf where a DoF is unbounded (a multi-DoF joint,
    a limit beyond :data:`UNBOUNDED`, or ``limits=False``) and ``qidx`` (len(cols),), the
    configuration index of each bounded 1-DoF joint (-1 for the DoFs not bounded this way).
    """
    na = len(cols)
    lo = np.full(na, -np.inf)
    hi = np.full(na, np.inf)
    qidx = np.full(na, -1)
    if limits:
        owners = dof_joints(model)
        for a, v in enumerate(cols):
            j = int(owners[int(v)])
            if model.nqs[j] == 1 and model.nvs[j] == 1:
                iq = model.idx_qs[j]
                lo_q, hi_q = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
                lo[a] = lo_q if abs(lo_q) < UNBOUNDED else -np.inf
                hi[a] = hi_q if abs(hi_q) < UNBOUNDED else np.inf
                qidx[a] = iq
    return lo, hi, qidx


def remove_limits(model: pin.Model, joints: list[str]) -> None:
    """Remove the position limits of the named 1-DoF joints of ``model`` (in place), e.g. the
    hips of a leg model whose pelvis orientation is not measured: the hip then carries the
    thigh's whole orientation, which no anatomical range bounds."""
    lo, hi = model.lowerPositionLimit.copy(), model.upperPositionLimit.copy()
    for name in joints:
        if not model.existJointName(name):
            raise KeyError(name)
        j = model.joints[model.getJointId(name)]
        lo[j.idx_q : j.idx_q + j.nq] = -np.inf
        hi[j.idx_q : j.idx_q + j.nq] = np.inf
    model.lowerPositionLimit, model.upperPositionLimit = lo, hi


def solve_linear(H: np.ndarray, g: np.ndarray) -> np.ndarray:
    """``x`` with ``H x = g`` for the symmetric normal matrix ``H``; where ``H`` is singular (a DoF
    no task observes, without damping: its row and column are exactly zero), the minimum-norm
    least-squares ``x``, which leaves that DoF alone. NumPy's LAPACK (LU), not SciPy's ``dposv``:
    ``scipy.linalg`` costs a command ~0.4 s of import."""
    try:
        return np.linalg.solve(H, g)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(H, g, rcond=None)[0]


def box_margin(qb: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Smallest distance of the bounded coordinates to their box (inf if there are none)."""
    return float(min((qb - lo).min(), (hi - qb).min())) if qb.size else np.inf


def box_step(
    H: np.ndarray, g: np.ndarray, lo: np.ndarray, hi: np.ndarray, d0: np.ndarray
) -> np.ndarray:
    """argmin 1/2 d^T H d + g^T d s.t. lo <= d <= hi (H SPD): primal-dual active set.

    ``d0`` is the unconstrained minimiser; the bounds it violates seed the active set.
    """
    n = g.size
    d = d0.copy()
    at_lo, at_hi = d0 < lo, d0 > hi
    for _ in range(3 * n + 3):
        fixed = at_lo | at_hi
        d[at_lo], d[at_hi] = lo[at_lo], hi[at_hi]
        free = np.flatnonzero(~fixed)
        if free.size:
            fx = np.flatnonzero(fixed)
            rhs = -g[free] - H[free][:, fx] @ d[fx]
            d[free] = solve_linear(H[free][:, free], rhs)
        new_lo, new_hi = d < lo, d > hi
        if new_lo.any() or new_hi.any():
            at_lo |= new_lo
            at_hi |= new_hi
            continue
        grad = H @ d + g  # KKT: >= 0 at a lower bound, <= 0 at an upper bound
        wrong = np.where(at_lo, -grad, 0.0) + np.where(at_hi, grad, 0.0)
        k = int(np.argmax(wrong))
        if wrong[k] <= 1e-12:
            break
        at_lo[k] = at_hi[k] = False
    return np.clip(d, lo, hi)
