"""Many frames at once: the Gauss-Newton step of :func:`pipeline.ik.solver.solve_frame` taken
for a block of frames together, in NumPy.

The per-frame solver spends most of its time in Python around small Pinocchio calls. Here the
same iteration (module :mod:`pipeline.ik.solver`),

    (A^T A o C + mu I) dq = -rowsum((A^T U) o W_m),   U_i = log3(R_i(q) R_i*^T),

is evaluated for every frame of a block with array operations: the world rotations of the joints
by forward kinematics over the block (:class:`~pipeline.model.batch_kinematics.JointRotations`:
the rotations Pinocchio computes, from the model's joint placements and axes), the world joint
axes ``A`` (3, na) of each frame, and one batched linear solve. Every frame keeps the per-frame
stopping test and leaves the block when it meets it, so each returned ``q`` is within ``tol`` of
its optimum, exactly as with :func:`~pipeline.ik.solver.solve_frame`.

Warm start (frames are independent once each has a starting point): anchor frames (every
``stride``-th, closer where the targets turn fast relative to their parent targets) are solved by
the per-frame solver, each warm-started from the previous one, as the sequential solver does, to
a loose tolerance (they only have to keep the motion's basin) and then to ``tol`` together in a
block; every other frame starts from the cubic through the solved frames around it, quaternions
renormalised (:func:`pipeline.ik.solver.solve_ik` drives this). The optimum reached is the one the
sequential solver reaches (tested within ``tol``); only the number of iterations differs.

The per-frame solver takes over, from the block's last iterate, where the block cannot match it:
frames that did not converge within ``max_iters`` and frames with a missing target. Joint limits
are handled in the block by projected Newton (:func:`solve_block`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pipeline.ik.problem import IKProblem
from pipeline.model.batch_kinematics import JointRotations, times
from pipeline.rotations import log3

__all__ = ["BlockSetup", "block_frame_rotations", "block_setup", "solve_block"]


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
    fixed_q: np.ndarray  # configuration entries no solved DoF moves (held at q_ref)
    root: np.ndarray  # DoFs coupled with every other one (a floating pelvis), positions in cols
    groups: list[np.ndarray]  # the other DoFs in mutually uncoupled groups (one per leg)
    columns: list = field(init=False)  # the DoFs' world axes as columns (JointRotations)
    root_index: slice | np.ndarray = field(init=False)  # root / groups as slices where ranges:
    group_index: list = field(init=False)  # views, not copies, of the normal matrix

    def __post_init__(self) -> None:
        self.columns = self.kin.axis_columns(self.owners, self.axes)
        self.root_index = _as_index(self.root)
        self.group_index = [_as_index(g) for g in self.groups]


def _as_index(a: np.ndarray) -> slice | np.ndarray:
    if a.size and np.array_equal(a, np.arange(a[0], a[0] + a.size)):
        return slice(int(a[0]), int(a[0]) + a.size)
    return a


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
    moved = set()
    for jt, _, _ in plan:
        if jt.kind == "revolute":
            moved.add(jt.iq)
        else:
            iq = jt.iq + (3 if jt.kind == "freeflyer" else 0)
            moved |= set(range(iq, iq + 4))
    fixed = np.array(sorted(set(range(model.nq)) - moved), dtype=int)
    root, groups = _coupling(p.C_all)
    return BlockSetup(kin, parents, rots, owners, axes, plan, fixed, root, groups)


def _coupling(C: np.ndarray) -> tuple[np.ndarray, list[np.ndarray]]:
    """The normal matrix's sparsity (``H = (A^T A) o C`` is zero where ``C`` is): the DoFs coupled
    with all others (``root``) and the connected groups of the rest. One group and no root: the
    dense solve."""
    na = C.shape[0]
    linked = C != 0.0
    root = np.flatnonzero(linked.all(axis=1))
    seen = set(root.tolist())  # the root joins no group
    groups = []
    for a in range(na):
        if a in seen:
            continue
        stack, group = [a], []
        seen.add(a)
        while stack:
            x = stack.pop()
            group.append(x)
            for y in np.flatnonzero(linked[x]).tolist():
                if y not in seen:
                    seen.add(y)
                    stack.append(y)
        groups.append(np.array(sorted(group), dtype=int))
    if len(groups) <= 1:
        return np.array([], dtype=int), [np.arange(na)]
    return root, groups


def _solve_normal(At: np.ndarray, g: np.ndarray, C: np.ndarray, mu: float, b: BlockSetup,
                  free: np.ndarray | None) -> np.ndarray:
    """``x`` with ``H x = g`` for every frame, ``H = (A^T A) o C + mu I`` (``At = A^T``: (B, na,
    3), the world axes of the DoFs as rows), the rows and columns of held DoFs (``free == 0``)
    replaced by the identity.

    ``A^T A`` of every frame in one stacked product, then arrowhead elimination where the model
    allows it (:func:`_coupling`): each group's block ``H_gg`` is solved against
    ``[H_gR | g_g]``, the root's Schur complement ``S = H_RR - sum_g H_Rg H_gg^-1 H_gR`` gives
    ``x_R``, then ``x_g = H_gg^-1 (g_g - H_gR x_R)``: two 8 x 8 solves and a 3 x 3 instead of one
    19 x 19 for a floating pelvis and two legs.
    """
    H = At @ np.ascontiguousarray(np.swapaxes(At, 1, 2))  # stacked products: contiguous
    H *= C
    diag = np.arange(H.shape[1])
    H[:, diag, diag] += mu
    if free is not None:  # held DoFs (few): their rows and columns replaced by the identity
        fb, fa = np.nonzero(free == 0.0)
        H[fb, fa, :] = 0.0
        H[fb, :, fa] = 0.0
        H[fb, fa, fa] = 1.0
    r = b.root
    out = np.empty_like(g)
    if not b.root.size:
        for grp in b.group_index:
            out[:, grp] = np.linalg.solve(H[:, grp][:, :, grp], g[:, grp, None])[..., 0]
        return out
    r = b.root_index
    S = H[:, r][:, :, r]
    t = g[:, r].copy()
    parts = []
    for grp in b.group_index:
        HgR = H[:, grp][:, :, r]
        X = np.linalg.solve(H[:, grp][:, :, grp], np.concatenate([HgR, g[:, grp, None]], axis=2))
        HRg = np.swapaxes(HgR, 1, 2)
        S -= HRg @ X[:, :, :-1]
        t -= (HRg @ X[:, :, -1:])[..., 0]
        parts.append((grp, X))
    xR = np.linalg.solve(S, t[..., None])
    out[:, r] = xR[..., 0]
    for grp, X in parts:
        out[:, grp] = X[:, :, -1] - (X[:, :, :-1] @ xR)[..., 0]
    return out


def block_frame_rotations(b: BlockSetup, Q: np.ndarray) -> np.ndarray:
    """World rotations (B, k, 3, 3) of the task frames at configurations ``Q`` (B, nq); rows of
    ``Q`` with NaN give NaN."""
    return _task_rotations(b, b.kin.world(Q))


def _task_rotations(b: BlockSetup, Rw: dict[int, np.ndarray]) -> np.ndarray:
    """The task frames' world rotations (B, k, 3, 3) from the joints' ``Rw``."""
    return np.stack([times(Rw[j], P) for j, P in zip(b.frame_joints, b.frame_rotations,
                                                     strict=True)], axis=1)


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
    Wm, C, tol = p.Wm_all, p.C_all, p.tol
    bq, bsel, blo, bhi = p.bq, p.bsel, p.blo, p.bhi
    na = p.cols.size
    for it in range(1, p.max_iters + 1):
        Qa = Q[active]
        Rw = b.kin.world(Qa)
        Rf = _task_rotations(b, Rw)
        U = log3((Rf @ p.RtT[frames[active]]).reshape(-1, 3, 3)).reshape(active.size, -1, 3)
        At = b.kin.world_axes(Rw, b.columns)  # (Ba, na, 3)
        # g_a = sum_i Wm[a, i] (A_a . u_i) = A_a . (Wm U)_a
        g = np.einsum("bac,bac->ba", At, Wm @ U)  # (Ba, na)
        free = None
        if bq.size:
            qb = Qa[:, bq]
            held = np.zeros((active.size, na), dtype=bool)
            held[:, bsel] = ((qb <= blo) & (g[:, bsel] > 0.0)) | ((qb >= bhi) & (g[:, bsel] < 0.0))
            if held.any():
                free = (~held).astype(float)
                g *= free
        d = -_solve_normal(At, g, C, p.damping, b, free)
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
