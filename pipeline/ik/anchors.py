"""Where the strided IK (:func:`pipeline.ik.solver.solve_ik`) solves frames in sequence, and
how the other frames get their starting points.

Anchors are frames solved one after the other, each from the one before, as the sequential solver
does, so that the solution follows the motion's basin of the least-squares problem; the frames
between them are solved in blocks (:mod:`pipeline.ik.block`) from the cubic through the solved
frames around them (:func:`interpolate`). Anchors come every ``stride`` frames, and closer where
the joint rotations are fast (:func:`anchor_frames`).
"""

from __future__ import annotations

import numpy as np

from pipeline.ik.problem import IKProblem

__all__ = ["ANCHOR_TOL", "ANCHOR_TURN_RAD", "anchor_frames", "interpolate", "parent_tasks"]


#: Tolerance (rad) of the anchors' sequential solve: it only has to keep the motion's basin; the
#: block then takes them to ``tol`` together (:func:`pipeline.ik.solver.solve_ik`).
ANCHOR_TOL = 1e-2

#: Largest rotation (rad, ~57 deg) of any target relative to its parent segment's target (of a
#: top target, such as the pelvis, in the world), summed along the trial, between two anchors:
#: where the motion is fast the anchors come closer (down to every frame), so that no frame starts
#: from an interpolation of joint coordinates across a large turn (a pelvis turning round, a knee
#: flexing fast, a recording spliced end to end: there the interpolated start can lie in another
#: basin of the least-squares problem). Relative rotations are what the interpolated joint
#: coordinates follow: a foot swinging with its leg turns fast in the world, not at its joints.
ANCHOR_TURN_RAD = 1.0


def parent_tasks(p: IKProblem) -> list[int]:
    """Per task, the task on the nearest joint above its own (-1 for a top task)."""
    model = p.model
    joint_task: dict[int, int] = {}
    for i, fid in enumerate(p.fids):
        joint_task.setdefault(int(model.frames[fid].parentJoint), i)
    parents = []
    for fid in p.fids:
        own = int(model.frames[fid].parentJoint)
        j = int(model.parents[own]) if own > 0 else 0
        while j > 0 and j not in joint_task:
            j = int(model.parents[j])
        parents.append(joint_task.get(j, -1) if j > 0 else -1)
    return parents


def anchor_frames(p: IKProblem, stride: int) -> np.ndarray:
    """Every ``stride``-th frame and the last, and more where the targets' rotation (relative to
    their parent target: :data:`ANCHOR_TURN_RAD`) summed since the previous anchor exceeds
    :data:`ANCHOR_TURN_RAD`."""
    N = p.n_frames
    if N < 2:
        return np.arange(N)
    R = np.swapaxes(p.RtT, 2, 3)  # (N, k, 3, 3) targets
    parents = parent_tasks(p)
    rel = np.array(R)
    for i, j in enumerate(parents):
        if j >= 0:
            rel[:, i] = p.RtT[:, j] @ R[:, i]  # R_j^T R_i
    tr = np.einsum("nkij,nkij->nk", rel[1:], rel[:-1])  # tr(A_{n-1}^T A_n), per task
    turn = np.arccos(np.clip(0.5 * (tr - 1.0), -1.0, 1.0))
    turn = np.nan_to_num(turn, nan=0.0).max(axis=1)  # (N-1,): from frame n to n + 1
    out, acc, last = [0], 0.0, 0
    for n, t in enumerate(turn.tolist(), start=1):
        acc += t
        if acc > ANCHOR_TURN_RAD or n - last >= stride:
            if t > ANCHOR_TURN_RAD and n - 1 > last:
                out.append(n - 1)  # a jump: no frame is interpolated across it
            out.append(n)
            acc, last = 0.0, n
    if out[-1] != N - 1:
        out.append(N - 1)
    return np.array(out)


def interpolate(ref: np.ndarray, known: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Starting points at frames ``at`` from the solutions ``known[ref]``: the cubic through the
    two solved frames on each side (Lagrange in the frame index; exact for cubic motion, so that
    most frames converge in one or two steps), linear where a side has only one or where an outer
    interval changes by more than 0.5 rad in a coordinate (a jump: the cubic would overshoot)."""
    right = np.minimum(np.searchsorted(ref, at), ref.size - 1)
    i1, i2 = np.maximum(right - 1, 0), right
    i0, i3 = np.maximum(i1 - 1, 0), np.minimum(i2 + 1, ref.size - 1)
    x = at.astype(float)
    nodes = [ref[i].astype(float) for i in (i0, i1, i2, i3)]
    cubic = (i0 < i1) & (i2 < i3)
    step = lambda a, b: np.abs(known[ref[a]] - known[ref[b]]).max(axis=1)  # noqa: E731
    cubic &= (step(i0, i1) < 0.5) & (step(i2, i3) < 0.5)
    w = np.zeros((at.size, 4))
    for k in range(4):
        wk = np.ones(at.size)
        for m in range(4):
            if m != k:
                with np.errstate(invalid="ignore", divide="ignore"):
                    wk *= (x - nodes[m]) / (nodes[k] - nodes[m])
        w[:, k] = wk
    with np.errstate(invalid="ignore", divide="ignore"):
        t = np.nan_to_num((x - nodes[1]) / (nodes[2] - nodes[1]))
    w = np.where(cubic[:, None], np.nan_to_num(w), np.c_[np.zeros_like(t), 1.0 - t, t,
                                                        np.zeros_like(t)])
    return sum(w[:, k, None] * known[ref[i]] for k, i in enumerate((i0, i1, i2, i3)))
