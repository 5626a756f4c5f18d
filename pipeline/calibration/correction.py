"""The knee-AoR orientation correction of one leg, as ``pipeline ik`` applies it (Wang 2023 §II.B).

Given the femur and tibia segment orientations ``ê_F(t), ê_T(t)`` a recording implies (sensor
orientations times the inverse of their placements) and a reference knee AoR ``(a_F, a_T)`` (the
population mean of the subject's sex, or the user's own), the correction is a constant rotation of
each segment frame in itself, ``e = ê R_co`` (eq 13):

* ``'aor'``: the closed form, eq 9-12 (:func:`pipeline.calibration.aor.correction_rotations` on
  :func:`pipeline.calibration.aor.knee_aor` of the recording, eq 1-8);
* ``'aor-ipopt'``: the whole-trial NLP (:func:`pipeline.calibration.aor_ipopt.aor_correction_ipopt`,
  CasADi/IPOPT; imported only when asked for).

A sensor ``s`` placed on its segment with rotation ``P`` (``R_s = ê P``) then has the placement
``P' = R_coᵀ P``, so the correction is a change of the IMU frames of the model and the IK is
unchanged (:func:`corrected_placement`). The foot's sensor, placed in the same calibration pose
with the ankle at neutral, follows the tibia's correction (:func:`carried_correction`).

What is reported (:class:`KneeCorrection`): the AoR the recording shows (eq 1-8, in the femoral and
tibial frames), each correction as an axis and angle, and the hinge residual about the reference
axis before and after: per sample the angle between the reference axis carried to the world by
the femur and by the tibia, ``∠(e_F a_F, e_T a_T)`` (0 for a knee that turns exactly about the
reference axis), RMS over the samples. A motion too small to define an axis is not corrected: the
result says so (``applied = False`` and ``reason``) instead of raising.

What the data support (:func:`correction_spread`): eq 9-12 computed on each half of the span the
knee moves in; the angle between the halves' rotations is how well the recording determines the
correction (``scripts/bench_defaults.py`` lists it for the simulator, S02 and OpenSense's walk).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from pipeline.calibration.aor import MIN_AXIS_Z, correction_rotations, knee_aor
from pipeline.errors import InputError
from pipeline.rotations import angle_between, axis_angle, rotation_aligning

__all__ = ["MIN_EXCURSION", "MOVING_DEG_S", "KneeCorrection", "carried_correction",
           "correct_knee", "correct_knee_to_axes", "corrected_placement", "correction_spread",
           "knee_excursion", "knee_hinge_residual", "population_correction"]

#: The corrections :func:`correct_knee` computes from the orientations themselves (eq 1-8 first).
_FROM_ORIENTATIONS = ("aor", "aor-ipopt")
#: Least knee excursion (rad, largest rotation between two samples of the shank relative to the
#: thigh) from which eq 1-8 define an axis: below it the axis error is the orientation error
#: divided by the excursion (a knee held still by a leg at rest moved 5 deg in a simulated
#: supine trial, and its axis came out 18 deg off). Gait and the Wang 2023 trials move 60-90 deg.
MIN_EXCURSION = np.radians(10.0)
#: A knee turning faster than this (deg/s, the shank relative to the thigh) is moving.
MOVING_DEG_S = 20.0


def knee_excursion(femur_R: np.ndarray, tibia_R: np.ndarray) -> float:
    """The largest rotation (rad) of the shank relative to the thigh between two samples,
    approximated from the sample farthest from the first one (a lower bound of at least half of
    it). Non-finite samples are ignored."""
    rel = np.einsum("nji,njk->nik", femur_R, tibia_R)
    rel = rel[np.all(np.isfinite(rel), axis=(1, 2))]
    if len(rel) < 2:
        return 0.0

    def angles_from(k: int) -> np.ndarray:
        tr = np.einsum("nij,ij->n", rel, rel[k])  # tr(rel_k^T rel_n)
        return np.arccos(np.clip(0.5 * (tr - 1.0), -1.0, 1.0))

    far = int(np.argmax(angles_from(0)))
    return float(angles_from(far).max())


@dataclass(frozen=True)
class KneeCorrection:
    """The correction of one leg (module docstring); angles in radians, axes unit vectors.

    ``femur_rotation``/``tibia_rotation``: ``R_co`` of each segment (3x3, identity when not
    applied); ``femur_axis_angle``/``tibia_axis_angle``: their rotation vectors (axis times angle,
    segment frame); ``measured_*_axis``: the AoR of the recording (None when it could not be
    estimated); ``reference_*_axis``: the axis corrected towards; ``hinge_residual_before`` /
    ``_after``: RMS hinge residual about the reference axis (rad); ``halves_apart``: the angle
    between the corrections of the two halves of the knee's moving span (rad,
    :func:`correction_spread`; None where not computed).
    """

    side: str
    method: str
    applied: bool
    reason: str
    femur_rotation: np.ndarray
    tibia_rotation: np.ndarray
    measured_femur_axis: np.ndarray | None
    measured_tibia_axis: np.ndarray | None
    reference_femur_axis: np.ndarray
    reference_tibia_axis: np.ndarray
    n_pairs: int
    hinge_residual_before: float
    hinge_residual_after: float
    halves_apart: float | None = None

    @property
    def femur_axis_angle(self) -> np.ndarray:
        axis, angle = axis_angle(self.femur_rotation)
        return np.nan_to_num(axis * angle)

    @property
    def tibia_axis_angle(self) -> np.ndarray:
        axis, angle = axis_angle(self.tibia_rotation)
        return np.nan_to_num(axis * angle)

    def as_dict(self) -> dict[str, object]:
        """Plain numbers (degrees for angles) for reports and configuration files."""

        def vec(v):
            return None if v is None else [float(x) for x in v]

        return {
            "side": self.side,
            "method": self.method,
            "applied": self.applied,
            "reason": self.reason,
            "femur_axis_angle_deg": vec(np.degrees(self.femur_axis_angle)),
            "tibia_axis_angle_deg": vec(np.degrees(self.tibia_axis_angle)),
            "measured_femur_axis": vec(self.measured_femur_axis),
            "measured_tibia_axis": vec(self.measured_tibia_axis),
            "reference_femur_axis": vec(self.reference_femur_axis),
            "reference_tibia_axis": vec(self.reference_tibia_axis),
            "n_pairs": self.n_pairs,
            "hinge_residual_before_deg": float(np.degrees(self.hinge_residual_before)),
            "hinge_residual_after_deg": float(np.degrees(self.hinge_residual_after)),
            "halves_apart_deg": None if self.halves_apart is None
            else float(np.degrees(self.halves_apart)),
        }


def knee_hinge_residual(
    femur_R: np.ndarray, tibia_R: np.ndarray, femur_axis: np.ndarray, tibia_axis: np.ndarray
) -> float:
    """RMS over the finite samples of ``∠(e_F a_F, e_T a_T)`` (rad; module docstring)."""
    a = np.asarray(femur_R, dtype=float) @ np.asarray(femur_axis, dtype=float)
    b = np.asarray(tibia_R, dtype=float) @ np.asarray(tibia_axis, dtype=float)
    ang = angle_between(a, b)
    ang = ang[np.isfinite(ang)]
    return float(np.sqrt(np.mean(ang**2))) if ang.size else float("nan")


def correct_knee(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    reference_femur_axis: np.ndarray,
    reference_tibia_axis: np.ndarray,
    *,
    method: str = "aor",
    side: str = "right",
    rate_hz: float = 100.0,
) -> KneeCorrection:
    """Correct one leg's femur and tibia orientations ``(N, 3, 3)`` towards the reference AoR.

    ``method`` is ``'aor'`` or ``'aor-ipopt'`` (module docstring); both start from the AoR the
    recording shows (eq 1-8 with :func:`knee_aor`'s defaults, as the Wang reproduction). When the
    knee moves too little for eq 1-8 the leg is left uncorrected and ``reason`` says why.
    """
    if method not in _FROM_ORIENTATIONS:
        raise InputError(f"expected a correction in {_FROM_ORIENTATIONS}, got {method!r} "
                         "('functional' is correct_knee_to_axes)", field="correction")
    F, T = np.asarray(femur_R, dtype=float), np.asarray(tibia_R, dtype=float)
    a_F = np.asarray(reference_femur_axis, dtype=float)
    a_T = np.asarray(reference_tibia_axis, dtype=float)
    before = knee_hinge_residual(F, T, a_F, a_T)
    try:
        excursion = knee_excursion(F, T)
        if excursion < MIN_EXCURSION:
            raise InputError(f"the knee moves {np.degrees(excursion):.0f} deg, less than the "
                             f"{np.degrees(MIN_EXCURSION):.0f} deg that define an axis")
        measured = knee_aor(F, T)
    except InputError as exc:
        reason = f"the knee AoR could not be estimated: {exc.message}"
        I3 = np.eye(3)
        return KneeCorrection(side, method, False, reason, I3, I3, None, None, a_F, a_T, 0,
                              before, before)
    if method == "aor-ipopt":
        from pipeline.calibration.aor_ipopt import aor_correction_ipopt  # CasADi: only here

        res = aor_correction_ipopt(F, T, a_F, a_T, rate_hz=rate_hz, start=measured)
        C_F, C_T = res.R_co_femur, res.R_co_tibia
    else:
        C_F, C_T = correction_rotations(measured, a_F, a_T)
    return _applied(side, method, F, T, C_F, C_T, measured.femur_axis, measured.tibia_axis, a_F,
                    a_T, measured.n_pairs, before)


def correct_knee_to_axes(
    femur_R: np.ndarray,
    tibia_R: np.ndarray,
    measured_femur_axis: np.ndarray,
    measured_tibia_axis: np.ndarray,
    reference_femur_axis: np.ndarray,
    reference_tibia_axis: np.ndarray,
    *,
    method: str = "functional",
    side: str = "right",
) -> KneeCorrection:
    """The closed-form correction (eq 10-12) of a knee whose AoR was measured otherwise than by
    eq 1-8: e.g. the joint-constraint hinge axis (Hu 2021 eq 4-6) carried into the segment frames
    by the sensors' placements. ``femur_R``/``tibia_R`` (N, 3, 3) only serve the hinge residuals
    reported before and after. Axis signs: the hinge constraint (Hu eq 6, ``|w x j|``) leaves each
    axis' sign free, so each measured axis is taken pointing to the same side as its reference
    (the subject's right, as eq 1-8's axes). As for eq 1-8, a femoral axis whose z component is
    not above :data:`~pipeline.calibration.aor.MIN_AXIS_Z` (more than 53 deg from the
    medio-lateral axis: the placements it was carried by are off) is not used: ``applied`` is
    False and ``reason`` says why."""
    F, T = np.asarray(femur_R, dtype=float), np.asarray(tibia_R, dtype=float)
    a_F = np.asarray(reference_femur_axis, dtype=float)
    a_T = np.asarray(reference_tibia_axis, dtype=float)
    v_F = np.asarray(measured_femur_axis, dtype=float)
    v_T = np.asarray(measured_tibia_axis, dtype=float)
    v_F = v_F if float(v_F @ a_F) >= 0.0 else -v_F
    v_T = v_T if float(v_T @ a_T) >= 0.0 else -v_T
    before = knee_hinge_residual(F, T, a_F, a_T)
    if v_F[2] <= MIN_AXIS_Z:
        reason = (f"the measured femoral axis has z = {v_F[2]:.2f} (<= {MIN_AXIS_Z}: more than "
                  f"{np.degrees(np.arccos(MIN_AXIS_Z)):.0f} deg from the medio-lateral axis)")
        I3 = np.eye(3)
        return KneeCorrection(side, method, False, reason, I3, I3, v_F, v_T, a_F, a_T, 0, before,
                              before)
    C_F, C_T = rotation_aligning(a_F, v_F), rotation_aligning(a_T, v_T)  # as eq 10-12
    return _applied(side, method, F, T, C_F, C_T, v_F, v_T, a_F, a_T, 0, before)


def moving_span(femur_R: np.ndarray, tibia_R: np.ndarray, rate_hz: float) -> slice:
    """The samples from the knee's first to its last turn faster than :data:`MOVING_DEG_S`
    (empty when it never does)."""
    rel = np.einsum("nji,njk->nik", femur_R, tibia_R)
    cos = 0.5 * (np.einsum("nij,nij->n", rel[1:], rel[:-1]) - 1.0)
    speed = np.degrees(np.arccos(np.clip(np.nan_to_num(cos, nan=1.0), -1.0, 1.0))) * rate_hz
    moving = np.flatnonzero(speed > MOVING_DEG_S)
    return slice(int(moving[0]), int(moving[-1]) + 2) if len(moving) else slice(0, 0)


def correction_spread(
    femur_R: np.ndarray, tibia_R: np.ndarray, reference_femur_axis: np.ndarray,
    reference_tibia_axis: np.ndarray, *, rate_hz: float = 100.0,
) -> float | None:
    """How far apart (rad) eq 9-12's corrections of the two halves of the knee's moving span are:
    the larger of the femur's and the tibia's ``∠(R_co,1ᵀ R_co,2)``. None when a half moves too
    little to define an axis."""
    span = moving_span(femur_R, tibia_R, rate_hz)
    mid = (span.start + span.stop) // 2
    halves = [correct_knee(femur_R[s], tibia_R[s], reference_femur_axis, reference_tibia_axis,
                           rate_hz=rate_hz)
              for s in (slice(span.start, mid), slice(mid, span.stop))]
    if not all(h.applied for h in halves):
        return None
    a, b = halves
    return max(_angle(a.femur_rotation.T @ b.femur_rotation),
               _angle(a.tibia_rotation.T @ b.tibia_rotation))


def _angle(R: np.ndarray) -> float:
    return float(np.arccos(np.clip(0.5 * (np.trace(R) - 1.0), -1.0, 1.0)))


def population_correction(
    femur_R: np.ndarray, tibia_R: np.ndarray, reference_femur_axis: np.ndarray,
    reference_tibia_axis: np.ndarray, pose_tibia_in_femur: np.ndarray, *, side: str = "right",
    reason: str,
) -> KneeCorrection:
    """A knee whose AoR the recording cannot show (``reason``): corrected as a knee of the
    reference population would be, so that a still leg's tibia is turned as a moving one's.

    In the calibration pose the tibia's frame is ``R_ft`` (``pose_tibia_in_femur``) in the
    femur's; a knee turning about the reference axis ``a_F`` would show ``v_F = a_F`` and
    ``v_T = R_ftᵀ a_F``, and eq 10-12 then give ``R_co_femur = I`` and ``R_co_tibia`` the
    smallest rotation with ``R_co v_T = ...`` as :func:`correction_rotations`: for a free knee
    (``R_ft = I``) the turn that aligns ``a_T`` onto ``a_F`` (~12 deg), for the hinge model's own
    pose (``R_ft`` that turn already) none. ``method`` is ``'population'``; no axis was seen.
    """
    a_F = np.asarray(reference_femur_axis, dtype=float)
    a_T = np.asarray(reference_tibia_axis, dtype=float)
    v_T = np.asarray(pose_tibia_in_femur, dtype=float).T @ a_F
    F, T = np.asarray(femur_R, dtype=float), np.asarray(tibia_R, dtype=float)
    before = knee_hinge_residual(F, T, a_F, a_T)
    c = _applied(side, "population", F, T, np.eye(3), rotation_aligning(a_T, v_T), a_F, v_T, a_F,
                 a_T, 0, before)
    return replace(c, reason=reason, measured_femur_axis=None, measured_tibia_axis=None)


def _applied(side, method, F, T, C_F, C_T, v_F, v_T, a_F, a_T, n_pairs, before) -> KneeCorrection:
    """An applied correction, with the hinge residual about the reference after it."""
    after = knee_hinge_residual(F @ C_F, T @ C_T, a_F, a_T)
    return KneeCorrection(side, method, True, "", C_F, C_T, v_F, v_T, a_F, a_T, n_pairs, before,
                          after)


def carried_correction(R_co: np.ndarray, R_child: np.ndarray) -> np.ndarray:
    """The correction a child segment inherits from its parent's: ``R_cᵀ R_co R_c``.

    ``R_child`` (``R_c``) is the child's frame in the parent's in the calibration pose. A sensor
    placement read off that pose assumes ``e_child = e_parent R_c``; when the parent's frame
    turns out to be ``e_parent R_co`` (eq 13) and the joint was at the pose's angle, the child's
    frame is ``e_parent R_co R_c = e_child (R_cᵀ R_co R_c)``. The foot follows the tibia so: its
    sensor was placed in the same standing pose with the ankle at neutral, as the hinge model's
    own neutral pose turns the tibia and the foot together.
    """
    R_c = np.asarray(R_child, dtype=float)
    return R_c.T @ np.asarray(R_co, dtype=float) @ R_c


def corrected_placement(placement: np.ndarray, R_co: np.ndarray) -> np.ndarray:
    """``P' = R_coᵀ P`` (rotation part of a 4x4 IMU placement; the position is kept)."""
    T = np.array(placement, dtype=float)
    T[:3, :3] = np.asarray(R_co, dtype=float).T @ T[:3, :3]
    return T
