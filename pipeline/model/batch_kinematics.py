"""Forward kinematics of a Pinocchio model vectorised over many configurations, in NumPy.

Pinocchio's ``forwardKinematics`` takes one configuration per call; a trial is thousands of them,
and the Python loop around the calls costs more than the kinematics. :class:`JointRotations`
evaluates the same joint and frame poses for a whole stack of configurations with array
operations (checked against Pinocchio in ``tests/test_model_batch_kinematics.py``), for the
joint types the subject models use: revolute (``RX``, ``RY``, ``RZ``, unaligned), spherical and
free-flyer. Used by the block IK solver (:mod:`pipeline.ik.block`) and the landmark trajectories
(:mod:`pipeline.analysis.landmarks`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pipeline.rotations import matrix_from_quat_xyzw, quat_xyzw_integrate, skew

__all__ = ["JointRotations", "times"]

_AXES = {"JointModelRX": 0, "JointModelRY": 1, "JointModelRZ": 2}


@dataclass(frozen=True)
class _Joint:
    index: int
    parent: int
    placement: np.ndarray  # rotation of the joint frame in its parent joint's frame (3, 3)
    offset: np.ndarray  # origin of the joint frame in its parent joint's frame (3,)
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
            M = model.jointPlacements[j]
            R, t = (np.asarray(x, dtype=float).copy() for x in (M.rotation, M.translation))
            self.joints.append(_Joint(j, int(model.parents[j]), R, t, kind, axis, jm.idx_q,
                                      jm.idx_v))
        self._MK = {}  # (M, M K, M K^2) of each revolute joint
        self._cols = {}  # revolute joints about +-e_k: (i, j, k, sign, M is the identity)
        revolute = [jt for jt in self.joints if jt.kind == "revolute"]
        self._rev_iq = [jt.iq for jt in revolute]  # their configuration entries
        self._rev_row = {jt.index: r for r, jt in enumerate(revolute)}
        for jt in self.joints:
            if jt.kind == "revolute":
                K = skew(jt.axis)
                self._MK[jt.index] = (jt.placement, jt.placement @ K, jt.placement @ K @ K)
                unit = _unit_axis(jt.axis)
                if unit is not None and jt.parent != 0:
                    k, sign = unit
                    ident = bool(np.array_equal(jt.placement, np.eye(3)))
                    self._cols[jt.index] = ((k + 1) % 3, (k + 2) % 3, k, sign, ident)

    def world(self, Q: np.ndarray) -> dict[int, np.ndarray]:
        """``{joint: (B, 3, 3)}`` world rotations for configurations ``Q`` (B, nq).

        A revolute joint about a unit axis ``+-e_k`` (the ``RX``, ``RY``, ``RZ`` joints and the
        mirrored left-leg axes) mixes two columns of ``P = R_parent M``: with ``(i, j, k)``
        cyclic, ``R e_i = c P_i + s P_j``, ``R e_j = c P_j - s P_i``, ``R e_k = P_k`` (``s``
        signed by the axis). Any other axis: ``R_parent M (I + s K + (1 - c) K^2)`` evaluated
        as ``R_parent M + s R_parent (M K) + (1 - c) R_parent (M K^2)`` on the (3B, 3) stack of
        rows, three BLAS products with constant matrices (~3x faster than ``np.matmul``'s
        per-item loop over (B, 3, 3) stacks).
        """
        B = Q.shape[0]
        out: dict[int, np.ndarray] = {}
        if self._rev_iq:  # every revolute joint's sine and cosine in one call each
            sines, cosines = np.sin(Q[:, self._rev_iq]).T, np.cos(Q[:, self._rev_iq]).T
        for jt in self.joints:
            if jt.kind == "revolute":
                cols = self._cols.get(jt.index)
                if cols is not None:
                    i, j, k, sign, ident = cols
                    P = out[jt.parent] if ident else times(out[jt.parent], jt.placement)
                    r = self._rev_row[jt.index]
                    s = (sines[r] if sign > 0 else -sines[r])[:, None]
                    c = cosines[r][:, None]
                    Pi, Pj = P[:, :, i], P[:, :, j]
                    R = np.empty_like(P)
                    R[:, :, i] = c * Pi + s * Pj
                    R[:, :, j] = c * Pj - s * Pi
                    R[:, :, k] = P[:, :, k]
                    out[jt.index] = R
                    continue
                r = self._rev_row[jt.index]
                s, c = sines[r], 1.0 - cosines[r]
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
        :meth:`tangent_plan`): revolute angles add (one indexed addition for all of them),
        quaternions move by ``q (x) exp(w)``."""
        Q = Q.copy()
        rq = [jt.iq for jt, _, _ in plan if jt.kind == "revolute"]
        if rq:
            Q[:, rq] += d[:, [sel[0] for jt, sel, _ in plan if jt.kind == "revolute"]]
        for jt, sel, comps in plan:
            if jt.kind != "revolute":
                iq = jt.iq + (3 if jt.kind == "freeflyer" else 0)
                w = np.zeros((Q.shape[0], 3))
                w[:, comps] = d[:, sel]
                Q[:, iq : iq + 4] = quat_xyzw_integrate(Q[:, iq : iq + 4], w)
        return Q

    @staticmethod
    def axis_columns(owners: list[int], axes: np.ndarray
                     ) -> list[tuple[int, int, float, np.ndarray]]:
        """Per tangent DoF (``owners``, ``axes`` from :meth:`tangent_plan`): ``(joint, k, sign,
        axis)``, its world axis being ``sign`` times column ``k`` of the joint's rotation when
        the axis is ``+-e_k`` (``k = -1``: any other axis), for :meth:`world_axes`."""
        out = []
        for j, a in zip(owners, axes, strict=True):
            k, sign = _unit_axis(a) or (-1, 0.0)
            out.append((j, k, sign, a))
        return out

    @staticmethod
    def world_axes(Rw: dict[int, np.ndarray], columns: list) -> np.ndarray:
        """World axes (B, na, 3) of tangent DoFs (``columns`` from :meth:`axis_columns`) given
        the joints' world rotations ``Rw``: ``R_j a``, a column of ``R_j`` (signed) when
        ``a = +-e_k``."""
        B = next(iter(Rw.values())).shape[0]
        At = np.empty((B, len(columns), 3))
        for col, (j, k, sign, a) in enumerate(columns):
            if k < 0:
                At[:, col] = times(Rw[j], a)
            elif sign > 0:
                At[:, col] = Rw[j][:, :, k]
            else:
                np.negative(Rw[j][:, :, k], out=At[:, col])
        return At

    def poses(self, Q: np.ndarray) -> dict[int, tuple[np.ndarray, np.ndarray]]:
        """``{joint: (R (B, 3, 3), p (B, 3))}`` world poses for configurations ``Q`` (B, nq):
        ``p_j = p_parent + R_parent (t_j + M_j t(q_j))``, ``t(q)`` the translation of a free
        flyer (zero for the other joints)."""
        Rw = self.world(Q)
        out: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        for jt in self.joints:
            local = np.broadcast_to(jt.offset, (Q.shape[0], 3))
            if jt.kind == "freeflyer":
                local = local + Q[:, jt.iq : jt.iq + 3] @ jt.placement.T
            if jt.parent == 0:
                p = np.array(local)
            else:
                Rp, pp = out[jt.parent]
                p = pp + np.einsum("nij,nj->ni", Rp, local)
            out[jt.index] = (Rw[jt.index], p)
        return out

    def frame_poses(
        self, model: pin.Model, Q: np.ndarray, frame_ids: list[int]
    ) -> tuple[np.ndarray, np.ndarray]:
        """World rotations (k, B, 3, 3) and positions (k, B, 3) of model frames ``frame_ids``
        (their parent joints must be among this object's joints)."""
        poses = self.poses(Q)
        R = np.empty((len(frame_ids), Q.shape[0], 3, 3))
        p = np.empty((len(frame_ids), Q.shape[0], 3))
        for i, fid in enumerate(frame_ids):
            f = model.frames[fid]
            if f.parentJoint == 0:
                R[i], p[i] = f.placement.rotation, f.placement.translation
                continue
            Rj, pj = poses[f.parentJoint]
            R[i] = times(Rj, np.asarray(f.placement.rotation))
            p[i] = pj + times(Rj, np.asarray(f.placement.translation))
        return R, p

    def normalize(self, Q: np.ndarray) -> np.ndarray:
        """Configurations with their quaternions normalised (after an interpolation)."""
        Q = Q.copy()
        for jt in self.joints:
            if jt.kind != "revolute":
                iq = jt.iq + (3 if jt.kind == "freeflyer" else 0)
                Q[:, iq : iq + 4] /= np.linalg.norm(Q[:, iq : iq + 4], axis=1, keepdims=True)
        return Q


def _unit_axis(a: np.ndarray) -> tuple[int, float] | None:
    """``(k, sign)`` when the unit axis ``a`` is ``sign * e_k``, else None."""
    k = int(np.argmax(np.abs(a)))
    return (k, float(a[k])) if abs(a[k]) == 1.0 else None


def times(R: np.ndarray, M: np.ndarray) -> np.ndarray:
    """``R @ M`` for a stack ``R`` (B, 3, 3) and one matrix ``M`` (3, 3) (or a vector (3,)),
    through one BLAS product (``np.matmul`` broadcasts it item by item, ~6x slower)."""
    B = R.shape[0]
    return (R.reshape(-1, 3) @ M).reshape((B, 3, 3) if M.ndim == 2 else (B, 3))
