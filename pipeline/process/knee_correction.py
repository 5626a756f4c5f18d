"""The knee-AoR correction step of :func:`pipeline.process.process_recording`: per leg with a knee,
which correction applies, and the sensor placements it changes (Wang 2023 eq 9-13; step 5).

The methods are a registry (:data:`CORRECTIONS`: the option's name -> a function of one knee's
:class:`KneeInputs` returning its :class:`~pipeline.calibration.correction.KneeCorrection`);
adding one is one function and one entry. Whatever the method, :func:`choose_correction` takes the
same decisions in the same order:

1. a knee whose thigh and shank sensors' headings should have been aligned and were not (6-D
   filter output) is not seen across one world: corrected as the reference population's knee;
2. the method runs (``functional`` falls back to ``aor`` where the knee's functional calibration
   is not trusted, with a note);
3. a correction that could not be computed (a knee that moves too little to define an axis) is
   replaced by the reference population's (:func:`~pipeline.calibration.correction.
   population_correction`), with a note;
4. a correction from the orientations (eq 1-8: ``aor``, ``aor-ipopt``) that the data do not
   determine is not applied, with a note: the two halves of the knee's moving span ask for
   corrections more than :data:`MAX_SPREAD_DEG` apart (:func:`~pipeline.calibration.correction.
   correction_spread`; the simulator's halves agree within it, the real S02 walk's do not).

The correction then becomes part of the femur's and tibia's sensor placements
(:func:`~pipeline.calibration.correction.corrected_placement`), and the foot's sensor, placed with
the ankle at neutral, follows the tibia (:func:`~pipeline.calibration.correction.
carried_correction`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from pipeline.calibration.correction import (
    KneeCorrection,
    carried_correction,
    correct_knee,
    correct_knee_to_axes,
    corrected_placement,
    correction_spread,
    population_correction,
)
from pipeline.process.functional import KneeCalibration
from pipeline.process.pose import CalibrationPose

__all__ = ["CORRECTIONS", "MAX_SPREAD_DEG", "KneeInputs", "apply_correction", "choose_correction",
           "correct_knees"]

#: Largest angle (deg) between the corrections of the two halves of a knee's moving span for which
#: a correction from the orientations is applied.
MAX_SPREAD_DEG = 5.0


@dataclass(frozen=True)
class KneeInputs:
    """What one knee's correction sees: ``femur_R``/``tibia_R`` (N, 3, 3) the segment
    orientations the sensors imply, the reference axes ``axis_femur``/``axis_tibia`` (segment
    frames), ``pose_tibia_in_femur`` (the tibia's frame in the femur's in the calibration pose),
    the sensors' placements (``placement_thigh``/``placement_shank``, 3x3), the knee's functional
    calibration (None without raw signals), and whether the sensors share a heading
    (``headings_shared``: False for 6-D filter output the joints did not align)."""

    side: str
    femur_R: np.ndarray
    tibia_R: np.ndarray
    axis_femur: np.ndarray
    axis_tibia: np.ndarray
    pose_tibia_in_femur: np.ndarray
    placement_thigh: np.ndarray
    placement_shank: np.ndarray
    rate_hz: float
    calibration: KneeCalibration | None = None
    headings_shared: bool = True


def _closed_form(k: KneeInputs, notes: list[str]) -> KneeCorrection:
    """Wang eq 9-12 on the AoR the orientations show (eq 1-8)."""
    return correct_knee(k.femur_R, k.tibia_R, k.axis_femur, k.axis_tibia, method="aor",
                        side=k.side, rate_hz=k.rate_hz)


def _ipopt(k: KneeInputs, notes: list[str]) -> KneeCorrection:
    """The whole-trial IPOPT version of eq 9-13 (:mod:`pipeline.calibration.aor_ipopt`)."""
    return correct_knee(k.femur_R, k.tibia_R, k.axis_femur, k.axis_tibia, method="aor-ipopt",
                        side=k.side, rate_hz=k.rate_hz)


def _functional(k: KneeInputs, notes: list[str]) -> KneeCorrection:
    """Towards the gyroscopes' hinge axis (Hu eq 4-6) where the knee's functional calibration is
    trusted: the sensor placement is right, but the filter's heading errors stay (eq 1-8 absorbs
    their constant part); elsewhere eq 1-8 (``aor``), with a note saying why."""
    c = k.calibration
    if c is not None and c.trusted:
        v_F = k.placement_thigh @ c.axis_thigh
        v_T = k.placement_shank @ c.axis_shank
        out = correct_knee_to_axes(k.femur_R, k.tibia_R, v_F, v_T, k.axis_femur, k.axis_tibia,
                                   side=k.side)
        if out.applied:
            return out
        why = f"its functional axis is not used: {out.reason}"
    elif c is not None:
        why = "its functional calibration is not trusted"
    else:
        why = "no functional calibration (raw gyroscope and accelerometer signals of both " \
              "sensors are needed)"
    notes.append(f"{k.side} knee: {why}; corrected by eq 1-8 ('aor') instead")
    return _closed_form(k, notes)


#: Correction name (the ``correction`` option, besides ``none``) -> its function.
CORRECTIONS: dict[str, Callable[[KneeInputs, list[str]], KneeCorrection]] = {
    "aor": _closed_form,
    "aor-ipopt": _ipopt,
    "functional": _functional,
}


def choose_correction(k: KneeInputs, method: str, notes: list[str]) -> KneeCorrection:
    """One knee's correction by ``method`` with the decisions of the module docstring."""
    if not k.headings_shared:
        reason = ("its thigh and shank sensors' headings were not aligned: the AoR seen across "
                  "two worlds is turned by their heading difference")
        c = None
    else:
        c = CORRECTIONS[method](k, notes)
        reason = c.reason
    if c is None or not c.applied:  # as the reference population's knee
        c = population_correction(k.femur_R, k.tibia_R, k.axis_femur, k.axis_tibia,
                                  k.pose_tibia_in_femur, side=k.side, reason=reason)
        notes.append(f"{k.side} knee: its AoR is not seen ({c.reason}); corrected as the "
                     "reference population's knee")
    elif c.method in ("aor", "aor-ipopt"):
        return _if_supported(k, c, notes)
    return c


def _if_supported(k: KneeInputs, c: KneeCorrection, notes: list[str]) -> KneeCorrection:
    """``c``, or no correction where the data do not determine it (decision 4)."""
    spread = correction_spread(k.femur_R, k.tibia_R, k.axis_femur, k.axis_tibia, rate_hz=k.rate_hz)
    c = replace(c, halves_apart=spread)
    if spread is None or np.degrees(spread) <= MAX_SPREAD_DEG:
        return c
    turn = np.degrees(max(np.linalg.norm(c.femur_axis_angle), np.linalg.norm(c.tibia_axis_angle)))
    reason = (f"the data do not determine its correction ({turn:.1f} deg): the two halves of the "
              f"walk ask for corrections {np.degrees(spread):.1f} deg apart (> {MAX_SPREAD_DEG:g})")
    notes.append(f"{k.side} knee: not corrected: {reason}")
    I3 = np.eye(3)
    return replace(c, applied=False, reason=reason, femur_rotation=I3, tibia_rotation=I3,
                   hinge_residual_after=c.hinge_residual_before)


def apply_correction(
    placements: dict[str, np.ndarray], c: KneeCorrection, pose: dict[str, np.ndarray]
) -> dict[str, np.ndarray]:
    """The placements with one knee's correction in the femur's, tibia's and (carried) foot's
    sensor frames (module docstring); ``pose``: segment orientations in the calibration pose."""
    out = dict(placements)
    fem, tib, foot = (f"{c.side}_{s}" for s in ("femur", "tibia", "foot"))
    out[f"{fem}_imu"] = corrected_placement(out[f"{fem}_imu"], c.femur_rotation)
    out[f"{tib}_imu"] = corrected_placement(out[f"{tib}_imu"], c.tibia_rotation)
    if f"{foot}_imu" in out:  # placed with the ankle at neutral
        R_c = pose[tib].T @ pose[foot]
        out[f"{foot}_imu"] = corrected_placement(out[f"{foot}_imu"],
                                                 carried_correction(c.tibia_rotation, R_c))
    return out


def correct_knees(rotations, cal: CalibrationPose, knee_axes, knee_cal, method: str,
                  unaligned: set[str], rate_hz: float, notes: list[str]):
    """Step 5 on every knee: ``(placements, corrections)``. ``rotations``: segment -> (N, 3, 3)
    sensor orientations; ``knee_axes``: side -> the reference axes (femur, tibia);
    ``knee_cal``: the knees' functional calibrations; ``unaligned``: the tibias whose sensors'
    headings were not aligned to their thighs'; ``method``: a :data:`CORRECTIONS` name or
    ``'none'``."""
    placements = dict(cal.placements)
    corrections: dict[str, KneeCorrection] = {}
    if method == "none":
        return placements, corrections
    calibrations = {c.side: c for c in knee_cal}
    for side, (a_F, a_T) in knee_axes.items():
        fem, tib = f"{side}_femur", f"{side}_tibia"
        P_F, P_T = placements[f"{fem}_imu"][:3, :3], placements[f"{tib}_imu"][:3, :3]
        k = KneeInputs(side, rotations[fem] @ P_F.T, rotations[tib] @ P_T.T, a_F, a_T,
                       cal.pose[fem].T @ cal.pose[tib], P_F, P_T, rate_hz,
                       calibrations.get(side),
                       headings_shared=tib not in unaligned)
        c = choose_correction(k, method, notes)
        corrections[side] = c
        placements = apply_correction(placements, c, cal.pose)
    return placements, corrections
