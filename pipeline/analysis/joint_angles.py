"""ISB joint angles from segment frames and model configurations.

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

import numpy as np

from pipeline.analysis.landmarks import CHUNK, check_configurations, frame_trajectories
from pipeline.errors import InputError
from pipeline.model.conventions import JOINT_SEGMENTS
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import euler_zxy_from_matrix

__all__ = ["ANGLE_NAMES", "angles_of_segments", "jcs_angles", "joint_angles", "segment_names"]

#: Joint -> the names of its three JCS angles (the ankle's third is not in the model).
ANGLE_NAMES = {"hip": ("flexion", "adduction", "rotation"),
               "knee": ("flexion", "adduction", "rotation"),
               "ankle": ("flexion", "inversion", "rotation")}


def jcs_angles(R_proximal: np.ndarray, R_distal: np.ndarray, joint: str, side: str) -> np.ndarray:
    """ISB joint angles ``(N, 3)`` = [flexion, adduction, internal rotation] (rad).

    ``R_proximal``, ``R_distal``: ``(N, 3, 3)`` or ``(3, 3)`` segment rotations in one world frame
    (ISB axes; left-leg frames mirrored). ``joint`` is ``'hip'`` or ``'knee'`` (knee flexion is
    ``-a`` of the Z-X-Y decomposition); see the module docstring for the signs.
    """
    if joint not in JOINT_SEGMENTS:
        raise InputError(f"expected joint 'hip', 'knee' or 'ankle', got {joint!r}",
                         field="joint")
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
    Q = check_configurations(skeleton, Q)
    out: dict[str, np.ndarray] = {}
    for start in range(0, len(Q), CHUNK):  # chunks of frames: bounded memory on long trials
        rows = slice(start, start + CHUNK)
        traj = frame_trajectories(skeleton, Q[rows], segment_names(skeleton.legs))
        chunk = angles_of_segments({seg: R for seg, (R, _) in traj.items()}, skeleton.legs)
        for name, v in chunk.items():
            out.setdefault(name, np.empty(len(Q)))[rows] = v
    return out


def segment_names(legs) -> list[str]:
    """The segments the joint angles of ``legs`` are taken between: the pelvis and each leg's."""
    return ["pelvis"] + [f"{s}_{seg}" for s in legs for seg in ("femur", "tibia", "foot")]


def angles_of_segments(rotations: dict[str, np.ndarray], legs) -> dict[str, np.ndarray]:
    """:func:`joint_angles` from the segments' world rotations (segment -> (N, 3, 3), the
    segments of :func:`segment_names`)."""
    out: dict[str, np.ndarray] = {}
    for side in legs:
        for joint, (prox, dist) in JOINT_SEGMENTS.items():
            p = prox if prox == "pelvis" else f"{side}_{prox}"
            ang = jcs_angles(rotations[p], rotations[f"{side}_{dist}"], joint, side)
            for i, name in enumerate(ANGLE_NAMES[joint][: 2 if joint == "ankle" else 3]):
                out[f"{side}_{joint}_{name}"] = ang[:, i]
    return out
