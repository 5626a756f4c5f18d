"""The joint-constraint calibration of each knee from raw signals, and whether to trust it.

Where a knee's thigh and shank sensors have gyroscope and accelerometer signals, the hinge is
calibrated from them alone (Hu 2021 eq 4-6 and 1-3/16: :func:`pipeline.calibration.calibrate`,
IPOPT by default, with an independent start), on the whole trial and on each half. Trust needs
evidence that holds on real data, all three of:

* **determined**: the observability test passes and the independent start agrees
  (:mod:`pipeline.calibration.observability`);
* **split-half agreement**: the axes fitted to the first and the second half of the moving samples
  (a standing start is no half of the motion) within :data:`SPLIT_HALF_DEG` of each other in both
  sensor frames (on a real recording the shank axis moved by 58-69 deg between halves while the
  formal SDs claimed 1-4 mm);
* **hinge residual**: the RMS of the eq-6 residual (``|w_1 x j_1| - |w_2 x j_2|``) below
  :data:`RESIDUAL_BOUND_RAD_S`.

Reported per knee, with the angle between the functional axis, carried into the segment by the
sensor's placement, and the model's knee axis. ``axes_trusted`` asks the same of the axes alone
(their directions determined, the halves agreeing, the residual within bounds): what aligning two
sensors' headings by the hinge axis needs (:mod:`pipeline.process.heading_alignment`), whatever
the motion leaves of the knee centre's position. With ``correction='functional'`` a trusted knee's
axes replace the AoR the orientations show (:func:`pipeline.process.run.process_recording`,
step 5): the sensor-to-segment rotations are turned so that the hinge axis is the model's knee
axis, ISB's medio-lateral direction (Hu 2021 eq 30-37 define the segment frame the same way).

Why it is not the default (``scripts/bench_raw_path.py``, simulated gait, sensors misplaced by up to
15 deg): it gives the same joint angles as eq 1-8 once the sensors share one heading (a
magnetometer, or the joints' heading alignment of 6-D orientations,
:mod:`pipeline.process.heading_alignment`; within 0.2 deg RMS on every axis), and needs raw signals.
Without that alignment it was worse (knee axes other than flexion 11-21 deg RMS against 4-6 deg):
the filter's heading difference between the thigh and shank sensors dominated, and eq 1-8, fitted to
the orientations, absorbed its constant part where a correct placement cannot.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, fields

import numpy as np

from pipeline.calibration.conventions import DEFAULT_METHOD
from pipeline.io.recording import Recording
from pipeline.rotations import angle_between

__all__ = ["MAX_SAMPLES", "MOVING_RAD_S", "RESIDUAL_BOUND_RAD_S", "SPLIT_HALF_DEG",
           "KneeCalibration", "calibrate_knees", "fit_joint", "joint_residual", "with_placements"]

SPLIT_HALF_DEG = 5.0
#: Samples whose two gyroscopes' speeds add up to more than this (rad/s) are the motion.
MOVING_RAD_S = 0.5
#: Samples one fit uses at most: a longer (half) trial is subsampled evenly after the angular
#: accelerations are taken on every sample (the hinge residuals are per sample), so that an hour of
#: raw signals costs a calibration of a minute's size, not an NLP of 360,000 residuals.
MAX_SAMPLES = 6000
RESIDUAL_BOUND_RAD_S = 0.35
_SENSORS = {"right": ("femur_r_imu", "tibia_r_imu"), "left": ("femur_l_imu", "tibia_l_imu")}


@dataclass(frozen=True)
class KneeCalibration:
    """One knee's functional calibration (axes unit, sensor frames; angles in degrees)."""

    side: str
    axis_thigh: np.ndarray
    axis_shank: np.ndarray
    split_half_deg: float
    residual_rad_s: float
    determined: bool
    vs_model_deg: float
    trusted: bool
    reason: str
    axes_trusted: bool = False


def calibrate_knees(
    trial: Recording,
    placements: dict[str, np.ndarray] | None,
    model_axes: dict[str, tuple[np.ndarray, np.ndarray]],
    method: str = "ipopt",
    min_samples: int = 200,
    *,
    shared_world: bool = True,
) -> list[KneeCalibration]:
    """Every knee whose two sensors have gyroscope and accelerometer (module docstring).

    ``placements``: IMU frame (``right_femur_imu``, ...) -> 4x4 placement on its segment (None:
    not yet known, ``vs_model_deg`` nan until :func:`with_placements`);
    ``model_axes``: side -> the model's knee axis in the femoral and tibial frames.
    ``shared_world``: the sensors' orientations share one world (vendor fusion, 9-D), so they
    may sign the two axes alike; False (6-D filters: a heading of each sensor's own) signs them
    by the specific force at the joint alone
    (:func:`~pipeline.calibration.joint_constraints.consistent_axis_signs`)."""
    out = []
    for side, (thigh, shank) in _SENSORS.items():
        s1, s2 = trial.sensors.get(thigh), trial.sensors.get(shank)
        if side not in model_axes or s1 is None or s2 is None:
            continue
        if any(v is None for v in (s1.gyr, s1.acc, s2.gyr, s2.acc)):
            continue
        n, own = trial.n_samples, trial.present(thigh, shank)  # not over a bridged gap
        moving = np.flatnonzero((np.linalg.norm(s1.gyr, axis=1) + np.linalg.norm(s2.gyr, axis=1)
                                 > MOVING_RAD_S) & own)
        if n < 2 * min_samples or moving.size < 2 * min_samples:
            continue
        middle = int(moving[moving.size // 2])
        halves = _halves(own, middle)
        # the independent start checks the whole trial's fit; the halves only give axes
        full, first, second = (fit_joint(trial.time, s1, s2, rows, method,
                                         shared_world=shared_world,
                                         verify_start=rows is halves[0])
                               for rows in halves)
        sign = 1.0 if float(first.axis_1 @ second.axis_1) >= 0 else -1.0
        split = float(np.degrees(max(angle_between(first.axis_1, sign * second.axis_1),
                                     angle_between(first.axis_2,
                                                   sign * second.axis_2))))
        # eq 6 alone: |w_1 x j_1| - |w_2 x j_2| (rad/s), over the whole trial
        r = (np.linalg.norm(np.cross(s1.gyr[own], full.axis_1), axis=1)
             - np.linalg.norm(np.cross(s2.gyr[own], full.axis_2), axis=1))
        residual = float(np.sqrt(np.mean(r**2)))
        vs_model = (float("nan") if placements is None else
                    _vs_model(full.axis_1, full.axis_2, placements, side, model_axes[side]))
        reasons = []
        if not full.observability.determined:
            reasons.append("not determined: " + "; ".join(full.observability.undetermined))
        if split > SPLIT_HALF_DEG:
            reasons.append(f"the halves' axes are {split:.1f} deg apart (> {SPLIT_HALF_DEG:g})")
        if residual > RESIDUAL_BOUND_RAD_S:
            reasons.append(f"hinge residual {residual:.2f} rad/s (> {RESIDUAL_BOUND_RAD_S:g})")
        axes_ok = (not any(u.startswith("ax") for u in full.observability.undetermined)
                   and split <= SPLIT_HALF_DEG and residual <= RESIDUAL_BOUND_RAD_S)
        out.append(KneeCalibration(side, full.axis_1, full.axis_2, split, residual,
                                   full.observability.determined, vs_model, not reasons,
                                   "; ".join(reasons), axes_ok))
    return out


def _halves(own: np.ndarray, middle: int) -> tuple:
    """The whole trial's rows and its two halves at ``middle``: slices, or the rows each has
    of its own where a sensor misses samples."""
    if own.all():
        return slice(None), slice(0, middle), slice(middle, None)
    rows = np.flatnonzero(own)
    return rows, rows[rows < middle], rows[rows >= middle]


def with_placements(
    calibrations: list[KneeCalibration],
    placements: dict[str, np.ndarray],
    model_axes: dict[str, tuple[np.ndarray, np.ndarray]],
) -> list[KneeCalibration]:
    """The calibrations with ``vs_model_deg`` recomputed for new ``placements`` (e.g. after the
    sensors' headings were made consistent, :mod:`pipeline.process.heading_alignment`)."""
    out = []
    for c in calibrations:
        vs = _vs_model(c.axis_thigh, c.axis_shank, placements, c.side, model_axes[c.side])
        out.append(dataclasses.replace(c, vs_model_deg=vs))
    return out


def _vs_model(axis_thigh, axis_shank, placements, side, model_axes):
    """The larger angle (deg) between the functional axes, carried into the segments by the
    placements, and the model's knee axes (the pair's sign chosen by the femoral axis)."""
    a_F, a_T = model_axes
    seg_F = placements[f"{side}_femur_imu"][:3, :3] @ axis_thigh
    seg_T = placements[f"{side}_tibia_imu"][:3, :3] @ axis_shank
    s = 1.0 if float(seg_F @ a_F) >= 0 else -1.0
    return float(np.degrees(max(angle_between(s * seg_F, a_F), angle_between(s * seg_T, a_T))))


def fit_joint(time, s1, s2, rows: slice | np.ndarray, method: str, *, shared_world: bool,
              joint: str = "hinge", verify_start: bool = True, **options):
    """Hu 2021's calibration of one joint between sensors ``s1`` and ``s2``
    (:class:`~pipeline.io.recording.SensorSignals`) on the samples ``rows``, at most
    :data:`MAX_SAMPLES` of them (``verify_start``: solved again from an independent start);
    ``options`` go to the method (:func:`~pipeline.calibration.calibrate.calibrate`)."""
    # the solvers (CasADi for IPOPT) load only when a recording has raw signals to calibrate
    from pipeline.calibration.calibrate import calibrate
    from pipeline.calibration.joint_constraints import JointData, joint_data

    if isinstance(rows, slice):
        d = joint_data(time[rows], s1.gyr[rows], s1.acc[rows], s2.gyr[rows], s2.acc[rows])
    else:  # chosen samples (a sensor's gap left out): the accelerations taken on every sample
        d = joint_data(time, s1.gyr, s1.acc, s2.gyr, s2.acc)
        d = JointData(*(getattr(d, f.name)[rows] for f in fields(JointData)))
    q1 = None if s1.quat is None or not shared_world else s1.quat[rows]
    q2 = None if s2.quat is None or not shared_world else s2.quat[rows]
    n = d.gyr_1.shape[0]
    if n > MAX_SAMPLES:
        keep = np.linspace(0, n - 1, MAX_SAMPLES).round().astype(int)
        d = JointData(*(getattr(d, f.name)[keep] for f in fields(JointData)))
        q1 = None if q1 is None else q1[keep]
        q2 = None if q2 is None else q2[keep]
    return calibrate(d, joint, method, quat_1=q1, quat_2=q2, verify_start=verify_start,
                     **options)


def joint_residual(time, rate_hz: float, s1, s2, *, joint: str = "spherical", cutoff_hz: float,
                   step: int, method: str = DEFAULT_METHOD) -> float:
    """RMS residual of :func:`fit_joint` between sensors ``s1`` and ``s2`` on their signals
    low-passed at ``cutoff_hz``, fitted on every ``step``-th sample and measured on all: Hu 2021
    eq 3 (``joint='spherical'``, the centre's force, m/s^2) or eq 6 (``'hinge'``, rad/s)."""
    from pipeline.calibration.joint_constraints import (
        hinge_residual,
        joint_data,
        spherical_residual,
    )

    s1, s2 = (s.low_passed(rate_hz, cutoff_hz) for s in (s1, s2))
    fit = fit_joint(time, s1, s2, slice(None, None, step), method, shared_world=False,
                    joint=joint, verify_start=False)
    if joint == "hinge":
        e = hinge_residual(fit.axis_1, fit.axis_2, s1.gyr, s2.gyr)
    else:
        e = spherical_residual(fit.position_1_m, fit.position_2_m,
                               joint_data(time, s1.gyr, s1.acc, s2.gyr, s2.acc))
    return float(np.sqrt(np.nanmean(e**2)))
