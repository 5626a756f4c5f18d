"""Anatomical landmark trajectories and ISB joint angles from model configurations.

Landmarks (Wang et al. 2023, eq 15-17): the landmark frames of the scaled model are fixed in their
segments, so their trajectories are the forward kinematics of those frames. With the hip at the
origin, the femoral landmarks follow ``t = e_F p`` (eq 15), the knee centre
``t_knee = (t_EFL + t_EFM) / 2`` (eq 16) and the malleoli ``t = e_T p + t_knee`` (eq 17).

Joint angles: the Grood & Suntay / ISB joint coordinate system (Wu et al. 2002) as a Z-X-Y
decomposition of the distal segment's rotation relative to the proximal one,
``R_p^T R_d = Rz(a) Rx(b) Ry(c)`` (Hu et al. 2021 eq 38-42):

* hip: flexion ``a``, adduction ``L b``, internal rotation ``L c``;
* knee: flexion ``-a`` (the tibia turns about -z when it flexes), adduction (varus) ``L b``,
  tibial internal rotation ``L c``;
* ankle (tibia -> foot): dorsiflexion ``a``, inversion ``L b`` (the model's ankle has no third
  rotation, so ``c`` is not reported);

with ``L = +1`` for the right leg and ``-1`` for the left leg, whose segment frames are mirrored
(z still to the subject's right): mirroring maps ``Rz(a) Rx(b) Ry(c)`` to ``Rz(a) Rx(-b) Ry(-c)``,
so the sign flip gives both legs the same anatomical meaning (adduction and internal rotation
positive). Radians throughout.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.model.batch_kinematics import JointRotations
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import euler_zxy_from_matrix

__all__ = [
    "frame_trajectories",
    "jcs_angles",
    "joint_angles",
    "landmark_trajectories",
    "wang_trajectories",
]

_JOINTS = {"hip": ("pelvis", "femur"), "knee": ("femur", "tibia"), "ankle": ("tibia", "foot")}
_CHUNK = 10_000
_ANGLE_NAMES = {"hip": ("flexion", "adduction", "rotation"),
                "knee": ("flexion", "adduction", "rotation"),
                "ankle": ("flexion", "inversion", "rotation")}  # fmt: skip


def _check_q(skeleton: Skeleton, Q: np.ndarray) -> np.ndarray:
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
    Q = _check_q(skeleton, Q)
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
        for lo in range(0, ok.size, _CHUNK):
            rows = ok[lo : lo + _CHUNK]
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


def jcs_angles(R_proximal: np.ndarray, R_distal: np.ndarray, joint: str, side: str) -> np.ndarray:
    """ISB joint angles ``(N, 3)`` = [flexion, adduction, internal rotation] (rad).

    ``R_proximal``, ``R_distal``: ``(N, 3, 3)`` or ``(3, 3)`` segment rotations in one world frame
    (ISB axes; left-leg frames mirrored). ``joint`` is ``'hip'`` or ``'knee'`` (knee flexion is
    ``-a`` of the Z-X-Y decomposition); see the module docstring for the signs.
    """
    if joint not in _JOINTS:
        raise InputError(f"expected joint 'hip', 'knee' or 'ankle', got {joint!r}",
                         field="joint")  # fmt: skip
    if side not in ("right", "left"):
        raise InputError(f"expected side 'right' or 'left', got {side!r}", field="side")
    Rp, Rd = np.asarray(R_proximal, dtype=float), np.asarray(R_distal, dtype=float)
    rel = np.swapaxes(Rp, -1, -2) @ Rd
    e = euler_zxy_from_matrix(rel)
    lat = 1.0 if side == "right" else -1.0
    flex = -e[..., 0] if joint == "knee" else e[..., 0]
    return np.stack([flex, lat * e[..., 1], lat * e[..., 2]], axis=-1)


def joint_angles(skeleton: Skeleton, Q: np.ndarray) -> dict[str, np.ndarray]:
    """ISB hip, knee and ankle angles over ``Q``: ``'<side>_<joint>_<angle>'`` -> ``(N,)`` rad.

    Keys: ``right_hip_flexion``, ``right_hip_adduction``, ``right_hip_rotation``,
    ``right_knee_flexion``, ``right_knee_adduction``, ``right_knee_rotation``,
    ``right_ankle_flexion`` (dorsiflexion), ``right_ankle_inversion`` (+ ``left_*``);
    rotation = internal rotation. Computed from the segment frames (not read from q), so a hinge
    knee reports its JCS angles including the reference rotation between the segments.
    """
    segs = ["pelvis"] + [f"{s}_{seg}" for s in skeleton.legs for seg in ("femur", "tibia", "foot")]
    Q = _check_q(skeleton, Q)
    out: dict[str, np.ndarray] = {}
    for start in range(0, len(Q), _CHUNK):  # chunks of frames: bounded memory on long trials
        rows = slice(start, start + _CHUNK)
        traj = frame_trajectories(skeleton, Q[rows], segs)
        for side in skeleton.legs:
            for joint, (prox, dist) in _JOINTS.items():
                p = prox if prox == "pelvis" else f"{side}_{prox}"
                ang = jcs_angles(traj[p][0], traj[f"{side}_{dist}"][0], joint, side)
                for i, name in enumerate(_ANGLE_NAMES[joint][: 2 if joint == "ankle" else 3]):
                    out.setdefault(f"{side}_{joint}_{name}", np.empty(len(Q)))[rows] = ang[:, i]
    return out


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
