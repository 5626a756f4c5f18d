"""Knee axis of rotation (AoR) from femur and tibia orientations, and its use to correct them.

Wang et al. 2023, §II.A eq 1-8 (estimate) and §II.B eq 9-13 (orientation correction). The
estimator only needs two orientation sequences, ``femur_R`` and ``tibia_R`` ``(N, 3, 3)`` (segment
axes as columns in the world), so the same code serves the optical data (femoral anatomical frame +
tibia marker cluster) and the inertial data (IMC femur and tibia segment frames):

* eq 1: tibia in the femoral frame ``F_R_T^k = (E_F^k)^T E_T^k``;
* eq 2: relative rotation from frame ``k`` to ``k+s``: ``F_R_knee^k = F_R_T^{k+s} (F_R_T^k)^T``;
* eq 3: axis ``F_V^k`` and angle ``A^k >= 0`` of that rotation;
* eq 4: world axis ``G_V^k = E_F^k F_V^k``; axes whose femoral z component is negative (knee
  flexion rather than extension, "pointing left") are reversed so every axis points right;
* pairs with a small angle are dropped (``A^k <= rel_angle_threshold * max A`` or
  ``A^k <= min_angle``), and, as in the reference code, axes with femoral ``z <= min_axis_z``;
* eq 5-6: angle-weighted mean in the femoral frame, ``sum A^k F_V^k`` normalised;
* eq 7-8: the same world axes in the tibial frame ``T_V^k = (E_T^k)^T G_V^k``, weighted mean.

Frame selection. The reference code used the samples where EFM's *vertical lab coordinate* lies
within 15-85 % of its range, which depends on the lab axes. Here the same band is applied to a
frame-independent motion coordinate computed from the orientations alone: by default
:func:`elevation_coordinate` (``sin`` of the hip flexion angle from the rest pose, proportional to
the knee height for a femur resting horizontal; on subjects 1-16 it gives AoRs within 0.2-1.7 deg
of the selection on EFM's lab Z, the vertical there), or ``window_coordinate="flexion"``, the hip
flexion angle itself (:func:`flexion_coordinate`; differs from the reference selection by up to
~5 deg because the knee height is not monotonic in the flexion angle beyond 90 deg). Each run of
consecutive valid samples inside the band is a window; within a window of ``L`` samples the step
is ``s = L // 2`` (windows shorter than ``min_length`` are skipped), giving the pairs
``(k, k + s)``.

Dispersion. ``sd_angle_*`` is the angle-weighted RMS of the angles between the per-pair axes and
the mean axis (radians).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import angle_between, axis_angle, normalize, rotation_aligning

__all__ = [
    "MIN_AXIS_Z",
    "KneeAoR",
    "PopulationAoR",
    "apply_correction",
    "correction_rotations",
    "elevation_coordinate",
    "flexion_coordinate",
    "frame_pairs",
    "knee_aor",
    "measured_aor",
    "population_aor",
    "projection_angles",
    "reexpress_tibia",
    "select_windows",
]

#: An AoR is kept only if its femoral z component exceeds this (the reference code's bound, eq 8:
#: within 53 deg of the medio-lateral axis); a knee axis elsewhere means frames that are off.
MIN_AXIS_Z = 0.6


@dataclass(frozen=True)
class KneeAoR:
    """Mean knee axis in the femoral and tibial frames (unit vectors) and the per-pair data.

    ``pairs`` ``(n, 2)`` holds the frame indices ``(k, k + s)`` kept; ``angles`` the rotation
    angles ``A^k`` (rad); ``femur_axes``, ``tibia_axes``, ``world_axes`` the per-pair unit axes in
    the femoral frame, the tibial frame and the world (all pointing right).
    """

    femur_axis: np.ndarray
    tibia_axis: np.ndarray
    n_pairs: int
    sd_angle_femur: float
    sd_angle_tibia: float
    pairs: np.ndarray
    angles: np.ndarray
    femur_axes: np.ndarray
    tibia_axes: np.ndarray
    world_axes: np.ndarray

    @classmethod
    def from_axes(cls, femur_axis: np.ndarray, tibia_axis: np.ndarray) -> KneeAoR:
        """A :class:`KneeAoR` carrying only two mean axes (normalised), no pairs: e.g. the
        whole-trial hinge fit's axes as the start of a correction when eq 1-8 find no pair."""
        empty = np.zeros((0, 3))
        return cls(
            femur_axis=normalize(femur_axis), tibia_axis=normalize(tibia_axis), n_pairs=0,
            sd_angle_femur=np.nan, sd_angle_tibia=np.nan, pairs=np.zeros((0, 2), dtype=int),
            angles=np.zeros(0), femur_axes=empty, tibia_axes=empty, world_axes=empty,
        )


# --------------------------------------------------------------------------------------------
# frame selection


def _valid_rows(*Rs: np.ndarray) -> np.ndarray:
    return np.logical_and.reduce([np.all(np.isfinite(R), axis=(1, 2)) for R in Rs])


def flexion_coordinate(femur_R: np.ndarray) -> np.ndarray:
    """Hip flexion angle (rad, up to sign and offset) from femur orientations alone.

    The femoral y axes ``y_k`` sweep (nearly) a plane during hip flexion; with ``n`` the normal of
    that plane (least-variance direction of the centred ``y_k``, SVD) and ``u`` the mean direction,
    the coordinate is the signed angle ``atan2(n . (u x y_k), u . y_k)``. It is invariant to the
    world frame. NaN where ``femur_R`` is NaN.
    """
    R = np.asarray(femur_R, dtype=float)
    y = R[:, :, 1]
    ok = np.all(np.isfinite(y), axis=1)
    out = np.full(len(y), np.nan)
    if ok.sum() < 3:
        return out
    yv = y[ok]
    u = normalize(yv.mean(axis=0))
    _, _, vt = np.linalg.svd(yv - yv.mean(axis=0), full_matrices=False)
    n = vt[2]
    out[ok] = np.arctan2(np.cross(u, yv) @ n, yv @ u)
    return out


def elevation_coordinate(femur_R: np.ndarray, tibia_R: np.ndarray) -> np.ndarray:
    """Frame-independent stand-in for the knee's height above the bed, ``sin|phi - phi_rest|``.

    ``phi`` is :func:`flexion_coordinate`. The rest end of its range (leg flat on the bed) is the
    end at which the knee is extended: going from that end to the other one the tibia rotates
    relative to the femur about an axis pointing left (knee flexion, eq 4 sign rule). For a femur
    resting horizontal, ``|HJC-KJC| sin|phi - phi_rest|`` is the knee height, so a 15-85 % band of
    this coordinate reproduces the reference's band on EFM's vertical lab coordinate without
    using the lab axes. NaN where either input is NaN.
    """
    F = np.asarray(femur_R, dtype=float)
    T = np.asarray(tibia_R, dtype=float)
    ok = _valid_rows(F, T)
    phi = flexion_coordinate(np.where(ok[:, None, None], F, np.nan))
    if not np.isfinite(phi).any():
        return phi
    k_lo, k_hi = int(np.nanargmin(phi)), int(np.nanargmax(phi))
    rel_lo, rel_hi = F[k_lo].T @ T[k_lo], F[k_hi].T @ T[k_hi]
    axis, _ = axis_angle(rel_hi @ rel_lo.T)
    rest = phi[k_lo] if np.nan_to_num(axis[2]) <= 0 else phi[k_hi]
    return np.sin(np.abs(phi - rest))


def select_windows(
    coordinate: np.ndarray,
    valid: np.ndarray | None = None,
    *,
    lower: float = 0.15,
    upper: float = 0.85,
    min_length: int = 10,
) -> list[tuple[int, int]]:
    """Half-open runs ``[a, b)`` of consecutive valid samples with the coordinate inside the band.

    The band is ``[min + lower * range, min + upper * range]`` of the valid samples (reference:
    15-85 %). Runs shorter than ``min_length`` samples are dropped.
    """
    c = np.asarray(coordinate, dtype=float)
    ok = np.isfinite(c) if valid is None else (np.asarray(valid, bool) & np.isfinite(c))
    if not ok.any():
        return []
    lo, hi = np.min(c[ok]), np.max(c[ok])
    a, b = lo + lower * (hi - lo), lo + upper * (hi - lo)
    inside = np.zeros(len(c), dtype=bool)
    inside[ok] = (c[ok] >= a) & (c[ok] <= b)
    d = np.diff(np.concatenate([[0], inside.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    return [(int(s), int(e)) for s, e in zip(starts, stops, strict=True) if e - s >= min_length]


def frame_pairs(windows: Sequence[tuple[int, int]], step: int | None = None) -> np.ndarray:
    """Frame pairs ``(k, k + s)`` inside each window; ``s`` = half the window unless given."""
    out = []
    for a, b in windows:
        s = (b - a) // 2 if step is None else int(step)
        if s < 1 or b - a <= s:
            continue
        k = np.arange(a, b - s)
        out.append(np.stack([k, k + s], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2), dtype=int)


# --------------------------------------------------------------------------------------------
# estimation (eq 1-8)


def _weighted_mean_axis(axes: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, float]:
    mean = normalize((w[:, None] * axes).sum(axis=0))
    dev = angle_between(axes, mean)
    return mean, float(np.sqrt(np.sum(w * dev**2) / np.sum(w)))


def knee_aor(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    *,
    tibia_frames_R: np.ndarray | None = None,
    pairs: np.ndarray | None = None,
    window: tuple[float, float] = (0.15, 0.85),
    window_coordinate: str = "elevation",
    min_window: int = 10,
    step: int | None = None,
    rel_angle_threshold: float = 0.5,
    min_angle: float = 0.0,
    min_axis_z: float = MIN_AXIS_Z,
) -> KneeAoR:
    """Knee AoR (Wang eq 1-8) from femur and tibia orientations ``(N, 3, 3)``.

    ``tibia_R`` is any tibia-fixed frame used for the relative rotation (eq 1; the marker cluster
    for OMC); ``tibia_frames_R`` the tibial frames in which the axis is expressed (eq 7; defaults
    to ``tibia_R``). ``pairs`` overrides the automatic frame selection (module docstring);
    ``window_coordinate`` is 'elevation' (default) or 'flexion'.
    Raises :class:`InputError` when no pair survives the thresholds (too little knee motion).
    """
    F = np.asarray(femur_R, dtype=float)
    T = np.asarray(tibia_R, dtype=float)
    if F.shape != T.shape or F.ndim != 3 or F.shape[1:] != (3, 3):
        raise ValueError(f"femur_R and tibia_R must both be (N, 3, 3), got {F.shape}, {T.shape}")
    TF = T if tibia_frames_R is None else np.asarray(tibia_frames_R, dtype=float)
    valid = _valid_rows(F, T, TF)
    if pairs is None:
        Fv = np.where(valid[:, None, None], F, np.nan)
        if window_coordinate == "elevation":
            coord = elevation_coordinate(Fv, T)
        elif window_coordinate == "flexion":
            coord = flexion_coordinate(Fv)
        else:
            raise ValueError(
                f"window_coordinate must be 'elevation' or 'flexion', got {window_coordinate!r}"
            )
        windows = select_windows(
            coord, valid, lower=window[0], upper=window[1], min_length=min_window
        )
        pairs = frame_pairs(windows, step)
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    pairs = pairs[valid[pairs[:, 0]] & valid[pairs[:, 1]]]
    if len(pairs) == 0:
        raise InputError("no usable frame pairs for the knee AoR (too little valid motion)")
    k0, k1 = pairs[:, 0], pairs[:, 1]
    rel = np.swapaxes(F, 1, 2) @ T  # eq 1
    r_knee = rel[k1] @ np.swapaxes(rel[k0], 1, 2)  # eq 2
    axes_f, angles = axis_angle(r_knee)  # eq 3
    ok = angles > 0
    axes_f = np.where(ok[:, None], axes_f, 0.0)
    axes_f = np.where(axes_f[:, 2:3] < 0, -axes_f, axes_f)  # point right
    keep = ok & (angles > rel_angle_threshold * angles.max()) & (angles > min_angle)
    keep &= axes_f[:, 2] > min_axis_z
    if not keep.any():
        raise InputError(
            "no frame pair passes the knee AoR thresholds (angle, axis direction); "
            f"largest relative rotation {np.degrees(angles.max()):.3g} deg"
        )
    pairs, angles, axes_f = pairs[keep], angles[keep], axes_f[keep]
    axes_g = np.einsum("nij,nj->ni", F[pairs[:, 0]], axes_f)  # eq 4 (eq 5 is its inverse)
    femur_axis, sd_f = _weighted_mean_axis(axes_f, angles)  # eq 6
    axes_t = np.einsum("nji,nj->ni", TF[pairs[:, 0]], axes_g)  # eq 7
    tibia_axis, sd_t = _weighted_mean_axis(axes_t, angles)  # eq 8
    return KneeAoR(
        femur_axis=femur_axis,
        tibia_axis=tibia_axis,
        n_pairs=int(len(pairs)),
        sd_angle_femur=sd_f,
        sd_angle_tibia=sd_t,
        pairs=pairs,
        angles=angles,
        femur_axes=axes_f,
        tibia_axes=axes_t,
        world_axes=axes_g,
    )


def reexpress_tibia(aor: KneeAoR, tibia_frames_R: np.ndarray) -> KneeAoR:
    """Same pairs and world axes, tibial side recomputed in other tibial frames (eq 7-8).

    Used for the OMC, where the tibial anatomical frame needs the femoral AoR first.
    """
    TF = np.asarray(tibia_frames_R, dtype=float)
    axes_t = np.einsum("nji,nj->ni", TF[aor.pairs[:, 0]], aor.world_axes)
    ok = np.all(np.isfinite(axes_t), axis=1)
    if not ok.any():
        raise InputError("tibial frames are missing at every selected frame pair")
    tibia_axis, sd_t = _weighted_mean_axis(axes_t[ok], aor.angles[ok])
    return replace(aor, tibia_axis=tibia_axis, sd_angle_tibia=sd_t, tibia_axes=axes_t)


# --------------------------------------------------------------------------------------------
# population (Table III)


def projection_angles(axes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Projection angles (rad) of right-pointing axes: transverse and frontal plane.

    Transverse plane (x-z, ISB): ``atan2(x, z)``, positive when the axis turns anterior.
    Frontal plane (y-z): ``atan2(y, z)``, positive when the axis tilts proximal (superior).
    """
    v = np.asarray(axes, dtype=float)
    return np.arctan2(v[..., 0], v[..., 2]), np.arctan2(v[..., 1], v[..., 2])


@dataclass(frozen=True)
class PopulationAoR:
    """Mean knee AoR over subjects (normalised mean of unit axes) and projection-angle spread.

    ``*_transverse`` / ``*_frontal``: per-subject projection angles (rad); ``sd_*``: their sample
    SD (ddof = 1), as in Wang Table III / Fig. 5.
    """

    femur_axis: np.ndarray
    tibia_axis: np.ndarray
    n_subjects: int
    femur_transverse: np.ndarray
    femur_frontal: np.ndarray
    tibia_transverse: np.ndarray
    tibia_frontal: np.ndarray
    sd_femur_transverse: float
    sd_femur_frontal: float
    sd_tibia_transverse: float
    sd_tibia_frontal: float


def population_aor(aors: Sequence[KneeAoR]) -> PopulationAoR:
    """Average subjects' AoRs and the SD of their transverse / frontal projection angles."""
    if len(aors) < 2:
        raise ValueError("population_aor needs at least two subjects")
    vf = np.stack([a.femur_axis for a in aors])
    vt = np.stack([a.tibia_axis for a in aors])
    ft, ff = projection_angles(vf)
    tt, tf = projection_angles(vt)
    return PopulationAoR(
        femur_axis=normalize(vf.mean(axis=0)),
        tibia_axis=normalize(vt.mean(axis=0)),
        n_subjects=len(aors),
        femur_transverse=ft,
        femur_frontal=ff,
        tibia_transverse=tt,
        tibia_frontal=tf,
        sd_femur_transverse=float(np.std(ft, ddof=1)),
        sd_femur_frontal=float(np.std(ff, ddof=1)),
        sd_tibia_transverse=float(np.std(tt, ddof=1)),
        sd_tibia_frontal=float(np.std(tf, ddof=1)),
    )


# --------------------------------------------------------------------------------------------
# correction (eq 9-13)


def correction_rotations(
    measured: KneeAoR, reference_femur_axis: np.ndarray, reference_tibia_axis: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Closed-form corrections ``(R_co_femur, R_co_tibia)`` (Wang eq 10-12).

    ``measured`` is the AoR of the IMC segment frames (``knee_aor`` on them, eq 9); the reference
    is e.g. the OMC population mean. Per segment, ``R_co`` is the smallest rotation about the
    axis ``V x v`` by the angle between them (eq 10-11) with ``R_co V = v`` (measured ``v``,
    reference ``V``), so that after ``e = e_hat R_co`` (eq 13) the measured world axis has the
    reference coordinates: ``e^T (e_hat v) = R_co^T v = V``. (Eq 11 as printed, ``v x V``, gives
    the transpose; combined with the right-multiplication of eq 13 it would double the error
    instead of removing it, which the tests check.)
    """
    R_f = rotation_aligning(reference_femur_axis, measured.femur_axis)
    R_t = rotation_aligning(reference_tibia_axis, measured.tibia_axis)
    return R_f, R_t


def apply_correction(R_seq: np.ndarray, R_co: np.ndarray) -> np.ndarray:
    """Eq 13: ``e^k = e_hat^k R_co`` (rotation of each segment frame in its own frame)."""
    return np.asarray(R_seq, dtype=float) @ np.asarray(R_co, dtype=float)


def measured_aor(
    femur_R: np.ndarray, tibia_R: np.ndarray, fallback_axes: Sequence[np.ndarray],
    **aor_kwargs: object,
) -> KneeAoR:
    """The AoR the recording shows, where the closed-form corrections start: :func:`knee_aor`
    (eq 1-8), or, where eq 1-8 find no usable pair, ``fallback_axes`` (femoral, tibial; e.g. the
    whole-trial hinge fit's) as a :class:`KneeAoR` without pairs."""
    try:
        return knee_aor(femur_R, tibia_R, **aor_kwargs)
    except InputError:
        return KneeAoR.from_axes(*fallback_axes)
