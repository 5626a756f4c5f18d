"""Anatomical landmark trajectories and segment poses from model configurations.

Landmarks (Wang et al. 2023, eq 15-17): the landmark frames of the scaled model are fixed in their
segments, so their trajectories are the forward kinematics of those frames. With the hip at the
origin, the femoral landmarks follow ``t = e_F p`` (eq 15), the knee centre
``t_knee = (t_EFL + t_EFM) / 2`` (eq 16) and the malleoli ``t = e_T p + t_knee`` (eq 17).
Joint angles are :mod:`pipeline.analysis.joint_angles`.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.model.batch_kinematics import JointRotations
from pipeline.model.skeleton import Skeleton

__all__ = ["CHUNK", "check_configurations", "frame_trajectories", "landmark_trajectories",
           "wang_trajectories"]

#: Frames per chunk of forward kinematics: bounded memory on long recordings.
CHUNK = 10_000


def check_configurations(skeleton: Skeleton, Q: np.ndarray) -> np.ndarray:
    Q = np.asarray(Q, dtype=float)
    if Q.ndim == 1:
        Q = Q[None]
    if Q.ndim != 2 or Q.shape[1] != skeleton.nq:
        raise InputError(f"expected configurations of shape (N, {skeleton.nq}), got {Q.shape}")
    return Q


def frame_trajectories(
    skeleton: Skeleton, Q: np.ndarray, names: Sequence[str]
) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """World rotations ``(N, 3, 3)`` and positions ``(N, 3)`` of frames over configurations ``Q``.

    Vectorised over the samples (:class:`~pipeline.model.batch_kinematics.JointRotations`, in
    blocks of 10,000); one ``pin.forwardKinematics`` per sample for joint types it does not
    cover. Rows of ``Q`` with NaN give NaN.
    """
    R, p = _frame_poses(skeleton, Q, names, rotations=True)
    return {name: (R[i], p[i]) for i, name in enumerate(names)}


def _frame_poses(skeleton: Skeleton, Q: np.ndarray, names: Sequence[str], rotations: bool):
    Q = check_configurations(skeleton, Q)
    model = skeleton.model
    ids = [skeleton.frame_id(n) for n in names]
    n = len(Q)
    R = np.full((len(ids), n, 3, 3), np.nan) if rotations else None
    p = np.full((len(ids), n, 3), np.nan)
    ok = np.flatnonzero(np.all(np.isfinite(Q), axis=1))
    try:
        kin = JointRotations(model, {model.frames[f].parentJoint for f in ids})
    except ValueError:
        kin = None
    if kin is None:
        data = skeleton.data
        for k in ok:
            pin.forwardKinematics(model, data, Q[k])
            for i, fid in enumerate(ids):
                M = pin.updateFramePlacement(model, data, fid)
                p[i, k] = M.translation
                if rotations:
                    R[i, k] = M.rotation
    else:
        for lo in range(0, ok.size, CHUNK):
            rows = ok[lo : lo + CHUNK]
            Rc, p[:, rows] = kin.frame_poses(model, Q[rows], ids)
            if rotations:
                R[:, rows] = Rc
    return R, p


def landmark_trajectories(
    skeleton: Skeleton, Q: np.ndarray, names: Sequence[str] | None = None
) -> dict[str, np.ndarray]:
    """Landmark name -> ``(N, 3)`` world positions (m) over configurations ``Q`` ``(N, nq)``.

    Default names: every landmark frame of the model (``right_EFM``, ..., ``left_LM``). This is
    Wang eq 15-17 evaluated by forward kinematics (positions only: memory stays at 24 bytes per
    landmark and sample on long recordings).
    """
    names = list(skeleton.landmark_frames if names is None else names)
    _, p = _frame_poses(skeleton, Q, names, rotations=False)
    return {name: p[i] for i, name in enumerate(names)}


def wang_trajectories(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    femur_landmarks: dict[str, np.ndarray],
    tibia_landmarks: dict[str, np.ndarray],
) -> dict[str, np.ndarray]:
    """Wang et al. 2023 eq 15-17 in closed form, hip at the origin, vectorised over frames.

    ``t_EFL,EFM = e_F p`` (eq 15), ``t_knee = (t_EFL + t_EFM) / 2`` (eq 16),
    ``t_LM,MM = e_T p + t_knee`` (eq 17). Returns EFM, EFL, KJC, MM, LM as (N, 3). Identical to the
    forward kinematics of the free-knee model's landmark frames (tested); used where a whole trial
    of orientations is already in segment frames and no joint limits apply.
    """
    F = np.asarray(femur_R, dtype=float)
    T = np.asarray(tibia_R, dtype=float)
    if F.shape != T.shape or F.ndim != 3 or F.shape[1:] != (3, 3):
        raise InputError(f"expected (N, 3, 3) femur and tibia rotations, got {F.shape}, {T.shape}")
    out = {n: F @ np.asarray(femur_landmarks[n], dtype=float) for n in ("EFM", "EFL")}
    out["KJC"] = 0.5 * (out["EFM"] + out["EFL"])
    for n in ("MM", "LM"):
        out[n] = T @ np.asarray(tibia_landmarks[n], dtype=float) + out["KJC"]
    return out
