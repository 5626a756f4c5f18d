"""Sensors whose headings are their own, put in one world by the joints (magnetometer-free).

A 6-D attitude filter observes each sensor's inclination from gravity but not its heading: every
sensor's world turns about the vertical by a heading of its own (a constant from its start plus
the integrated vertical gyro bias); a disturbed magnetometer gives a 9-D filter (or a vendor's
fusion) a wrong heading too (:mod:`pipeline.calibration.magnetometer`). A standing calibration
turns the sensors' frames, not their worlds, so it cannot undo either: a segment's motion is then
expressed about axes turned by its heading error, and flexion leaks into ab/adduction and
rotation. The joints tie the headings together, joint by joint down each leg, each distal
sensor's orientations turned into its proximal neighbour's world by ``psi(t)``
(:mod:`pipeline.calibration.heading_offset`, eq 1 there, on windows of :data:`WINDOW_S`):

* **hip** (pelvis -> thigh) and **ankle** (shank -> foot): the specific force at the joint's
  centre seen by both sensors (Hu 2021 eq 2, the centre from Hu's spherical calibration, eq 1-3),
  one physical vector whose horizontal part fixes the heading while the joint accelerates
  (Laidig et al. 2017; Weygers et al. 2020). The signals are low-passed first
  (:data:`CUTOFF_HZ`): above it soft tissue and heel strikes
  break the rigid-body constraint, and on the real walk ``gaittoolbox_s02`` no window agreed
  without the filter. The centre's fit (eq 1-3 compare norms: non-convex) starts from the
  vertical part of the vector constraint, linear in the centres and exact whatever the headings
  (:func:`~pipeline.calibration.joint_centres.joint_centre`, ``shared_axis``), so it ends in one
  minimum however the sensors sit. From random starts in the sensors' frames S02's knee fits
  ended in one of two minima by the mounting (mean squared residual 0.32 / 0.42 as recorded,
  0.22 / 0.29 turned), the angles moving by up to 1.2 deg (``bench_sensor_sets``); the simulated
  gait's hips (seed 0, 6-D) now end where a start at the true centres ends, before on the box's
  bound, where their headings happened to be steadier (0.2-0.7 against 2.9-3.7 deg RMS about
  the truth): its sagittal median rose from 0.96 to 1.18 deg through one hip, the other axes fell
  from 2.20 to 1.99 (``bench_defaults``' sim real);
* **knee** (thigh -> shank): its hinge axis in both sensors' frames from the knee's
  joint-constraint calibration (Hu 2021 eq 4-6, :mod:`pipeline.process.functional`) where its
  axes are trusted (exact for a hinge); else whichever the data hold better (smaller residual)
  of the knee centre's force, as for the hip, and each segment's flexion axis in its sensor's
  frame (:func:`~pipeline.calibration.flexion_axis.flexion_axis`, the principal axis of its
  horizontal angular velocity, signed by ``leg_flexion_axes``): in walking thigh and shank
  turn about one medio-lateral direction, so ``R_1 j_1``, ``R_2 j_2`` are one world line.
  Measured: the simulated walk's knees (6-D, seeds 0-2) leave 2.4-3.7 deg by the centre, 3.2-9.0
  by the flexion axes; S02's 7.8-7.9 and 6.6-6.8 (vendor; sagittal median 4.55 and 4.42 deg).

* **a hip that does not align** (its windows never agree: the real x-IMU3 walk's hips without
  magnetometers; both of the simulated walk's under its soft tissue): its thigh, with the leg's
  sensors aligned to it, is turned into the other thigh's heading where that one is the
  pelvis's, by the two thighs' flexion axes (in walking both swing about the body's
  medio-lateral line; Vicon's thighs on S02: 2.6 and 6.7 deg apart over the walk's two
  halves); else onto the pelvis's medio-lateral line, which its list at the stride frequency
  shows in its sensor's frame (``pelvis_lateral_line``), signed by the hip centres (the right
  one on the right, :data:`MIN_SIDE_MARGIN`). Before, such
  a thigh kept the heading a 6-D filter takes from how its sensor sits: the x-IMU3 walk's angles
  moved by up to 20 deg with the mounting, the simulated walk's 6-D median error by up to 25 deg
  (``results/bench_sensor_sets.txt``). On S02 without magnetometers, with one hip
  refused on purpose, every sagittal RMSE within 0.8 deg of the run whose hips both aligned;
  with both refused, the median within 0.1 deg and the hips' ab/adduction r 0.86 / 0.92 instead
  of 0.75 / 0.86 (measured once by hand). A thigh that neither aligns keeps its own heading, and
  the quality gate flags its hip;
* **no pelvis sensor**: a thigh whose heading is its own is turned, with its leg, into the other
  thigh's by the two thighs' flexion axes, so that both legs share one heading (the x-IMU3 walk
  without its pelvis's sensor: the remaining joints within 0.5-0.9 deg of the run with it,
  3.9-5.0 before).

Windows of :data:`WINDOW_S` hold several whole strides, over which a real knee's rotation and
ab/adduction, the hip's rotation and the soft tissue average out; a window whose samples do not
agree is left out (``MIN_AGREEMENT``), and a joint whose constraint is not met after the turn
(:data:`MAX_RESIDUAL_DEG`) is not used. On S02 without magnetometers this takes the
sagittal median RMS error from 18.8 deg to the vendor orientations' (``bench_real_gait``).

Which sensors are aligned (:func:`sensors_to_align`): ``drift='auto'`` those whose heading is
not the shared world's (6-D output, a disturbed magnetometer), ``'joints'`` all, ``'none'`` none.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pipeline.calibration.flexion_axis import (
    FlexionAxis,
    pelvis_lateral_line,
    stride_frequency,
)
from pipeline.calibration.heading_offset import (
    HeadingDrift,
    hinge_heading,
    turn_about_vertical,
)
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR
from pipeline.model.conventions import JOINT_SEGMENTS, other_side
from pipeline.process.functional import KneeCalibration
from pipeline.process.joint_headings import (
    MAX_RESIDUAL_DEG,
    UP,
    WINDOW_S,
    ball_heading,
    centre_fit,
    flexion_heading,
    has_signals,
    knee_heading,
    leg_axes,
    signals_of,
)

__all__ = ["MAX_RESIDUAL_DEG", "MIN_SIDE_MARGIN", "align_headings", "sensors_to_align"]

#: The hip centres sign the pelvis's medio-lateral line when the cosine between it and the
#: vector from the left hip centre to the right (or one centre's lateral side) is at least this:
#: 0.53-0.99 on the simulated walk (6-D, seeds 1-3), S02 (hips refused) and the x-IMU3 walk.
MIN_SIDE_MARGIN = 0.05


def sensors_to_align(mode: str, segments: list[str], shared: frozenset[str]) -> set[str]:
    """The segments whose sensor's heading the joints align (module docstring): ``mode`` is the
    ``drift`` option, ``shared`` the sensors whose headings are in one world
    (:class:`~pipeline.process.signals.Orientations`)."""
    if mode == "none":
        return set()
    if mode == "joints":
        return set(segments)
    return {seg for seg in segments if SEGMENT_SENSOR[seg] not in shared}


def align_headings(
    trial: Recording,
    rotations: dict[str, np.ndarray],
    legs: list[str] | tuple[str, ...],
    align: set[str],
    knees: list[KneeCalibration],
    method: str,
    notes: list[str],
) -> tuple[dict[str, np.ndarray], dict[str, HeadingDrift]]:
    """``(rotations, drifts)``: segment -> (N, 3, 3) sensor orientations (y-up world) with each
    segment in ``align`` turned into its proximal neighbour's heading, down each leg
    (module docstring), and ``'<side>_<joint>'`` -> the
    :class:`~pipeline.calibration.heading_offset.HeadingDrift` applied. ``knees``: the knees'
    functional calibrations; ``method``: the hip's spherical calibration method."""
    out = dict(rotations)
    drifts: dict[str, HeadingDrift] = {}
    axes = {side: leg_axes(trial, out, side) for side in legs}  # inclinations only: no heading
    adrift = []  # legs whose thigh sensor kept a heading of its own
    for side in legs:
        for joint, (prox, dist) in JOINT_SEGMENTS.items():  # from the pelvis down
            p = prox if prox == "pelvis" else f"{side}_{prox}"
            d = f"{side}_{dist}"
            if p not in out or d not in out or d not in align:
                continue
            name = f"{side} {joint}"
            try:
                if joint != "knee":
                    drift = ball_heading(trial, out[p], out[d], p, d, method)
                    how = f"the {joint} centre's acceleration"
                else:
                    drift, how = knee_heading(trial, out[p], out[d], p, d, side, knees, axes[side],
                                       method)
                _check_residual(drift)
            except InputError as e:
                notes.append(f"{name}: {dist} sensor's heading not aligned: {e.message}")
                adrift += [side] if joint == "hip" else []
                continue
            drift = _through(drift, out[p], rotations[p])
            out[d] = turn_about_vertical(out[d], drift.psi, UP)
            drifts[f"{side}_{joint}"] = drift
            notes.append(_turned(name, dist, prox, how, drift))
    for side in adrift:
        _align_adrift_thigh(trial, out, side, align, axes, drifts, method, notes)
    _legs_in_one_heading(trial, out, align, axes, drifts, notes)
    return out, drifts


def _through(drift: HeadingDrift, proximal: np.ndarray, own: np.ndarray) -> HeadingDrift:
    """``drift`` NaN where the proximal segment's heading is not known though its sensor has
    samples (``proximal``, turned, NaN there; ``own``, its sensor's, not): a distal segment
    turned into it is not known there either
    (:func:`~pipeline.calibration.heading_offset.heading_between`)."""
    unknown = _rows_nan(proximal) & ~_rows_nan(own)
    if not unknown.any():
        return drift
    return dataclasses.replace(drift, psi=np.where(unknown, np.nan, drift.psi))


def _rows_nan(R: np.ndarray) -> np.ndarray:
    return ~np.all(np.isfinite(R), axis=(1, 2))


def _check_residual(drift: HeadingDrift) -> None:
    if drift.residual_deg > MAX_RESIDUAL_DEG:
        raise InputError(f"the constraint's residual after the turn is "
                         f"{drift.residual_deg:.1f} deg (> {MAX_RESIDUAL_DEG:g})")


def _turned(name: str, dist: str, prox: str, how: str, drift: HeadingDrift) -> str:
    low, high = np.degrees(np.nanmin(drift.psi)), np.degrees(np.nanmax(drift.psi))
    unknown = float(np.mean(np.isnan(drift.psi)))
    return (f"{name}: {dist} sensor turned into the {prox} sensor's heading by {how} "
            f"({low:.1f} to {high:.1f} deg; "
            f"constraint residual {drift.residual_deg:.1f} deg, {drift.before_deg:.1f} deg with a "
            "constant heading)" + (f"; not observed on {100 * unknown:.0f}% of the samples (a "
            "filter started again after a sensor's gap, and no window after it shows the "
            "heading): the joints it turns are blank there" if unknown else ""))


def _align_adrift_thigh(trial, out, side, align, axes, drifts, method, notes) -> None:
    """A thigh whose hip did not align (module docstring) turned, with the leg's sensors aligned
    to it, into the pelvis's heading by the other thigh's flexion axis or else the pelvis's
    medio-lateral line; else left in its own heading, which the note (a quality flag) says."""
    reasons = []
    for source in (_by_other_thigh, _by_pelvis_line):
        try:
            drift, how = source(trial, out, side, align, axes, drifts, method)
            _check_residual(drift)
            break
        except InputError as e:
            reasons.append(e.message)
    else:
        notes.append(f"{side} hip: the {side} leg keeps its thigh sensor's heading "
                     f"({'; '.join(reasons)}): the {side} hip's angles depend on how that sensor "
                     "sits, unreliable; its magnetometer or the vendor's orientations would give "
                     "it the pelvis's")
        return
    _turn_leg(out, side, drift, drifts)
    drifts[f"{side}_hip"] = drift
    notes.append(_turned(f"{side} hip", "femur", "pelvis", how, drift)
                 + f"; with it the {side} leg's sensors aligned below")


def _turn_leg(out, side: str, drift: HeadingDrift, drifts) -> None:
    """The thigh's orientations turned by ``drift``, and each sensor below it aligned to it."""
    turned = {f"{side}_femur"}
    for joint, (prox, dist) in JOINT_SEGMENTS.items():
        seg = f"{side}_{dist}"
        if seg in out and (seg in turned or (f"{side}_{joint}" in drifts
                                             and f"{side}_{prox}" in turned)):
            out[seg] = turn_about_vertical(out[seg], drift.psi, UP)
            turned.add(seg)


def _legs_in_one_heading(trial, out, align, axes, drifts, notes) -> None:
    """Without a pelvis sensor each leg keeps its thigh's heading: a thigh whose heading is its
    own (6-D, a distrusted magnetometer) is turned, with its leg, into the other thigh's by the
    two thighs' flexion axes, so that both legs share one."""
    side = next((s for s in ("left", "right") if f"{s}_femur" in align), None)
    if side is None or "pelvis" in out or f"{other_side(side)}_femur" not in out:
        return
    other = other_side(side)
    try:
        drift = _thigh_on_thigh(trial, out, axes, side)
        _check_residual(drift)
    except InputError as e:
        notes.append(f"the two legs keep their thighs' own headings ({e.message}): the angles "
                     "between the legs and the subject's heading may be unreliable")
        return
    _turn_leg(out, side, drift, drifts)
    drifts[f"{side}_thigh"] = drift
    notes.append(_turned(f"{side} thigh", "femur", f"{other} femur", f"the {other} thigh's "
                         "flexion axis (no pelvis sensor)", drift))


def _leg_axes_of(axes, side: str) -> dict[str, FlexionAxis]:
    if isinstance(axes.get(side), str):
        raise InputError(f"no flexion axes: {axes[side]}")
    if f"{side}_femur" not in axes.get(side, {}):
        raise InputError("no flexion axis of the thigh: raw gyroscope signals are needed")
    return axes[side]


def _thigh_on_thigh(trial, out, axes, side: str) -> HeadingDrift:
    """Eq (1) on the two thighs' flexion axes: ``side``'s thigh into the other's heading (in
    walking both flex about the body's medio-lateral line: one line in the world)."""
    o, femur = f"{other_side(side)}_femur", f"{side}_femur"
    both = {**_leg_axes_of(axes, other_side(side)), **_leg_axes_of(axes, side)}
    return flexion_heading(trial, out[o], out[femur], both, o, femur)


def _by_other_thigh(trial, out, side, align, axes, drifts, method) -> tuple[HeadingDrift, str]:
    """:func:`_thigh_on_thigh`, where the other thigh is in the pelvis's heading."""
    other = other_side(side)
    o = f"{other}_femur"
    if o not in out or (o in align and f"{other}_hip" not in drifts):
        raise InputError(f"the {other} thigh's sensor is not in the pelvis sensor's heading "
                         "either")
    return _thigh_on_thigh(trial, out, axes, side), f"the {other} thigh's flexion axis"


def _by_pelvis_line(trial, out, side, align, axes, drifts, method) -> tuple[HeadingDrift, str]:
    """The thigh's flexion axis on the pelvis's medio-lateral line (its list at the stride
    frequency, :func:`~pipeline.calibration.flexion_axis.pelvis_lateral_line`), signed by the hip
    centres: the right one lies on the right."""
    femur = f"{side}_femur"
    thigh = _leg_axes_of(axes, side)[femur]
    pelvis, s_f = signals_of(trial, "pelvis"), signals_of(trial, femur)
    stride_hz = stride_frequency(s_f.gyr @ thigh.axis, trial.rate_hz)
    up = np.einsum("nji,j->ni", out["pelvis"], UP)
    line = pelvis_lateral_line(pelvis.gyr, up, trial.rate_hz, stride_hz).axis
    rightward = np.zeros(3)  # the hip centres in the pelvis sensor's frame, right minus left
    for s, sign in (("right", 1.0), ("left", -1.0)):
        if f"{s}_femur" not in out or not has_signals(trial, f"{s}_femur"):
            continue
        fit, _, _ = centre_fit(trial, out["pelvis"], out[f"{s}_femur"], "pelvis", f"{s}_femur",
                                method)
        rightward += sign * fit.position_1_m
    margin = float(rightward @ line) / max(float(np.linalg.norm(rightward)), 1e-9)
    if abs(margin) < MIN_SIDE_MARGIN:
        raise InputError(f"the hip centres do not say which way the pelvis's medio-lateral line "
                         f"points (cosine {margin:.2f})")
    line = line if margin > 0 else -line
    drift = hinge_heading(out["pelvis"], out[femur], line, thigh.axis, trial.rate_hz, up=UP,
                          window_s=WINDOW_S)
    return drift, "the pelvis's medio-lateral line (its list at the stride frequency)"


