"""Inverse kinematics from segment (or IMU) orientations on any Pinocchio model.

For each time frame ``n`` the joint configuration ``q_n`` minimises the weighted orientation misfit

    E(q) = 1/2 sum_i w_i |r_i(q)|^2 + 1/2 lambda |q (-) q_ref|^2,
    r_i(q) = log3(R_i*^T R_i(q))                                  (body-frame residual, rad)

where ``R_i*`` is the measured world orientation of model frame ``i`` (a segment frame such as
``right_femur`` or a sensor frame such as ``right_femur_imu``) and ``R_i(q)`` its forward
kinematics. Perturbing ``q`` by a tangent step ``dq`` (``pin.integrate``) turns ``R_i`` into
``R_i exp(J_i^w dq)``, ``J_i^w`` the angular rows of the LOCAL frame Jacobian; hence the exact
residual Jacobian ``dr_i/dq = Jlog3(R_i*^T R_i) J_i^w`` (``pin.Jlog3`` = inverse right Jacobian).

Each frame is solved by Levenberg-Marquardt-damped Gauss-Newton, ``(J^T W J + mu I) dq = -J^T W
r``. Since ``Jlog3(M)^T log3(M) = log3(M)`` (the inverse left Jacobian fixes its own rotation
vector), the gradient ``sum_i w_i (J_i^w)^T r_i`` is exact without ``Jlog3``; the Gauss-Newton
matrix drops ``Jlog3^T Jlog3 = I + O(|r|^2)``, which only changes the (linear) rate, not the fixed
point. As ``J_i^w = R_i^T A m_i`` (``A``: world axes of the joints, the angular rows of Pinocchio's
WORLD joint Jacobians; ``m_i``: DoFs that move frame ``i``), the normal equations need no per-frame
Jacobian: ``J^T W J = (A^T A) o sum_i w_i m_i m_i^T`` and ``J^T W r = sum_i w_i m_i o (A^T u_i)``
with the world residual ``u_i = R_i r_i = log3(R_i R_i*^T)``. Damping does not move the fixed point
either, so the result is the exact weighted least-squares optimum (stationary: ``J^T W r = 0`` with
the exact Jacobian of :func:`orientation_residuals`); with an exactly reachable target set it
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
from scipy.linalg.lapack import dposv

from pipeline.errors import InputError
from pipeline.ik.bounds import box_margin, box_step, joint_box
from pipeline.rotations import log3

__all__ = ["IKResult", "OrientationTask", "frame_rotations", "orientation_residuals", "solve_ik"]


@dataclass(frozen=True)
class OrientationTask:
    """Track the world orientation of model frame ``frame`` with weight ``weight`` (>= 0)."""

    frame: str
    weight: float = 1.0


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
    fids = [_frame_id(model, f) for f in frames]
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
        fid = _frame_id(model, name)
        M = np.asarray(Rt, dtype=float).T @ pin.updateFramePlacement(model, data, fid).rotation
        r.append(pin.log3(M))
        J.append(
            pin.Jlog3(M) @ pin.getFrameJacobian(model, data, fid, pin.LOCAL).reshape(6, -1)[3:]
        )
    return np.concatenate(r), np.vstack(J)


def _frame_id(model: pin.Model, name: str) -> int:
    if not isinstance(name, str) or not model.existFrame(name):
        known = sorted({f.name for f in model.frames})
        raise InputError(
            f"no frame named {name!r} in the model (known frames: {', '.join(known[:40])}"
            + (", ..." if len(known) > 40 else "")
            + ")",
            field=str(name),
        )
    return model.getFrameId(name)


def _parse_tasks(
    targets: Mapping, weights: Mapping[str, float] | None
) -> tuple[list[OrientationTask], list[np.ndarray]]:
    if not isinstance(targets, Mapping) or len(targets) == 0:
        raise InputError("targets must be a non-empty dict frame -> (N, 3, 3) world rotations")
    weights = dict(weights or {})
    tasks, arrays = [], []
    for key, value in targets.items():
        task = key if isinstance(key, OrientationTask) else OrientationTask(str(key))
        w = float(weights.pop(task.frame, task.weight))
        if not np.isfinite(w) or w < 0:
            raise InputError(f"weight must be a finite number >= 0, got {w}", field=task.frame)
        tasks.append(OrientationTask(task.frame, w))
        arr = np.asarray(value, dtype=float)
        if arr.ndim == 2:
            arr = arr[None]
        if arr.ndim != 3 or arr.shape[1:] != (3, 3):
            raise InputError(
                f"expected (N, 3, 3) rotation matrices, got shape {arr.shape}", field=task.frame
            )
        arrays.append(arr)
    if weights:
        raise InputError(f"weights given for frames without targets: {sorted(weights)}")
    n = {a.shape[0] for a in arrays}
    if len(n) != 1:
        raise InputError(f"all targets need the same number of frames, got {sorted(n)}")
    for task, arr in zip(tasks, arrays, strict=True):
        ok = np.all(np.isfinite(arr), axis=(1, 2))
        if ok.any():
            a = arr[ok]
            ortho = np.abs(np.swapaxes(a, 1, 2) @ a - np.eye(3)).max()
            det = np.abs(np.linalg.det(a) - 1.0).max()
            if ortho > 1e-3 or det > 1e-3:
                raise InputError(
                    "targets must be rotation matrices (R^T R = I, det 1); "
                    f"deviation {max(ortho, det):.3g}",
                    field=task.frame,
                )
    return tasks, arrays


def _support_dofs(model: pin.Model, fids: list[int]) -> np.ndarray:
    """Tangent indices that rotate at least one task frame (structural, checked numerically)."""
    joints: set[int] = set()
    for fid in fids:
        j = model.frames[fid].parentJoint
        while j > 0:
            joints.add(j)
            j = model.parents[j]
    cand = sorted(
        v
        for j in joints
        for v in range(model.joints[j].idx_v, model.joints[j].idx_v + model.nvs[j])
    )
    # drop DoFs with an identically zero angular Jacobian (translations, prismatic joints)
    data = model.createData()
    rng = np.random.default_rng(0)
    seen = np.zeros(model.nv, dtype=bool)
    for _ in range(2):
        qr = pin.integrate(model, pin.neutral(model), rng.uniform(-1.0, 1.0, model.nv))
        pin.computeJointJacobians(model, data, qr)
        for fid in fids:
            seen |= (
                np.abs(pin.getFrameJacobian(model, data, fid, pin.LOCAL)[3:]).max(axis=0) > 1e-12
            )
    return np.array([v for v in cand if seen[v]], dtype=int)


def _joints_of(model: pin.Model, cols: np.ndarray) -> list[int]:
    return sorted({j for j in range(1, model.njoints) for v in cols if _owns(model, j, v)})


def _owns(model: pin.Model, j: int, v: int) -> bool:
    return model.joints[j].idx_v <= v < model.joints[j].idx_v + model.nvs[j]


def _q_of_v(model: pin.Model, v: int) -> int:
    """Configuration index of tangent index ``v`` of a one-DoF (nq = nv = 1) joint."""
    j = next(j for j in range(1, model.njoints) if _owns(model, j, v))
    return model.joints[j].idx_q


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
    present (off by default: with white orientation noise it costs iterations). Raises
    ``InputError`` on unknown frames, wrong shapes, non-rotation targets or weights < 0.
    """
    tasks, arrays = _parse_tasks(targets, weights)
    fids = [_frame_id(model, t.frame) for t in tasks]
    k, N = len(tasks), arrays[0].shape[0]
    Rt = np.stack(arrays, axis=1)  # (N, k, 3, 3)
    if root is not None:
        root = np.asarray(root, dtype=float)
        if root.shape not in ((3, 3), (N, 3, 3)):
            raise InputError(
                f"expected (3, 3) or ({N}, 3, 3), got shape {root.shape}", field="root"
            )
        root = np.broadcast_to(root, (N, 3, 3))
        Rt = np.swapaxes(root, 1, 2)[:, None] @ Rt
    RtT = np.ascontiguousarray(np.swapaxes(Rt, 2, 3))
    finite = np.all(np.isfinite(Rt), axis=(2, 3))  # (N, k)

    q_ref = pin.neutral(model) if q0 is None else np.asarray(q0, dtype=float).copy()
    if q_ref.shape != (model.nq,) or not np.all(np.isfinite(q_ref)):
        raise InputError(
            f"expected a finite ({model.nq},) configuration, got {q_ref.shape}", field="q0"
        )

    cols = _support_dofs(model, fids)
    na = cols.size
    if na == 0:
        raise InputError("no joint of the model rotates any of the target frames")
    cs = slice(cols[0], cols[-1] + 1) if np.all(np.diff(cols) == 1) else cols

    # box limits on tangent DoFs of 1-DoF joints (q and v coincide there)
    lo, hi, qidx = joint_box(model, cols, limits)
    bounded = qidx >= 0
    bq, blo, bhi = qidx[bounded], lo[bounded], hi[bounded]
    has_limits = bool(bounded.any())
    if has_limits:
        q_ref[bq] = np.clip(q_ref[bq], blo, bhi)

    weights = np.array([t.weight for t in tasks])
    # support masks: DoF a (of cols) rotates task frame i
    masks = np.zeros((k, na))
    for i, fid in enumerate(fids):
        sup = set(model.supports[model.frames[fid].parentJoint])
        masks[i] = [any(_owns(model, j, int(v)) for j in sup) for v in cols]
    euclid = all(model.nqs[j] == 1 and model.nvs[j] == 1 for j in _joints_of(model, cols))
    qcols = np.array([_q_of_v(model, v) for v in cols]) if euclid else cols
    cq = slice(qcols[0], qcols[-1] + 1) if np.all(np.diff(qcols) == 1) else qcols
    bsel = np.flatnonzero(bounded)
    all_bounded = bool(bounded.all())
    data = model.createData()
    Q = np.full((N, model.nq), np.nan)
    iters = np.zeros(N, dtype=int)
    conv = np.zeros(N, dtype=bool)
    U = np.empty((3, k))  # world-frame residuals u_i = R_i r_i = log3(R_i R_i*^T)
    v = np.zeros(model.nv)
    mu_eye = damping * np.eye(na)
    lam = float(regularization)
    q = q_ref.copy()
    log3_, cjj, ufp = pin.log3, pin.computeJointJacobians, pin.updateFramePlacement

    def world_axes(data=data, rs=(6, model.nv)):  # angular rows of the WORLD joint Jacobians
        return data.J.reshape(rs)[3:, cs]

    def normal_weights(w):
        Wm = masks.T * w  # (na, k)
        return Wm, Wm @ masks  # sum_i w_i m_i m_i^T

    Wm_all, C_all = normal_weights(weights)
    all_finite = finite.all(axis=1)
    tasks_range = list(enumerate(fids))
    for n in range(N):
        if all_finite[n]:
            Rn, Wm, C = RtT[n], Wm_all, C_all
        else:
            fin = finite[n]
            if not fin.any():
                continue
            Rn = np.where(fin[:, None, None], RtT[n], np.eye(3))
            Wm, C = normal_weights(weights * fin)
        if extrapolate and euclid and n >= 2 and all_finite[n - 2 : n + 1].all():
            q[cq] += Q[n - 1, cq] - Q[n - 2, cq]  # constant-velocity prediction
            if has_limits:
                q[bq] = np.clip(q[bq], blo, bhi)
        margin = box_margin(q[bq], blo, bhi) if has_limits else np.inf
        prev = np.inf
        for it in range(1, max_iters + 1):
            iters[n] = it
            cjj(model, data, q)
            for i, fid in tasks_range:
                U[:, i] = log3_(ufp(model, data, fid).rotation @ Rn[i])
            Wa = world_axes()
            # J_i^w = R_i^T (Wa o m_i): J^T W J = (Wa^T Wa) o C; J^T W r = rowsum((Wa^T U) o Wm)
            H = (Wa.T @ Wa) * C + mu_eye
            g = ((Wa.T @ U) * Wm).sum(axis=1)
            if lam > 0.0:
                e = pin.difference(model, q_ref, q)[cols]
                De = pin.dDifference(model, q_ref, q, pin.ARG1)[np.ix_(cols, cols)]
                H += lam * (De.T @ De)
                g += lam * (De.T @ e)
            d = -dposv(H, g)[1]
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
            if euclid:
                q[cq] += d
            else:
                v[cs] = d
                q = pin.integrate(model, q, v)
            if clipped:
                q[bq] = np.clip(q[bq], blo, bhi)
                margin = box_margin(q[bq], blo, bhi)
            else:
                margin -= dn
            # stop when the linear-rate estimate of the error left after this step,
            # |d|^2 / (|d_prev| - |d|), is below tol / 10 (the rate seen over the first steps
            # underestimates the asymptotic one by up to ~6x on noisy hinge fits), or on a step
            # below tol / 10
            if dn < 0.1 * tol or (
                it > 1 and prev > 2.0 * dn and 10.0 * dn * dn < tol * (prev - dn)
            ):
                conv[n] = True
                break
            prev = dn
        Q[n] = q

    # residuals at the returned configurations (vectorised log map)
    R_fit = np.stack(list(frame_rotations(model, Q, [t.frame for t in tasks]).values()), axis=1)
    ok = np.all(np.isfinite(R_fit), axis=(2, 3)) & finite
    err = np.full((N, k), np.nan)
    if ok.any():
        err[ok] = np.linalg.norm(log3(RtT[ok] @ R_fit[ok]), axis=-1)
    count = ok.sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        rms = np.sqrt(np.where(ok, err, 0.0) ** 2 @ np.ones(k) / count)
    rms[count == 0] = np.nan
    return IKResult(Q, rms, iters, conv, err, tuple(tasks))
