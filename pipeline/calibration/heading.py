"""The subject's heading at the calibration pose: which horizontal direction is its right.

Orientation IK in a world whose y axis points up needs the heading ``H`` (a rotation about the
vertical) of the subject at the calibration pose. Two ways:

* ``'anatomical'`` (default): from the motion itself, independent of how the sensors were mounted.
  The hip flexes about +right and the knee about -right, so the dominant axis of the thigh's
  rotation relative to the pelvis, and minus that of the shank relative to the thigh (both
  expressed at t0, weighted by angle, over the frames of largest excursion), give the right
  direction; projected on the horizontal plane it fixes ``H`` (forward = up x right).
* ``'pelvis_imu:<axis>'``: OpenSense's convention, an axis of the pelvis sensor points forward.
"""

from __future__ import annotations

import numpy as np

from pipeline.calibration.conventions import HEADINGS
from pipeline.errors import InputError
from pipeline.quantiles import quantile
from pipeline.rotations import (
    angle_between,
    axis_angle,
    euler_xyz_fixed_from_matrix,
    normalize,
    rot_y,
    rotation_aligning,
)

__all__ = [
    "FLEXION_RANGE",
    "HEADINGS",
    "UP",
    "anatomical_right",
    "check_vertical",
    "dominant_axis",
    "heading_rotation",
    "pelvis_axis_right",
    "subject_right",
    "turning_axis",
]

UP = np.array([0.0, 1.0, 0.0])


def dominant_axis(
    R_ref: np.ndarray, R_moving: np.ndarray, top: float = 0.2
) -> tuple[np.ndarray | None, float]:
    """Angle-weighted mean axis (world, at t0) of the moving sensor's rotation relative to the
    reference sensor since t0, over the ``top`` fraction of frames with the largest angle."""
    rel = np.swapaxes(R_ref, 1, 2) @ R_moving
    change = rel @ rel[0].T  # rotation in the reference sensor's coordinates
    axis, angle = axis_angle(change)
    ok = np.isfinite(angle) & (angle > 0)
    if ok.sum() < 10:
        return None, 0.0
    thresh = quantile(angle[ok], 1.0 - top)
    sel = ok & (angle >= thresh)
    v = np.sum(axis[sel] * angle[sel, None], axis=0)
    if np.linalg.norm(v) == 0:
        return None, 0.0
    return R_ref[0] @ normalize(v), float(np.max(angle[ok]))


def turning_axis(
    R: np.ndarray, min_turn: float = np.radians(60.0), top: float = 0.2
) -> tuple[np.ndarray | None, float]:
    """The line (unit vector, sign arbitrary, world frame) a segment turns about over a trial.

    With ``C(t) = R(t) R(0)^T`` the world-frame rotation since t0 (axis ``a_t``, angle
    ``theta_t``), the line is the principal eigenvector of ``sum theta_t a_t a_t^T`` over the
    ``top`` fraction of frames with the largest angle (sign-free, so a half turn's ambiguous axis
    sign does not matter). For the pelvis of a walking subject the large rotations are the turns,
    about the vertical. Returns ``(None, max angle)`` when the segment turns less than
    ``min_turn`` rad: the motion then does not define the vertical.
    """
    change = R @ np.swapaxes(R[0], 0, 1)[None]
    axis, angle = axis_angle(change)
    ok = np.isfinite(angle) & (angle > 0)
    largest = float(np.max(angle[ok])) if ok.any() else 0.0
    if ok.sum() < 10 or largest < min_turn:
        return None, largest
    sel = ok & (angle >= quantile(angle[ok], 1.0 - top))
    scatter = np.einsum("n,ni,nj->ij", angle[sel], axis[sel], axis[sel])
    return normalize(np.linalg.eigh(scatter)[1][:, -1]), largest


def check_vertical(
    pelvis: np.ndarray,
    notes: list[str] | None = None,
    tolerance: float = np.radians(30.0),
    applied: np.ndarray | None = None,
) -> None:
    """Refuse a recording whose pelvis turns about an axis that is not the model's up (y).

    A subject who walks and turns turns about the vertical; when that line is more than
    ``tolerance`` from y, the world is not y-up (e.g. an Xsens z-up world given without
    ``--sensor-to-model``) and the subject would be laid on its side. The message names the
    rotation that fixes it; whether the recording's vertical points up or down cannot be told
    from orientations alone, so both signs are given, as complete ``--sensor-to-model`` values
    (including the rotation ``applied`` already; angles within 3 deg of a quarter turn are
    rounded to it). When the pelvis turns too little the check is skipped, with a note.
    """
    line, largest = turning_axis(pelvis)
    if line is None:
        if notes is not None:
            notes.append(
                f"the world's vertical was not checked: the pelvis turns at most "
                f"{np.degrees(largest):.0f} deg (check that --sensor-to-model makes y point up)"
            )
        return
    tilt = float(np.degrees(np.arccos(min(1.0, abs(float(line @ UP))))))
    if tilt <= np.degrees(tolerance):
        return
    fixes = []
    W = np.eye(3) if applied is None else np.asarray(applied, dtype=float)
    own = W.T @ line  # the line in the recording's own frame: point it along +axis
    k = int(np.argmax(np.abs(own)))
    line = line if own[k] > 0 else -line
    for sign in (1.0, -1.0):
        R = rotation_aligning(sign * line, UP) @ W
        angles = euler_xyz_fixed_from_matrix(R)  # space-fixed X-Y-Z, as OpenSense
        quarter = np.round(angles / (np.pi / 2)) * (np.pi / 2)
        angles = np.where(np.abs(angles - quarter) < np.radians(3.0), quarter, angles) + 0.0
        fixes.append(" ".join(f"{v:.4f}" for v in angles))
    axis_name = "xyz"[k]
    raise InputError(
        f"the pelvis turns about the recording's {axis_name} axis ({tilt:.0f} deg from the "
        "model's up, y): the world is not y-up and the subject would lie on its side; give "
        f"--sensor-to-model {fixes[0]} (if {axis_name} points up, e.g. Xsens, OpenSense) or "
        f"{fixes[1]} (if it points down, e.g. NED)",
        field="sensor_to_model",
    )


#: Plausible flexion ranges (rad) that orient a flexion axis: a hip rarely extends beyond
#: -40 deg or flexes beyond 140 deg, a knee neither hyperextends beyond -10 deg nor flexes
#: beyond 160 deg.
FLEXION_RANGE = {"hip": (np.radians(-40.0), np.radians(140.0)),
                 "knee": (np.radians(-10.0), np.radians(160.0))}


def _signed_excursion(R_ref: np.ndarray, R_mov: np.ndarray, line: np.ndarray) -> np.ndarray:
    """``phi(t)``: the moving sensor's rotation since t0 relative to the reference sensor, signed
    about ``line`` (world at t0); the opposite line gives ``-phi``."""
    rel = np.swapaxes(R_ref, 1, 2) @ R_mov
    axis, angle = axis_angle(rel @ rel[0].T)
    ok = np.isfinite(angle) & np.all(np.isfinite(axis), axis=-1)  # no axis at zero angle
    return angle[ok] * np.sign(axis[ok] @ (R_ref[0].T @ line))


def _range_violation(flex: np.ndarray, joint: str) -> float:
    """How far (rad, summed over frames) the flexion ``flex`` leaves :data:`FLEXION_RANGE`."""
    lo, hi = FLEXION_RANGE[joint]
    return float(np.sum(np.clip(lo - flex, 0, None) + np.clip(flex - hi, 0, None)))


def anatomical_right(
    rotations: dict[str, np.ndarray],
    min_excursion: float = 0.35,
    notes: list[str] | None = None,
    start_flexion: tuple[float, float] = (0.0, 0.0),
    knee_axes: dict[str, np.ndarray] | None = None,
) -> np.ndarray:
    """The subject's right at t0 from hip (+right) and knee (-right) flexion (module doc, step 3).

    ``knee_axes``: per side, the knee's flexion axis (pointing right) in the world of the
    calibration pose at zero heading, e.g. the femur's orientation in that pose times the
    reference AoR ``a_F`` (None: the model's right, a knee flexing about the femur's z). The knee
    AoR is tilted from the femur's z (Wang 2023: ~10 deg in the femur's frontal plane, ~9 deg
    in its transverse plane); seen from above, its tilt turns the knee's cue by the angle
    between the horizontal part of that axis and the right, which is taken out here (standing,
    the transverse tilt shows and cancels between two legs that both move; lying supine, the
    frontal tilt shows, and a single moving leg would turn the heading by half of it).

    ``start_flexion``: the hip and knee flexion at t0 (rad): zero standing or supine, 90 deg
    seated. Each cue's line is the dominant axis of the relative rotation since t0; its sign is
    the one whose flexion ``start + phi(t)`` stays within :data:`FLEXION_RANGE` (a seated knee
    extends from 90 deg, so its largest excursions are extensions), and, when both signs keep
    it plausible (a hip swinging about the standing pose), the sign of the largest excursions
    (flexion from standing). Raises :class:`InputError` when the motion is too small to define
    an axis (less than ``min_excursion`` rad of hip or knee rotation). When a cue points more
    than 45 deg away from the others' mean (horizontal directions), a note says so: the heading
    may then be unreliable.
    """
    cues = []
    for side in ("right", "left"):
        pairs = (("pelvis", f"{side}_femur", 1.0, "hip", start_flexion[0]),
                 (f"{side}_femur", f"{side}_tibia", -1.0, "knee", start_flexion[1]))
        for ref, mov, sign, joint, start in pairs:
            if ref in rotations and mov in rotations:
                axis, excursion = dominant_axis(rotations[ref], rotations[mov])
                if axis is not None and excursion >= min_excursion:
                    # flexion = sign * (rotation about right): right = sign * axis keeps the
                    # largest excursions flexions; check that against the joint's range
                    phi = _signed_excursion(rotations[ref], rotations[mov], sign * axis)
                    keep = _range_violation(start + sign * phi, joint)
                    flip = _range_violation(start - sign * phi, joint)  # about -sign * axis
                    cue = -sign * axis if flip < keep else sign * axis
                    if joint == "knee" and knee_axes is not None and side in knee_axes:
                        k = np.asarray(knee_axes[side], dtype=float)
                        cue = rot_y(-np.arctan2(k[0], k[2])) @ cue  # k's heading taken out
                    cues.append(cue)
    if not cues:
        raise InputError(
            "the hips and knees barely move: the subject's right cannot be found from the motion; "
            "give the heading explicitly (e.g. --heading pelvis_imu:-z)",
            field="heading",
        )
    right = np.mean(cues, axis=0)
    if notes is not None and len(cues) > 1:
        flat = [c - UP * (c @ UP) for c in cues]
        spread = max(np.degrees(angle_between(c, right - UP * (right @ UP))) for c in flat)
        if spread > 45.0:
            notes.append(
                f"the hip and knee flexion axes disagree by up to {spread:.0f} deg: the anatomical "
                "heading may be unreliable; check the result or give --heading"
            )
    horizontal = right - UP * (right @ UP)
    if np.linalg.norm(horizontal) < 0.3 * np.linalg.norm(right):
        raise InputError(
            "the flexion axes point vertically: is the world's up axis y? Set --sensor-to-model "
            "(e.g. -1.5708 0 0 for an Xsens z-up world)",
            field="sensor_to_model",
        )
    return normalize(horizontal)


def heading_rotation(right: np.ndarray) -> np.ndarray:
    """Rotation about the vertical (y) taking the model's right (z) to the horizontal ``right``."""
    # Ry(psi) @ z = (sin psi, 0, cos psi) must equal (r_x, 0, r_z): psi = atan2(r_x, r_z)
    psi = np.arctan2(right[0], right[2])
    return rot_y(psi)


def pelvis_axis_right(rotations: dict[str, np.ndarray], spec: str) -> np.ndarray:
    """The subject's right from an axis of the pelvis sensor (OpenSense's ``base_heading_axis``):
    ``spec`` is ``'pelvis_imu:-z'`` style; forward is that axis at t0, made horizontal, and
    right = forward x up."""
    axis = spec.split(":")[1]
    sign = -1.0 if axis.startswith("-") else 1.0
    forward = sign * rotations["pelvis"][0][:, "xyz".index(axis[-1])]
    forward = forward - UP * (forward @ UP)
    if np.linalg.norm(forward) < 1e-3:
        raise InputError(f"pelvis sensor axis {axis} is vertical at t0", field="heading")
    return normalize(np.cross(normalize(forward), UP))  # right = forward x up


def subject_right(rotations: dict[str, np.ndarray], heading: str = "anatomical",
                  notes: list[str] | None = None,
                  start_flexion: tuple[float, float] = (0.0, 0.0),
                  knee_axes: dict[str, np.ndarray] | None = None) -> np.ndarray:
    """The subject's horizontal right at t0 by the ``heading`` method (one of :data:`HEADINGS`;
    ``start_flexion`` and ``knee_axes`` as :func:`anatomical_right`)."""
    if heading not in HEADINGS:
        raise InputError(f"expected one of {HEADINGS}, got {heading!r}", field="heading")
    if heading == "anatomical":
        return anatomical_right(rotations, notes=notes, start_flexion=start_flexion,
                                knee_axes=knee_axes)
    return pelvis_axis_right(rotations, heading)
