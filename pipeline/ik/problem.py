"""The per-trial setup of orientation IK (:func:`setup_ik`): inputs checked, targets in the
model's universe, the DoFs the tasks observe, box limits and the support masks of the normal
equations (see :mod:`pipeline.ik.solver` for the math)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.ik.bounds import dof_joints, joint_box
from pipeline.rotations import cross

__all__ = ["IKProblem", "OrientationTask", "frame_id", "setup_ik"]


@dataclass(frozen=True)
class OrientationTask:
    """Track the world orientation of model frame ``frame`` with weight ``weight`` (>= 0)."""

    frame: str
    weight: float = 1.0


def frame_id(model: pin.Model, name: str) -> int:
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
            ortho, det = _rotation_deviation(arr[ok])
            if ortho > 1e-3 or det > 1e-3:
                raise InputError(
                    "targets must be rotation matrices (R^T R = I, det 1); "
                    f"deviation {max(ortho, det):.3g}",
                    field=task.frame,
                )
    return tasks, arrays


def _rotation_deviation(a: np.ndarray) -> tuple[float, float]:
    """Largest ``|R^T R - I|`` entry and ``|det R - 1|`` over a stack (M, 3, 3), from the columns'
    dot products and triple product (no per-matrix product: ~5x faster than ``a^T @ a``)."""
    c = [a[:, :, i] for i in range(3)]
    dot = lambda u, v: np.einsum("ni,ni->n", u, v)  # noqa: E731
    ortho = max(np.abs(dot(c[i], c[i]) - 1.0).max() for i in range(3))
    ortho = max(ortho, *(np.abs(dot(c[i], c[j])).max() for i, j in ((0, 1), (0, 2), (1, 2))))
    det = np.abs(dot(c[0], cross(c[1], c[2])) - 1.0).max()
    return float(ortho), float(det)


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
    # drop DoFs with an identically zero angular Jacobian (translations, prismatic joints), seen
    # at two generic configurations: tangent steps in [-1, 1] from an additive (Weyl) sequence,
    # deterministic and free of special angles (numpy.random's import: ~7 ms of a command)
    data = model.createData()
    seen = np.zeros(model.nv, dtype=bool)
    for k in range(2):
        step = 2.0 * ((np.arange(1, model.nv + 1) * 0.6180339887 + 0.5 * k) % 1.0) - 1.0
        qr = pin.integrate(model, pin.neutral(model), step)
        pin.computeJointJacobians(model, data, qr)
        for fid in fids:
            seen |= (
                np.abs(pin.getFrameJacobian(model, data, fid, pin.LOCAL)[3:]).max(axis=0) > 1e-12
            )
    return np.array([v for v in cand if seen[v]], dtype=int)


@dataclass
class IKProblem:
    """Everything :func:`solve_frame` needs, computed once per trial by :func:`setup_ik`.

    ``RtT`` (N, k, 3, 3) the transposed targets in the model's universe; ``finite`` (N, k) which
    targets are present; ``cols`` the tangent DoFs some task rotates (``cs`` a slice or index
    array of them); ``masks`` (k, na) which of those DoFs move each task frame; the box limits
    ``bq, blo, bhi`` (q indices and bounds of the bounded 1-DoF joints); ``euclid`` whether all
    solved joints are 1-DoF (then ``q[cq] += d``, else ``pin.integrate``).
    """

    model: pin.Model
    data: pin.Data
    tasks: tuple[OrientationTask, ...]
    fids: list[int]
    RtT: np.ndarray
    finite: np.ndarray
    q_ref: np.ndarray
    cols: np.ndarray
    cs: slice | np.ndarray
    cq: slice | np.ndarray
    masks: np.ndarray
    weights: np.ndarray
    bq: np.ndarray
    blo: np.ndarray
    bhi: np.ndarray
    bsel: np.ndarray
    euclid: bool
    max_iters: int
    tol: float
    damping: float
    regularization: float
    extrapolate: bool
    Wm_all: np.ndarray = field(repr=False, default=None)
    C_all: np.ndarray = field(repr=False, default=None)
    mu_eye: np.ndarray = field(repr=False, default=None)  # damping * I (na, na)
    all_bounded: bool = False

    @property
    def n_frames(self) -> int:
        return self.RtT.shape[0]

    @property
    def has_limits(self) -> bool:
        return self.bq.size > 0

    def normal_weights(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(W_m, C)``: ``W_m = masks^T o w`` (na, k) and ``C = sum_i w_i m_i m_i^T`` (na, na)."""
        Wm = self.masks.T * w
        return Wm, Wm @ self.masks


def setup_ik(
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
) -> IKProblem:
    """Check the inputs of :func:`solve_ik` (same arguments) and precompute the per-trial data."""
    tasks, arrays = _parse_tasks(targets, weights)
    fids = [frame_id(model, t.frame) for t in tasks]
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
    owners = dof_joints(model)
    owner = [int(owners[v]) for v in cols]
    for i, fid in enumerate(fids):
        sup = set(model.supports[model.frames[fid].parentJoint])
        masks[i] = [j in sup for j in owner]
    euclid = all(model.nqs[j] == 1 and model.nvs[j] == 1 for j in set(owner))
    qcols = np.array([model.idx_qs[j] for j in owner]) if euclid else cols  # 1-DoF: q of v
    cq = slice(qcols[0], qcols[-1] + 1) if np.all(np.diff(qcols) == 1) else qcols
    bsel = np.flatnonzero(bounded)
    problem = IKProblem(model, model.createData(), tuple(tasks), fids, RtT, finite, q_ref, cols, cs,
                        cq, masks, weights, bq, blo, bhi, bsel, euclid, max_iters, tol,
                        float(damping), float(regularization), extrapolate)
    problem.Wm_all, problem.C_all = problem.normal_weights(weights)
    problem.mu_eye = float(damping) * np.eye(na)
    problem.all_bounded = bool(bounded.all())
    return problem
