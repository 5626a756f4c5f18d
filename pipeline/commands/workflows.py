"""The command line's library side: ``pipeline simulate`` and ``pipeline calibrate``.

* :func:`run_simulation` simulates a trial on a default scaled subject (1.75 m male, Wang eq 14
  regression + population knee AoR, hinge knee) with :mod:`pipeline.simulate.model` and writes,
  all or nothing, one IMU CSV per sensor, ``truth.json``, the URDF, the landmark trajectories and
  the model configurations.
* :func:`run_calibration` reads two IMU CSVs and runs the Hu 2021 joint-constraint calibration
  (Gauss-Newton, DWPSO, GWO or the IPOPT formulation), reporting undetermined parameters.
* :func:`imu_placements_from_calibration` turns a hinge calibration into IMU frames of the model
  (``build_urdf(..., imu_placements=...)``): what the data determine and what must be assumed.
"""

from __future__ import annotations

import json
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import normalize, rotation_aligning_with_twist

__all__ = [
    "PlacementEstimate",
    "imu_placements_from_calibration",
    "run_calibration",
    "run_simulation",
]

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
METHODS = ("gn", "dwpso", "gwo", "ipopt")
MAX_DURATION_S = 600.0


# ---------------------------------------------------------------------------------- simulation


def _jsonable(x):
    """Nested dicts/lists/arrays -> JSON types; non-finite floats -> None."""
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    if isinstance(x, Path):
        return str(x)
    return x


def _truth(trial, files: dict[str, str], sex: str, height_m: float) -> dict:
    from pipeline.rotations import log3

    sensors = {}
    for name, s in trial.imus.items():
        sensors[name] = {
            "file": files[name],
            "segment": s.segment,
            "rotation_in_segment": s.R_segment,
            "position_in_segment_m": s.p_segment,
            "misalignment": s.misalignment,
            "misalignment_deg": float(np.degrees(np.linalg.norm(log3(s.misalignment)))),
            "offset_m": s.offset_m,
            "gyro_bias_rad_s": s.gyro_bias,
        }
    joints = {}
    for joint, centres in trial.joint_centres.items():
        (s1, o1), (s2, o2) = centres.items()
        entry = {"proximal": s1, "distal": s2, "position_1_m": o1, "position_2_m": o2}
        if joint.endswith("_knee") and s1 in trial.knee_axis:
            entry = {"type": "hinge", **entry, "axis_1": trial.knee_axis[s1]}
            entry["axis_2"] = trial.knee_axis[s2]
            entry["note"] = (
                "axes point to the subject's right; positions: knee centre (KJC); a hinge "
                "calibration returns the point of the axis with axis_1.o_1 + axis_2.o_2 = 0 (eq 16)"
            )
        else:
            entry = {"type": "spherical", **entry}
        joints[joint] = entry
    noise = trial.noise
    return {
        "motion": trial.motion,
        "seed": trial.seed,
        "duration_s": float(trial.time.size / trial.imus["pelvis_imu"].recording.rate_hz),
        "rate_hz": trial.imus["pelvis_imu"].recording.rate_hz,
        "subject": {"sex": sex, "height_m": height_m},
        "model": {"urdf": "model.urdf", "root": "freeflyer", "knee": trial.skeleton.knee},
        "world": {"up": "z", "gravity_m_s2": trial.gravity},
        "noise": {
            "gyro_sd_rad_s": noise.gyro_sd,
            "acc_sd_m_s2": noise.acc_sd,
            "gyro_bias_sd_rad_s": noise.gyro_bias_sd,
            "orientation_sd_deg": noise.orientation_sd_deg,
            "landmark_sd_m": noise.landmark_sd_m,
        },
        "sensors": sensors,
        "joints": joints,
    }


def _write_table(f, header: Sequence[str], data: np.ndarray) -> None:
    f.write(",".join(header) + "\n")
    for row in data:
        f.write(",".join(f"{v:.10g}" for v in row) + "\n")


def run_simulation(
    out_dir: str | Path, motion: str = "rich", duration_s: float = 15.0, seed: int = 0
) -> str:
    """Simulate ``motion`` ('rich'/'gait', 'supine_hip_flexion', 'still_thigh', 'static') on a
    default scaled subject and write (all or nothing) into ``out_dir``:

    ``<imu frame>.csv`` per sensor (``time,gyr_x..acc_z,quat_w..quat_z``, SI units),
    ``truth.json`` (sensor placements and misalignments, knee axis and joint centres in each
    sensor frame, noise, seed, motion), ``model.urdf``, ``landmarks.csv`` (world positions, m)
    and ``configuration.csv`` (model q). Returns a summary listing the files.
    """
    from pipeline.io.atomic import output_set
    from pipeline.io.imu_csv import write_imu_csv
    from pipeline.model.anthropometry import Measures
    from pipeline.model.builder import build_urdf
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.model import simulate_trial

    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise InputError("expected an output directory, found a file", file=out)
    duration_s = float(duration_s)
    if not np.isfinite(duration_s) or not 0 < duration_s <= MAX_DURATION_S:
        raise InputError(
            f"expected a duration in (0, {MAX_DURATION_S:g}] s, got {duration_s:g}",
            field="duration_s",
        )
    measures = Measures(sex="m", height_m=1.75)
    geometry, _ = geometry_from_measures(measures)
    with tempfile.TemporaryDirectory(prefix="pipeline_sim_") as tmp:
        urdf = build_urdf(geometry, Path(tmp) / "model.urdf", knee="hinge")
        urdf_text = urdf.read_text(encoding="utf-8")
        skeleton = Skeleton.from_urdf(urdf, root="freeflyer")
        trial = simulate_trial(skeleton, motion, duration_s=duration_s, seed=seed)
        files = {name: f"{name}.csv" for name in trial.imus}
        truth = _truth(trial, files, measures.sex, measures.height_m)
        lm_names = list(trial.landmarks)
        lm = np.column_stack([trial.time] + [trial.landmarks[n] for n in lm_names])
        lm_header = ["time"] + [f"{n}_{c}" for n in lm_names for c in "xyz"]
        q_header = ["time", "root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz"]
        q_header += ["root_qw"] + skeleton.joint_names[1:]
        with output_set() as outs:
            for name, fname in files.items():
                write_imu_csv(outs.path(out / fname), trial.imus[name].recording)
            with outs.open(out / "truth.json") as f:
                json.dump(_jsonable(truth), f, indent=2)
                f.write("\n")
            with outs.open(out / "model.urdf") as f:
                f.write(urdf_text)
            with outs.open(out / "landmarks.csv", newline="\n") as f:
                _write_table(f, lm_header, lm)
            with outs.open(out / "configuration.csv", newline="\n") as f:
                _write_table(f, q_header, np.column_stack([trial.time, trial.q]))
        written = [p.name for p in outs.destinations]
    knee = truth["joints"]["right_knee"]
    lines = [
        f"simulated {duration_s:g} s of '{trial.motion}' at {truth['rate_hz']:g} Hz (seed {seed}) "
        f"on a {measures.height_m:g} m male model (hinge knee, free-flyer pelvis, world z up)",
        f"wrote {len(written)} files to {out}:",
        *(f"  {n}" for n in written),
        "right knee truth (unit axis, joint centre in m, sensor frames):",
        f"  axis_1 {_fmt(knee['axis_1'])}  position_1_m {_fmt(knee['position_1_m'])}"
        f"  ({knee['proximal']})",
        f"  axis_2 {_fmt(knee['axis_2'])}  position_2_m {_fmt(knee['position_2_m'])}"
        f"  ({knee['distal']})",
    ]
    return "\n".join(lines)


def _fmt(v) -> str:
    return "[" + ", ".join(f"{x:+.4f}" for x in np.asarray(v, float)) + "]"


# --------------------------------------------------------------------------------- calibration


def _read_pair(imu1: Path, imu2: Path):
    from pipeline.io.checks import check_same_length, check_same_rate
    from pipeline.io.imu_csv import read_imu_csv

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
    return r1, r2


def _observability_summary(obs: dict) -> dict:
    out = _jsonable(obs)
    undetermined = list(obs.get("undetermined", []))
    out["determined"] = not undetermined
    if undetermined:
        out["warning"] = (
            "UNDETERMINED by this motion: "
            + "; ".join(undetermined)
            + " - these values are not trustworthy (excite the segments about other axes, "
            "or use the IPOPT method with a population-axis prior)"
        )
    return out


def run_calibration(
    joint: str,
    imu1: str | Path,
    imu2: str | Path,
    method: str = "ipopt",
    seed: int = 0,
    as_json: bool = False,
) -> str:
    """Calibrate a 'hinge' or 'spherical' joint from two IMU CSVs (proximal ``imu1``, distal
    ``imu2``) with ``method`` in ('gn', 'dwpso', 'gwo', 'ipopt') and return the report text.

    JSON keys: ``axis_1``, ``axis_2`` (unit, sensor frames, null for a spherical joint),
    ``position_1_m``, ``position_2_m`` (sensor -> joint centre, m; hinge: the eq-16 point),
    ``cost``, ``iterations``, ``seconds``, ``method``, ``observability`` (with ``determined`` and,
    if needed, a ``warning`` naming what the motion leaves undetermined).
    """
    from pipeline.calibration.ipopt import calibrate_ipopt
    from pipeline.calibration.joint_constraints import joint_data
    from pipeline.calibration.solvers import calibrate

    if joint not in ("hinge", "spherical"):
        raise InputError(f"expected joint 'hinge' or 'spherical', got {joint!r}", field="joint")
    if method not in METHODS:
        raise InputError(f"expected method in {METHODS}, got {method!r}", field="method")
    imu1, imu2 = Path(imu1), Path(imu2)
    r1, r2 = _read_pair(imu1, imu2)
    data = joint_data(r1.time, r1.gyr, r1.acc, r2.gyr, r2.acc)
    # orientations, when both files have them, make the two axis signs consistent
    have_quats = r1.quat is not None and r2.quat is not None
    quats = {"quat_1": r1.quat, "quat_2": r2.quat} if have_quats else {}
    if method == "ipopt":
        res = calibrate_ipopt(data, joint, seed=seed, **quats)
    else:
        res = calibrate(data, joint, method, seed=seed, **quats)
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
        return json.dumps(_jsonable(out), indent=2)
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


@dataclass(frozen=True)
class PlacementEstimate:
    """IMU frame name -> 4x4 placement in its segment frame (for ``build_urdf``), the common
    shift along the knee axis that was assumed (``axial_shift_m``: KJC -> eq-16 point, m), and
    how the twist about the axis was fixed (``twist_from``: 'static pose' or 'default')."""

    placements: dict[str, np.ndarray]
    axial_shift_m: float
    twist_from: str
    notes: tuple[str, ...]


def imu_placements_from_calibration(
    skeleton,
    axis_1: np.ndarray,
    axis_2: np.ndarray,
    position_1_m: np.ndarray,
    position_2_m: np.ndarray,
    *,
    side: str = "right",
    static_acc: tuple[np.ndarray, np.ndarray] | None = None,
    static_up: tuple[np.ndarray, np.ndarray] = ((0.0, 1.0, 0.0), (0.0, 1.0, 0.0)),
    undetermined: Sequence[str] = (),
) -> PlacementEstimate:
    """Thigh and shank IMU frames from a hinge calibration (Hu 2021 eq 4-6, 16) on ``skeleton``.

    Inputs: the knee axis ``axis_S`` and the eq-16 joint point ``position_S_m`` (sensor -> point)
    in the thigh (1) and shank (2) sensor frames. The model gives the knee axis ``a_G`` pointing
    right and the knee centre ``c_G`` in each segment (:meth:`Skeleton.knee_axis`, KJC frames).

    Rotation ``R_GS`` (sensor axes in the segment): ``R_GS j_S = a_G`` fixes two of its three
    DoF. The twist about the axis is not determined by a hinge calibration. It is fixed

    * from a static pose when ``static_acc`` (mean specific force of sensors 1, 2 while still)
      is given: ``R_GS f_S`` is aligned with the up direction ``static_up`` of each segment in
      that pose (default: standing in the neutral pose, segment y axes vertical);
    * otherwise by keeping the model's current IMU frame orientation ``R_def`` as far as the
      axis allows (the rotation with ``R j = a`` nearest to ``R_def``).

    The axis signs (both flipped together by the calibration) are chosen so that ``R_def j_1``
    points right, i.e. the current frames must be within 90 deg of the truth.

    Position: the eq-16 point lies on the axis, ``p_GS + R_GS o_S = c_G + lambda a_G``. The
    relative position of both sensors along the axis is determined; one common shift ``lambda``
    is not (any point of a hinge axis satisfies the constraint). It is chosen so that the mean
    axial coordinate of the two sensors stays that of the current IMU frames (least squares).
    """
    if static_acc is not None and len(static_acc) != 2:
        raise InputError("expected static_acc as (thigh, shank) 3-vectors", field="static_acc")
    a_f, a_t = skeleton.knee_axis(side)
    names = (f"{side}_femur", f"{side}_tibia")
    q0 = skeleton.neutral()
    centres = [skeleton.relative_pose(f"{side}_KJC", seg, q0)[:3, 3] for seg in names]
    defaults = [skeleton.relative_pose(f"{seg}_imu", seg, q0) for seg in names]
    js = [normalize(np.asarray(axis_1, float)), normalize(np.asarray(axis_2, float))]
    os_ = [np.asarray(position_1_m, float), np.asarray(position_2_m, float)]
    if np.dot(defaults[0][:3, :3] @ js[0], a_f) < 0:
        js = [-js[0], -js[1]]
    notes = []
    rotations = []
    for k, (j, a, T) in enumerate(zip(js, (a_f, a_t), defaults, strict=True)):
        if static_acc is not None:
            f = normalize(np.asarray(static_acc[k], float))
            R = rotation_aligning_with_twist(j, a, f, np.asarray(static_up[k], float))
        else:
            R = rotation_aligning_with_twist(j, a, np.eye(3), T[:3, :3].T)
        rotations.append(R)
    twist = "static pose" if static_acc is not None else "default"
    if static_acc is None:
        notes.append("twist about the knee axis kept from the current IMU frames (undetermined)")
    # lambda_S = a.(p_def - c) + j.o per sensor; the common shift is their mean.
    lams = [
        float(a @ (T[:3, 3] - c) + j @ o)
        for a, T, c, j, o in zip((a_f, a_t), defaults, centres, js, os_, strict=True)
    ]
    lam = float(np.mean(lams))
    notes.append(f"common shift along the knee axis assumed: {lam * 1000:.1f} mm from the KJC")
    placements = {}
    for seg, R, a, c, o in zip(names, rotations, (a_f, a_t), centres, os_, strict=True):
        T = np.eye(4)
        T[:3, :3] = R
        T[:3, 3] = c + lam * a - R @ o
        placements[f"{seg}_imu"] = T
    if undetermined:
        notes.append("calibration reported undetermined: " + "; ".join(undetermined))
    return PlacementEstimate(placements, lam, twist, tuple(notes))
