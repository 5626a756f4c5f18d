"""Many frames at once: the Gauss-Newton step of :func:`pipeline.ik.solver.solve_frame` taken
for a block of frames together, in NumPy.

The per-frame solver spends most of its time in Python around small Pinocchio calls. Here the
same iteration (module :mod:`pipeline.ik.solver`),

    (A^T A o C + mu I) dq = -rowsum((A^T U) o W_m),   U_i = log3(R_i(q) R_i*^T),

is evaluated for every frame of a block with array operations: the world rotations of the joints
by forward kinematics over the block (:class:`JointRotations`, from the model's joint placements
and axes: the same rotations Pinocchio computes, checked by the tests), the world joint axes
``A`` (3, na) of each frame, and one batched linear solve. Every frame keeps the per-frame stopping
test and leaves the block when it meets it, so each returned ``q`` is within ``tol`` of its optimum,
exactly as with :func:`~pipeline.ik.solver.solve_frame`.

Warm start (frames are independent once each has a starting point): every ``stride``-th frame is
solved by the per-frame solver, warm-started from the previous one of them, as the sequential
solver does; each frame between two of them starts from the interpolation of their solutions
(linear in the revolute angles, normalised linear in the quaternion of a spherical root). The
optimum reached is the one the sequential solver reaches (tested within ``tol``); only the number
of iterations differs.

The per-frame solver takes over, from the block's last iterate, where the block cannot match it:
frames that did not converge within ``max_iters`` and frames with a missing target. Joint limits
are handled in the block by projected Newton (:func:`solve_block`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pipeline.ik.problem import IKProblem
from pipeline.rotations import log3, matrix_from_quat_xyzw, quat_xyzw_integrate, skew

__all__ = ["BlockSetup", "JointRotations", "block_frame_rotations", "block_setup", "solve_block"]

_AXES = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}


@dataclass(frozen=True)
class _Joint:
    index: int
    parent: int
    placement: np.ndarray  # rotation of the joint frame in its parent joint's frame (3, 3)
    kind: str  # "revolute" | "spherical" | "freeflyer"
    axis: np.ndarray | None  # unit axis of a revolute joint, in its own frame
    iq: int
    iv: int


class JointRotations:
    """World rotations of a model's joints, vectorised over configurations (forward kinematics
    of the rotational part only: ``R_j = R_parent(j) M_j R_j(q_j)``, ``M_j`` the joint placement).

    ``joints``: the joint indices needed (with their ancestors). Revolute joints (``RX``, ``RY``,
    ``RZ``, unaligned) rotate by ``I + sin q K + (1 - cos q) K^2``, spherical and free-flyer joints
    by their configuration quaternion (scalar-last). Other joint types raise ``ValueError``.
    """

    def __init__(self, model: pin.Model, joints: set[int]):
        needed: set[int] = set()
        for j in joints:
            while j > 0:
                needed.add(j)
                j = model.parents[j]
        self.joints: list[_Joint] = []
        for j in sorted(needed):  # Pinocchio orders parents before children
            jm = model.joints[j]
            name = jm.shortname()
            axis = None
            if name in _AXES:
                kind, axis = "revolute", np.eye(3)[_AXES[name]]
            elif name == "JointModelRevoluteUnaligned":
                kind, axis = "revolute", np.asarray(jm.extract().axis, dtype=float).copy()
            elif name == "JointModelSpherical":
                kind = "spherical"
            elif name == "JointModelFreeFlyer":
                kind = "freeflyer"
            else:
                raise ValueError(f"joint type {name} is not vectorised")
            R = np.asarray(model.jointPlacements[j].rotation, dtype=float).copy()
            self.joints.append(_Joint(j, int(model.parents[j]), R, kind, axis, jm.idx_q, jm.idx_v))
        self._MK = {}  # (M, M K, M K^2) of each revolute joint
        for jt in self.joints:
            if jt.kind == "revolute":
                K = skew(jt.axis)
                self._MK[jt.index] = (jt.placement, jt.placement @ K, jt.placement @ K @ K)

    def world(self, Q: np.ndarray) -> dict[int, np.ndarray]:
        """``{joint: (B, 3, 3)}`` world rotations for configurations ``Q`` (B, nq).

        A revolute joint's ``R_parent M (I + s K + c K^2)`` (``s = sin q``, ``c = 1 - cos q``) is
        evaluated as ``R_parent M + s R_parent (M K) + c R_parent (M K^2)`` on the (3B, 3) stack of
        rows: three BLAS products with constant matrices, ~3x faster than ``np.matmul``'s per-item
        loop over (B, 3, 3) stacks.
        """
        B = Q.shape[0]
        out: dict[int, np.ndarray] = {}
        for jt in self.joints:
            if jt.kind == "revolute":
                a = Q[:, jt.iq]
                s, c = np.sin(a), 1.0 - np.cos(a)
                M, MK, MK2 = self._MK[jt.index]
                if jt.parent == 0:
                    out[jt.index] = M + s[:, None, None] * MK + c[:, None, None] * MK2
                else:
                    s, c = np.repeat(s, 3)[:, None], np.repeat(c, 3)[:, None]
                    R = out[jt.parent].reshape(-1, 3)
                    r = R @ M
                    r += s * (R @ MK)
                    r += c * (R @ MK2)
                    out[jt.index] = r.reshape(B, 3, 3)
            else:
                iq = jt.iq + (3 if jt.kind == "freeflyer" else 0)
                Rj = matrix_from_quat_xyzw(Q[:, iq : iq + 4]).reshape(B, 3, 3)
                if jt.parent != 0:
                    out[jt.index] = times(out[jt.parent], jt.placement) @ Rj
                elif np.array_equal(jt.placement, np.eye(3)):
                    out[jt.index] = Rj
                else:
                    out[jt.index] = jt.placement @ Rj
        return out

    def tangent_plan(
        self, model: pin.Model, cols: np.ndarray
    ) -> tuple[list[int], np.ndarray, list[tuple[_Joint, np.ndarray, np.ndarray]]]:
        """For the tangent indices ``cols``: each one's joint, its rotation axis in that joint's
        frame (a revolute joint's axis; the unit axes of a spherical or free-flyer joint's angular
        velocity, Pinocchio's LOCAL convention), and per joint the positions in ``cols`` and the
        angular components they move (for :meth:`integrate`)."""
        owners, axes, plan = [], [], []
        for jt in self.joints:
            off = 3 if jt.kind == "freeflyer" else 0
            sel = np.flatnonzero((cols >= jt.iv + off) & (cols < jt.iv + model.nvs[jt.index]))
            if sel.size == 0:
                continue
            comps = cols[sel] - jt.iv - off
            plan.append((jt, sel, comps))
        for v in cols:
            jt, _, comps = next(e for e in plan if v in cols[e[1]])
            owners.append(jt.index)
            off = 3 if jt.kind == "freeflyer" else 0
            axes.append(jt.axis if jt.kind == "revolute" else np.eye(3)[int(v - jt.iv - off)])
        return owners, np.array(axes), plan

    @staticmethod
    def integrate(Q: np.ndarray, d: np.ndarray, plan: list) -> np.ndarray:
        """``pin.integrate`` of the tangent steps ``d`` (B, na) (``plan`` from
        :meth:`tangent_plan`): revolute angles add, quaternions move by ``q (x) exp(w)``."""
        Q = Q.copy()
        for jt, sel, comps in plan:
            if jt.kind == "revolute":
                Q[:, jt.iq] += d[:, sel[0]]
            else:
                iq = jt.iq + (3 if jt.kind == "freeflyer" else 0)
                w = np.zeros((Q.shape[0], 3))
                w[:, comps] = d[:, sel]
                Q[:, iq : iq + 4] = quat_xyzw_integrate(Q[:, iq : iq + 4], w)
        return Q

    def normalize(self, Q: np.ndarray) -> np.ndarray:
        """Configurations with their quaternions normalised (after an interpolation)."""
        Q = Q.copy()
        for jt in self.joints:
            if jt.kind != "revolute":
                iq = jt.iq + (3 if jt.kind == "freeflyer" else 0)
                Q[:, iq : iq + 4] /= np.linalg.norm(Q[:, iq : iq + 4], axis=1, keepdims=True)
        return Q


@dataclass
class BlockSetup:
    """Per-trial constants of the block solver: kinematics, the frames' parent joints and
    placements, the owners and axes of the solved DoFs."""

    kin: JointRotations
    frame_joints: list[int]
    frame_rotations: np.ndarray  # (k, 3, 3)
    owners: list[int]
    axes: np.ndarray  # (na, 3)
    plan: list


def block_setup(p: IKProblem) -> BlockSetup | None:
    """The block solver's constants for problem ``p``, or ``None`` where it does not apply
    (a joint type it does not vectorise, or a regularised problem)."""
    model = p.model
    if p.regularization > 0.0:
        return None
    parents = [model.frames[f].parentJoint for f in p.fids]
    try:
        kin = JointRotations(model, set(parents))
    except ValueError:
        return None
    rots = np.array([model.frames[f].placement.rotation for f in p.fids])
    owners, axes, plan = kin.tangent_plan(model, p.cols)
    return BlockSetup(kin, parents, rots, owners, axes, plan)


def times(R: np.ndarray, M: np.ndarray) -> np.ndarray:
    """``R @ M`` for a stack ``R`` (B, 3, 3) and one matrix ``M`` (3, 3) (or a vector (3,)),
    through one BLAS product (``np.matmul`` broadcasts it item by item, ~6x slower)."""
    B = R.shape[0]
    return (R.reshape(-1, 3) @ M).reshape((B, 3, 3) if M.ndim == 2 else (B, 3))


def block_frame_rotations(b: BlockSetup, Q: np.ndarray) -> np.ndarray:
    """World rotations (B, k, 3, 3) of the task frames at configurations ``Q`` (B, nq); rows of
    ``Q`` with NaN give NaN."""
    Rw = b.kin.world(Q)
    return np.stack([times(Rw[j], P) for j, P in zip(b.frame_joints, b.frame_rotations,
                                                     strict=True)], axis=1)  # fmt: skip


def solve_block(
    p: IKProblem, b: BlockSetup, frames: np.ndarray, Q: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Newton on ``frames`` (all targets present) from ``Q`` (B, nq, inside the joint box):
    ``(Q, iterations, converged)``, with the stopping test of
    :func:`~pipeline.ik.solver.solve_frame` per frame.

    Joint limits by projected Newton (Bertsekas 1982): a bounded DoF at a bound whose gradient
    points out of the box is held (its row and column of the normal matrix replaced by the
    identity, its step 0), the others take the reduced Gauss-Newton step, and the result is
    clipped to the box. A fixed point is a KKT point of the bounded problem, the optimum the
    per-frame active-set solver reaches.
    """
    B = frames.size
    Q = np.array(Q, dtype=float)
    iters = np.zeros(B, dtype=int)
    conv = np.zeros(B, dtype=bool)
    active = np.arange(B)
    prev = np.full(B, np.inf)
    Wm, C, mu_eye, tol = p.Wm_all, p.C_all, p.mu_eye, p.tol
    bq, bsel, blo, bhi = p.bq, p.bsel, p.blo, p.bhi
    na = p.cols.size
    for it in range(1, p.max_iters + 1):
        Qa = Q[active]
        Rw = b.kin.world(Qa)
        Rf = np.stack([times(Rw[j], P) for j, P in zip(b.frame_joints, b.frame_rotations,
                                                       strict=True)], axis=1)  # fmt: skip
        U = log3((Rf @ p.RtT[frames[active]]).reshape(-1, 3, 3)).reshape(active.size, -1, 3)
        A = np.stack([times(Rw[j], a) for j, a in zip(b.owners, b.axes, strict=True)], axis=2)
        At = np.swapaxes(A, 1, 2)
        H = At @ A * C + mu_eye  # (Ba, na, na)
        g = ((At @ np.swapaxes(U, 1, 2)) * Wm).sum(axis=2)  # (Ba, na)
        if bq.size:
            qb = Qa[:, bq]
            held = np.zeros((active.size, na), dtype=bool)
            held[:, bsel] = ((qb <= blo) & (g[:, bsel] > 0.0)) | ((qb >= bhi) & (g[:, bsel] < 0.0))
            rows = np.flatnonzero(held.any(axis=1))
            if rows.size:
                h, free = held[rows], (~held[rows]).astype(float)
                H[rows] = H[rows] * free[:, :, None] * free[:, None, :] + h[:, :, None] * np.eye(na)
                g[rows] *= free
        d = -np.linalg.solve(H, g[..., None])[..., 0]
        if bq.size:
            d[:, bsel] = np.clip(qb + d[:, bsel], blo, bhi) - qb
        dn = np.abs(d).max(axis=1)
        Q[active] = b.kin.integrate(Qa, d, b.plan)
        pa = prev[active]
        done = (dn < 0.1 * tol) | ((it > 1) & (pa > 2.0 * dn) & (10.0 * dn * dn < tol * (pa - dn)))
        iters[active] = it
        conv[active[done]] = True
        prev[active] = dn
        active = active[~done]
        if active.size == 0:
            break
    return Q, iters, conv
