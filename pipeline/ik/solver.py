"""Inverse kinematics from segment (or IMU) orientations on any Pinocchio model.

For each time frame ``n`` the joint configuration ``q_n`` minimises the weighted orientation misfit

    E(q) = 1/2 sum_i w_i |r_i(q)|^2 + 1/2 lambda |q (-) q_ref|^2,
    r_i(q) = log3(R_i*^T R_i(q))                                  (body-frame residual, rad)

where ``R_i*`` is the measured world orientation of model frame ``i`` (a segment frame such as
``right_femur`` or a sensor frame such as ``right_femur_imu``) and ``R_i(q)`` its forward
kinematics. Perturbing ``q`` by a tangent step ``dq`` (``pin.integrate``) turns ``R_i`` into
``R_i exp(J_i^w dq)``, ``J_i^w`` the angular rows of the LOCAL frame Jacobian; hence the exact
residual Jacobian ``dr_i/dq = Jlog3(R_i*^T R_i) J_i^w`` (``pin.Jlog3`` = inverse right Jacobian).

The trial is set up once (:func:`pipeline.ik.problem.setup_ik`); each frame is then one call of
:func:`solve_frame`: Levenberg-Marquardt-damped Gauss-Newton, ``(J^T W J + mu I) dq = -J^T W
r``. Since ``Jlog3(M)^T log3(M) = log3(M)`` (the inverse left Jacobian fixes its own rotation
vector), the gradient ``sum_i w_i (J_i^w)^T r_i`` is exact without ``Jlog3``; the Gauss-Newton
matrix drops ``Jlog3^T Jlog3 = I + O(|r|^2)``, which only changes the (linear) rate, not the fixed
point. As ``J_i^w = R_i^T A m_i`` (``A``: world axes of the joints, the angular rows of Pinocchio's
WORLD joint Jacobians; ``m_i``: DoFs that move frame ``i``), the normal equations need no per-frame
Jacobian: ``J^T W J = (A^T A) o sum_i w_i m_i m_i^T`` and ``J^T W r = sum_i w_i m_i o (A^T u_i)``
with the world residual ``u_i = R_i r_i = log3(R_i R_i*^T)``. With ``damping = 0`` and a DoF that no
present task observes (e.g. the ankle of a frame without its foot target) the matrix is singular:
its factorisation fails (:func:`pipeline.ik.bounds.solve_linear`) and the step is then the
minimum-norm least-squares one, which leaves that DoF alone. Damping does not move the fixed point
either, so the result is the exact weighted least-squares optimum (stationary: ``J^T W r = 0``
with the exact Jacobian of :func:`orientation_residuals`); with an exactly reachable target set it
reproduces the targets (Wang 2023 eq 15-17 then follow from the model's forward kinematics).

Warm start: the previous frame's solution (plus its last velocity if ``extrapolate``); revolute
angles are never wrapped, so trajectories are continuous. Stopping: when the linear-rate estimate
of the error left in ``q``, ``|dq_k|^2 / (|dq_{k-1}| - |dq_k|)``, or the step itself is below
``tol / 10``, so that the returned ``q`` is within ``tol`` (rad, max over DoFs) of the optimum.
Joint limits of 1-DoF joints are a box on ``dq`` solved by a small active-set QP (projected Gauss-
Newton, :mod:`pipeline.ik.bounds`); configurations never leave the box. DoFs that no target can
rotate (translations of a free-flyer root, prismatic joints, an ankle without a foot target) are
left untouched at ``q0``.

Missing data: tasks whose target is non-finite at a frame are dropped for that frame (DoFs they
alone observe are held at the previous solution); a frame with no finite target gets a NaN row,
``converged = False`` and ``iterations = 0``, and the next frame is warm-started from the last
solved one.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.ik.anchors import ANCHOR_TOL, anchor_frames, interpolate
from pipeline.ik.block import BlockSetup, block_frame_rotations, block_setup, solve_block
from pipeline.ik.bounds import box_margin, box_step, solve_linear
from pipeline.ik.problem import IKProblem, OrientationTask, frame_id, setup_ik
from pipeline.rotations import log3

__all__ = ["IKResult", "frame_rotations", "orientation_residuals", "solve_frame", "solve_ik"]


@dataclass(frozen=True)
class IKResult:
    """Per-frame IK solution.

    ``q`` (N, nq) configurations (NaN rows where no target was finite); ``residual_rms`` (N,)
    unweighted RMS over the tasks of the residual angle |r_i| (rad); ``task_errors`` (N, k) the
    residual angle of each task (NaN where its target was missing); ``iterations`` (N,) Gauss-Newton
    steps taken; ``converged`` (N,) the stopping test (``tol``) met within ``max_iters``;
    ``tasks`` the tasks in column order of ``task_errors``.
    """

    q: np.ndarray
    residual_rms: np.ndarray
    iterations: np.ndarray
    converged: np.ndarray
    task_errors: np.ndarray
    tasks: tuple[OrientationTask, ...]


def frame_rotations(
    model: pin.Model, q: np.ndarray, frames: Sequence[str]
) -> dict[str, np.ndarray]:
    """World rotations (N, 3, 3) of model ``frames`` along a trajectory ``q`` (N, nq).

    Rows of ``q`` containing NaN give NaN rotations.
    """
    q = np.atleast_2d(np.asarray(q, dtype=float))
    fids = [frame_id(model, f) for f in frames]
    data = model.createData()
    out = np.full((len(fids), q.shape[0], 3, 3), np.nan)
    for n in np.flatnonzero(np.isfinite(q).all(axis=1)):
        pin.forwardKinematics(model, data, q[n])
        for i, fid in enumerate(fids):
            out[i, n] = pin.updateFramePlacement(model, data, fid).rotation
    return dict(zip(frames, out, strict=True))


def orientation_residuals(
    model: pin.Model, q: np.ndarray, targets: Mapping[str, np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """Stacked residuals ``r_i = log3(R_i*^T R_i(q))`` (3k,) and their Jacobian (3k, nv).

    ``dr_i/dq = Jlog3(R_i*^T R_i(q)) J_i^w(q)`` with ``J_i^w`` the angular rows of the LOCAL frame
    Jacobian, in the tangent space of ``pin.integrate`` (the math :func:`solve_ik` iterates on).
    ``targets`` maps frame names to single (3, 3) world rotations.
    """
    data = model.createData()
    q = np.asarray(q, dtype=float)
    pin.computeJointJacobians(model, data, q)
    r, J = [], []
    for name, Rt in targets.items():
        fid = frame_id(model, name)
        M = np.asarray(Rt, dtype=float).T @ pin.updateFramePlacement(model, data, fid).rotation
        r.append(pin.log3(M))
        J.append(
            pin.Jlog3(M) @ pin.getFrameJacobian(model, data, fid, pin.LOCAL).reshape(6, -1)[3:]
        )
    return np.concatenate(r), np.vstack(J)


def solve_frame(
    p: IKProblem, n: int, q: np.ndarray, previous: np.ndarray | None = None,
    tol: float | None = None,
) -> tuple[np.ndarray, int, bool]:
    """Gauss-Newton on frame ``n`` from ``q`` (updated in place): ``(q, iterations, converged)``.
    ``tol``: the stopping tolerance (default the problem's).

    ``previous`` (2, nq): the solutions of frames ``n-2`` and ``n-1`` for the constant-velocity
    warm start (``extrapolate``). A frame without any finite target returns ``q`` untouched with
    0 iterations. When the normal matrix is singular (no damping and a DoF that no present task
    observes), the step is the minimum-norm least-squares one: unobserved DoFs do not move.
    """
    model, data = p.model, p.data
    finite = p.finite[n]
    if finite.all():
        Rn, Wm, C = p.RtT[n], p.Wm_all, p.C_all
    else:
        if not finite.any():
            return q, 0, False
        Rn = np.where(finite[:, None, None], p.RtT[n], np.eye(3))
        Wm, C = p.normal_weights(p.weights * finite)
    cq, bq, blo, bhi, bsel = p.cq, p.bq, p.blo, p.bhi, p.bsel
    has_limits, all_bounded = bq.size > 0, p.all_bounded
    if p.extrapolate and p.euclid and previous is not None and np.isfinite(previous).all():
        q[cq] += previous[1, cq] - previous[0, cq]  # constant-velocity prediction
        if has_limits:
            q[bq] = np.clip(q[bq], blo, bhi)
    na, k = p.cols.size, len(p.fids)
    U = np.empty((3, k))  # world-frame residuals u_i = R_i r_i = log3(R_i R_i*^T)
    v = np.zeros(model.nv)
    mu_eye = p.mu_eye
    lam, tol = p.regularization, (p.tol if tol is None else tol)
    log3_, cjj, ufp = pin.log3, pin.computeJointJacobians, pin.updateFramePlacement
    rs = (6, model.nv)
    margin = box_margin(q[bq], blo, bhi) if has_limits else np.inf
    prev = np.inf
    it = 0
    for it in range(1, p.max_iters + 1):
        cjj(model, data, q)
        for i, fid in enumerate(p.fids):
            U[:, i] = log3_(ufp(model, data, fid).rotation @ Rn[i])
        Wa = data.J.reshape(rs)[3:, p.cs]  # angular rows of the WORLD joint Jacobians
        # J_i^w = R_i^T (Wa o m_i): J^T W J = (Wa^T Wa) o C; J^T W r = rowsum((Wa^T U) o Wm)
        H = (Wa.T @ Wa) * C + mu_eye
        g = ((Wa.T @ U) * Wm).sum(axis=1)
        if lam > 0.0:
            e = pin.difference(model, p.q_ref, q)[p.cols]
            De = pin.dDifference(model, p.q_ref, q, pin.ARG1)[np.ix_(p.cols, p.cols)]
            H += lam * (De.T @ De)
            g += lam * (De.T @ e)
        d = -solve_linear(H, g)
        dn = max(d.max(), -d.min())
        clipped = False
        if dn >= margin:  # a bound may be crossed (margin: distance of q to the box)
            qb = q[bq]
            qn = qb + (d if all_bounded else d[bsel])
            if (qn < blo).any() or (qn > bhi).any():
                dlo = np.full(na, -np.inf)
                dhi = np.full(na, np.inf)
                dlo[bsel] = np.minimum(blo - qb, 0.0)
                dhi[bsel] = np.maximum(bhi - qb, 0.0)
                d = box_step(H, g, dlo, dhi, d)
                dn = max(d.max(), -d.min())
                clipped = True
        if p.euclid:
            q[cq] += d
        else:
            v[p.cs] = d
            q[:] = pin.integrate(model, q, v)
        if clipped:
            q[bq] = np.clip(q[bq], blo, bhi)
            margin = box_margin(q[bq], blo, bhi)
        else:
            margin -= dn
        # stop when the linear-rate estimate of the error left after this step,
        # |d|^2 / (|d_prev| - |d|), is below tol / 10 (the rate seen over the first steps
        # underestimates the asymptotic one by up to ~6x on noisy hinge fits), or on a step
        # below tol / 10
        if dn < 0.1 * tol or (it > 1 and prev > 2.0 * dn and 10.0 * dn * dn < tol * (prev - dn)):
            return q, it, True
        prev = dn
    return q, it, False


def solve_ik(
    model: pin.Model,
    targets: Mapping[str | OrientationTask, np.ndarray],
    weights: Mapping[str, float] | None = None,
    *,
    q0: np.ndarray | None = None,
    root: np.ndarray | None = None,
    max_iters: int = 20,
    tol: float = 1e-4,
    limits: bool = True,
    damping: float = 1e-6,
    regularization: float = 0.0,
    extrapolate: bool = False,
    stride: int = 64,
) -> IKResult:
    """Joint trajectories whose frame orientations best match ``targets`` (module docstring).

    ``targets``: frame name (or :class:`OrientationTask`) -> (N, 3, 3) world rotations of that
    model frame; ``weights``: frame -> w_i (default 1, or the task's weight). ``q0`` (nq,): initial
    guess of the first frame, value of unobserved DoFs and ``q_ref`` of the regularisation (default
    ``pin.neutral``). ``root``: (3, 3) or (N, 3, 3) world orientation of the model's universe frame
    (e.g. the measured pelvis of a fixed-pelvis leg model); targets are expressed in the model as
    ``root^T R*``. ``limits``: enforce the model's position limits of 1-DoF joints. ``damping``:
    Levenberg-Marquardt ``mu`` (does not bias the optimum). ``regularization``: ``lambda`` pulling
    towards ``q0`` (biases the optimum; 0 by default). ``tol``: bound on the error (rad) left in
    ``q`` at exit (default 1e-4 rad = 0.006 deg); ``max_iters`` per frame. ``extrapolate``:
    constant-velocity prediction of the warm start for Euclidean chains and frames with all targets
    present (off by default: with white orientation noise it costs iterations). ``stride``: every
    ``stride``-th frame is solved in sequence and the frames between them in blocks, every 8th
    first (:mod:`pipeline.ik.block`: the same optima, ~5x faster); ``stride=1`` solves every frame
    in sequence (also the path of regularised, extrapolated or non-vectorisable problems). Raises
    ``InputError`` on unknown frames, wrong shapes, non-rotation targets or weights < 0.
    """
    p = setup_ik(model, targets, weights, q0=q0, root=root, max_iters=max_iters, tol=tol,
                 limits=limits, damping=damping, regularization=regularization,
                 extrapolate=extrapolate)
    if not isinstance(stride, int | np.integer) or stride < 1:
        raise InputError(f"stride must be an integer >= 1, got {stride!r}", field="stride")
    b = None if stride == 1 or extrapolate else block_setup(p)
    if b is not None:
        return _result(p, *_solve_strided(p, b, int(stride)), b)
    N = p.n_frames
    Q = np.full((N, model.nq), np.nan)
    iters = np.zeros(N, dtype=int)
    conv = np.zeros(N, dtype=bool)
    all_finite = p.finite.all(axis=1)
    q = p.q_ref.copy()
    for n in range(N):
        if not p.finite[n].any():
            continue
        previous = Q[n - 2 : n] if n >= 2 and all_finite[n - 2 : n + 1].all() else None
        q, iters[n], conv[n] = solve_frame(p, n, q, previous)
        Q[n] = q
    return _result(p, Q, iters, conv)


def _solve_strided(
    p: IKProblem, b: BlockSetup, stride: int, block: int = 2048
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Anchors (every ``stride``-th frame, closer where the joints turn fast:
    :func:`~pipeline.ik.anchors.anchor_frames`) in sequence to
    :data:`~pipeline.ik.anchors.ANCHOR_TOL`, then to ``tol`` in a block, then the frames between
    them level by level (spacing divided by 8 per level,
    down to 1), each level in blocks started from the interpolation of the frames solved so far
    (:func:`~pipeline.ik.anchors.interpolate`, :mod:`pipeline.ik.block`). Frames with a
    missing target are solved last, in time order, each warm-started from the solution before
    it, so that the DoFs only the missing targets observe are held as in the sequential solver."""
    model = p.model
    N = p.n_frames
    Q = np.full((N, model.nq), np.nan)
    iters = np.zeros(N, dtype=int)
    conv = np.zeros(N, dtype=bool)
    whole = p.finite.all(axis=1)
    anchors = anchor_frames(p, stride)
    known = np.empty((N, model.nq))  # the warm start each solved frame leaves
    done = np.zeros(N, dtype=bool)
    q = p.q_ref.copy()
    for n in anchors:  # in sequence, each from the one before: the basin of the motion
        if whole[n]:
            q, iters[n], _ = solve_frame(p, n, q, tol=max(ANCHOR_TOL, p.tol))
            Q[n] = q.copy()
        known[n] = q
    # the anchors then to tol together, from where the sequence left them
    _refine(p, b, anchors[whole[anchors]], Q, iters, conv)
    known[anchors] = np.where(whole[anchors, None], Q[anchors], known[anchors])
    done[anchors] = True
    spacing = stride
    while spacing > 1:
        spacing = max(1, spacing // 8)
        level = np.flatnonzero(~done & whole & (np.arange(N) % spacing == 0))
        ref = np.flatnonzero(done)
        for first in range(0, level.size, block):  # memory: one block's starting points
            frames = level[first : first + block]
            start = b.kin.normalize(interpolate(ref, known, frames))
            start[:, b.fixed_q] = p.q_ref[b.fixed_q]  # exactly as given, not interpolated
            Q[frames] = start
            _refine(p, b, frames, Q, iters, conv)
        known[level] = Q[level]
        done[level] = True
    # frames with a missing target last, in order, each from the solution before it (the
    # sequential solver's warm start)
    solved = p.finite.any(axis=1)
    before = np.maximum.accumulate(np.where(solved, np.arange(N), -1))  # last solved <= n
    for n in np.flatnonzero(solved & ~whole):
        m = before[n - 1] if n > 0 else -1
        Q[n], iters[n], conv[n] = solve_frame(p, n, Q[m].copy() if m >= 0 else p.q_ref.copy())
    return Q, iters, conv


def _refine(p: IKProblem, b: BlockSetup, frames: np.ndarray, Q: np.ndarray, iters: np.ndarray,
            conv: np.ndarray) -> None:
    """``frames`` (all targets present) solved to ``tol`` in a block from ``Q[frames]``, in
    place (iterations added); the per-frame solver finishes what the block did not, with
    ``max_iters`` steps of its own."""
    if not frames.size:
        return
    Q[frames], it, conv[frames] = solve_block(p, b, frames, Q[frames])
    iters[frames] += it
    for n in frames[~conv[frames]]:
        qn = Q[n].copy()
        if p.has_limits:
            qn[p.bq] = np.clip(qn[p.bq], p.blo, p.bhi)
        Q[n], extra, conv[n] = solve_frame(p, n, qn)
        iters[n] += extra


def _result(
    p: IKProblem, Q: np.ndarray, iters: np.ndarray, conv: np.ndarray,
    b: BlockSetup | None = None, chunk: int = 10_000,
) -> IKResult:
    """Residuals at the returned configurations (vectorised log map, in chunks of frames so
    that memory stays bounded on long trials; the block kinematics where ``b`` is given)."""
    tasks, RtT, finite = p.tasks, p.RtT, p.finite
    N, k = finite.shape
    frames = [t.frame for t in tasks]
    err = np.full((N, k), np.nan)
    ok = np.zeros((N, k), dtype=bool)
    for start in range(0, N, chunk):
        rows = slice(start, start + chunk)
        if b is None:
            R_fit = np.stack(list(frame_rotations(p.model, Q[rows], frames).values()), axis=1)
        else:
            R_fit = block_frame_rotations(b, Q[rows])
        ok_c = np.all(np.isfinite(R_fit), axis=(2, 3)) & finite[rows]
        ok[rows] = ok_c
        if ok_c.any():
            e = err[rows]
            e[ok_c] = np.linalg.norm(log3(RtT[rows][ok_c] @ R_fit[ok_c]), axis=-1)
    count = ok.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(np.where(ok, err, 0.0) ** 2 @ np.ones(k) / count)
    rms[count == 0] = np.nan
    return IKResult(Q, rms, iters, conv, err, tuple(tasks))
