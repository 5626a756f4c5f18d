"""``pipeline calibrate``: joint-constraint calibration (Hu 2021) of two IMU CSVs.

:func:`run_calibration` reads the two files, checks that they share one time base, runs
:func:`pipeline.calibration.calibrate.calibrate` and reports what the motion leaves undetermined.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from pipeline.calibration.calibrate import ITERATION_OPTION, POPULATION_OPTION, calibrate
from pipeline.calibration.conventions import DEFAULT_METHOD, JOINTS, METHODS
from pipeline.calibration.joint_constraints import joint_data
from pipeline.calibration.observability import Observability
from pipeline.errors import InputError
from pipeline.io.checks import check_same_length, check_same_rate
from pipeline.io.imu_csv import read_imu_csv
from pipeline.io.jsonio import jsonable

__all__ = ["CALIBRATION_KEYS", "MIN_MOTION_RAD_S", "run_calibration"]

CALIBRATION_KEYS = (
    "axis_1",
    "axis_2",
    "position_1_m",
    "position_2_m",
    "cost",
    "iterations",
    "seconds",
    "method",
    "observability",
)


#: Below this RMS angular speed (rad/s, about 3 deg/s) of both sensors a trial has no motion
#: to calibrate from: every axis and position would be undetermined. (One still sensor is a
#: poorly excited trial, whose undetermined parameters the observability test reports.)
MIN_MOTION_RAD_S = 0.05


def _read_pair(imu1: Path, imu2: Path):
    if imu1.resolve() == imu2.resolve():
        raise InputError(f"--imu1 and --imu2 name the same file ({imu1}); expected the sensors "
                         "on the two segments of the joint", field="imu2")
    r1, r2 = read_imu_csv(imu1), read_imu_csv(imu2)
    check_same_length({str(imu1): r1.time.size, str(imu2): r2.time.size})
    check_same_rate({str(imu1): r1.rate_hz, str(imu2): r2.rate_hz})
    dt = 1.0 / r1.rate_hz
    lag = float(np.max(np.abs(r1.time - r2.time)))
    if lag > 0.5 * dt:
        raise InputError(
            f"time stamps differ by up to {lag:.4g} s between {imu1} and {imu2}; expected the "
            f"two sensors on one time base (within half a sample, {0.5 * dt:.4g} s)",
            field="time",
        )
    if r1.gyr.shape == r2.gyr.shape and np.array_equal(r1.gyr, r2.gyr):
        raise InputError(f"{imu1} and {imu2} hold identical gyroscope signals; expected two "
                         "sensors on the two segments of the joint", field="gyr")
    speeds = [float(np.sqrt(np.nanmean(np.sum(r.gyr**2, axis=1)))) for r in (r1, r2)]
    if max(speeds) < MIN_MOTION_RAD_S:  # one still segment is poor excitation, reported later
        raise InputError(
            f"the sensors barely move (RMS angular speeds {np.degrees(speeds[0]):.2f} and "
            f"{np.degrees(speeds[1]):.2f} deg/s, below {np.degrees(MIN_MOTION_RAD_S):.1f} deg/s): "
            "a joint cannot be calibrated without motion; record the segments moving through "
            "their range",
            file=imu1,
            field="gyr",
        )
    return r1, r2


def _observability_summary(obs: Observability) -> dict:
    out = jsonable(obs.as_dict())
    out["determined"] = obs.determined
    if not obs.determined:
        starts = any("independent starts" in u for u in obs.undetermined)
        advice = []
        if any("independent starts" not in u for u in obs.undetermined):
            advice.append("the motion leaves these directions free: excite the segments about "
                          "other axes, or use ipopt with a population-axis prior")
        if starts:
            advice.append("two starts disagree: the optimiser did not converge (raise "
                          "--iterations/--population, or use gn or ipopt)")
        what = "; ".join(obs.undetermined)
        out["warning"] = f"UNDETERMINED: {what} - not trustworthy ({'; '.join(advice)})"
    return out


def run_calibration(
    joint: str,
    imu1: str | Path,
    imu2: str | Path,
    method: str = DEFAULT_METHOD,
    seed: int = 0,
    as_json: bool = False,
    *,
    iterations: int | None = None,
    population: int | None = None,
) -> str:
    """Calibrate a 'hinge' or 'spherical' joint from two IMU CSVs (proximal ``imu1``, distal
    ``imu2``) with ``method`` in ('gn', 'dwpso', 'gwo', 'ipopt') and return the report text.

    JSON keys: ``axis_1``, ``axis_2`` (unit, sensor frames, null for a spherical joint),
    ``position_1_m``, ``position_2_m`` (sensor -> joint centre, m; hinge: the eq-16 point),
    ``cost``, ``iterations``, ``seconds``, ``method``, ``observability`` (with ``determined`` and,
    if needed, a ``warning`` naming what the motion leaves undetermined).
    """
    if joint not in JOINTS:
        raise InputError(f"expected joint in {JOINTS}, got {joint!r}", field="joint")
    if method not in METHODS:
        raise InputError(f"expected method in {METHODS}, got {method!r}", field="method")
    imu1, imu2 = Path(imu1), Path(imu2)
    r1, r2 = _read_pair(imu1, imu2)
    data = joint_data(r1.time, r1.gyr, r1.acc, r2.gyr, r2.acc)
    # orientations, when both files have them, make the two axis signs consistent
    have_quats = r1.quat is not None and r2.quat is not None
    quats = {"quat_1": r1.quat, "quat_2": r2.quat} if have_quats else {}
    options = {}
    if iterations is not None:
        options[ITERATION_OPTION[method]] = int(iterations)
    if population is not None:
        if method not in POPULATION_OPTION:
            raise InputError(f"--population applies to the swarms ({', '.join(POPULATION_OPTION)})"
                             f", not {method}", field="population")
        options[POPULATION_OPTION[method]] = int(population)
    res = calibrate(data, joint, method, seed=seed, **quats, **options)
    obs = _observability_summary(res.observability)
    out = {
        "axis_1": res.axis_1,
        "axis_2": res.axis_2,
        "position_1_m": res.position_1_m,
        "position_2_m": res.position_2_m,
        "cost": res.cost,
        "iterations": res.iterations,
        "seconds": res.seconds,
        "method": res.method,
        "observability": obs,
    }
    if as_json:
        return json.dumps(jsonable(out), indent=2)
    lines = [
        f"{joint} calibration: {res.method}, {res.iterations} iterations, {res.seconds:.3f} s, "
        f"cost {res.cost:.4g}",
        f"  sensor 1: {imu1}",
        f"  sensor 2: {imu2}",
        f"  {'':<14}{'x':>9}{'y':>9}{'z':>9}",
    ]
    for key in CALIBRATION_KEYS[:4]:
        v = out[key]
        if v is not None:
            lines.append(f"  {key:<14}" + "".join(f"{x:>9.4f}" for x in np.asarray(v, float)))
    lines.append("  (axes: unit vectors in each sensor frame; positions: sensor -> joint, m)")
    lines.append(f"  observability: {obs.get('message', '')}")
    if not obs["determined"]:
        lines.append(f"  WARNING: {obs['warning']}")
    return "\n".join(lines)


# ------------------------------------------------------------------------ calibration -> model
