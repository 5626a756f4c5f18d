"""All sensors of a leg in the pelvis sensor's heading: joint constraints against heading drift.

A 6-D attitude filter (no magnetometer, or a disturbed one) gives every sensor a heading of its own:
VQF starts each at its sensor's first orientation, and the vertical component of the gyro bias,
unobservable in motion, turns it further (0.005 rad/s is 3 deg a minute). The standing calibration
turns the sensors' frames, not their worlds, so it cannot undo either: a segment's motion is then
expressed about axes turned by its heading error, and the joint angles mix flexion into ab/adduction
and rotation. Joint constraints tie the headings together without a magnetometer
(:mod:`pipeline.calibration.heading_offset`, eq 1 there), joint by joint down the chain, each distal
sensor's orientations turned into its proximal neighbour's heading by ``psi(t)`` before the
calibration pose is read:

* **hip** (pelvis -> thigh) and **ankle** (shank -> foot), ball joints: the specific force at the
  joint centre seen by both sensors, with the joint positions of Hu 2021's spherical calibration
  (eq 1-3) from the gyroscopes and accelerometers;
* **knee** (thigh -> shank), a hinge: its axis in both sensor frames from the knee's
  joint-constraint calibration (eq 4-6, :mod:`pipeline.process.functional`) where it is trusted
  (a wrong axis would turn the shank by a flexion-dependent error), else the knee centre's force
  as for a ball joint (any point on the axis is one physical point).

A joint whose constraint is not met after the turn (:data:`MAX_RESIDUAL_DEG`) is not used.

The notes say which joints were aligned, how far the headings drifted and the constraint's
residual before and after, or why a joint was not.
"""

from __future__ import annotations

import numpy as np

from pipeline.calibration.heading_offset import (
    MIN_ACCELERATION,
    HeadingDrift,
    heading_between,
    hinge_heading,
    turn_about_vertical,
)
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR
from pipeline.model.conventions import JOINT_SEGMENTS
from pipeline.process.functional import KneeCalibration, fit_joint

__all__ = ["MAX_RESIDUAL_DEG", "align_headings", "uses_drift_correction"]

_UP = np.array([0.0, 1.0, 0.0])
#: A joint's heading is not used when the constraint's RMS residual after the turn (the angle
#: between the two sensors' views of its axis or centre force, over the windows used) exceeds
#: this (deg). The simulated joints leave 0.1-1 deg. On the real x-IMU3 recording (6-D, its 9-D
#: orientations as the reference) the knees and ankles leave 11-15 deg and aligning them brings
#: the joint angles closer to the 9-D ones (median RMS difference 4.3 deg against 8.2 unaligned);
#: no window of the hips agrees (:data:`~pipeline.calibration.heading_offset.MIN_AGREEMENT`).
MAX_RESIDUAL_DEG = 20.0


def uses_drift_correction(mode: str, filtered: str | None) -> bool:
    """Whether ``mode`` (:data:`~pipeline.calibration.conventions.DRIFT_CORRECTIONS`) applies to
    orientations ``filtered`` as :func:`~pipeline.process.signals.orientations_from_signals`
    says (``'auto'``: only 6-D filter output)."""
    return mode == "joints" or (mode == "auto" and filtered == "6-D")


def align_headings(
    trial: Recording,
    rotations: dict[str, np.ndarray],
    knees: list[KneeCalibration],
    legs: list[str] | tuple[str, ...],
    method: str,
    notes: list[str],
) -> tuple[dict[str, np.ndarray], dict[str, HeadingDrift]]:
    """``(rotations, drifts)``: segment -> (N, 3, 3) sensor orientations (y-up world) with each
    leg's sensors turned into the pelvis sensor's heading as far down the chain as the joints
    allow (module docstring), and ``'<side>_<joint>'`` -> the
    :class:`~pipeline.calibration.heading_offset.HeadingDrift` applied. ``knees``: the knees'
    calibrations; ``method``: the ball joints' calibration method."""
    out = dict(rotations)
    drifts: dict[str, HeadingDrift] = {}
    for side in legs:
        for joint, (prox, dist) in JOINT_SEGMENTS.items():  # from the pelvis down
            p = prox if prox == "pelvis" else f"{side}_{prox}"
            d = f"{side}_{dist}"
            if p not in out or d not in out:
                continue
            name = f"{side} {joint}"
            try:
                drift, how = None, "the joint centre's acceleration"
                if joint == "knee":
                    drift, why = _knee(out[p], out[d], side, knees, trial.rate_hz)
                    how = "the hinge axis" if drift else f"the knee centre's acceleration ({why})"
                drift = drift or _ball(trial, out[p], out[d], p, d, method)
                if drift.residual_deg > MAX_RESIDUAL_DEG:
                    raise InputError(f"the constraint's residual after the turn is "
                                     f"{drift.residual_deg:.1f} deg (> {MAX_RESIDUAL_DEG:g})")
            except InputError as e:
                notes.append(f"{name}: heading not aligned: {e.message}")
                continue
            out[d] = turn_about_vertical(out[d], drift.psi, _UP)
            drifts[f"{side}_{joint}"] = drift
            notes.append(f"{name}: {dist} sensor turned into the {prox} sensor's heading by {how} "
                         f"({np.degrees(drift.psi.min()):.1f} to {np.degrees(drift.psi.max()):.1f}"
                         f" deg, drift {drift.drift_deg:.1f} deg; constraint residual "
                         f"{drift.residual_deg:.1f} deg, {drift.before_deg:.1f} deg with a "
                         "constant heading)")  # fmt: skip
    return out, drifts


def _knee(R_1, R_2, side, knees, rate_hz) -> tuple[HeadingDrift | None, str]:
    """The hinge axis' heading if the knee's functional calibration is trusted, else None and
    why not."""
    c = next((k for k in knees if k.side == side), None)
    if c is None:
        return None, "no functional calibration of the knee"
    if not c.trusted:
        return None, f"its hinge calibration is not trusted: {c.reason}"
    return hinge_heading(R_1, R_2, c.axis_thigh, c.axis_shank, rate_hz, up=_UP), ""


def _ball(trial: Recording, R_1, R_2, prox: str, dist: str, method: str) -> HeadingDrift:
    s1 = trial.sensors.get(SEGMENT_SENSOR[prox])
    s2 = trial.sensors.get(SEGMENT_SENSOR[dist])
    if any(s is None or s.gyr is None or s.acc is None for s in (s1, s2)):
        raise InputError("raw gyroscope and accelerometer signals of both sensors are needed")
    from pipeline.calibration.joint_constraints import joint_data, joint_force

    fit = fit_joint(trial.time, s1, s2, slice(None), method, shared_world=False,
                    joint="spherical", verify_start=False)
    # no observability test: a direction the fit leaves free (a pelvis that hardly turns, a
    # centre anywhere on a hinge-like ankle's axis) moves the centre without changing its force
    # much; the constraint's residual after the turn is the check (MAX_RESIDUAL_DEG)
    data = joint_data(trial.time, s1.gyr, s1.acc, s2.gyr, s2.acc)
    f1, f2 = joint_force(data, fit.position_1_m, fit.position_2_m)
    u = np.einsum("nij,nj->ni", R_1, f1)
    v = np.einsum("nij,nj->ni", R_2, f2)
    return heading_between(u, v, trial.rate_hz, up=_UP, min_weight=MIN_ACCELERATION**2)
