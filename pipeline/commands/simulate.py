"""``pipeline simulate``: a simulated trial with known truth, written as a user's recording.

:func:`run_simulation` simulates a trial on a default scaled subject (1.75 m male, Wang eq 14
regression + population knee AoR, hinge knee) with :mod:`pipeline.simulate.model` and writes,
all or nothing, the recording (``imu/``: one IMU CSV per sensor, what ``pipeline ik`` and
``pipeline orientations`` read) and the truth (``truth/``: ``truth.json``, the URDF, the landmark
trajectories and the model configurations).
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.atomic import output_dir, output_set
from pipeline.io.imu_csv import write_imu_csv
from pipeline.io.jsonio import jsonable
from pipeline.io.tables import write_array_csv
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import log3
from pipeline.simulate.model import simulate_trial

__all__ = ["MAX_DURATION_S", "run_simulation"]

MAX_DURATION_S = 600.0


def _truth(trial, files: dict[str, str], sex: str, height_m: float) -> dict:
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


def run_simulation(
    out_dir: str | Path, motion: str = "gait", duration_s: float = 15.0, seed: int = 0,
    standing_s: float = 0.0,
) -> str:
    """Simulate ``motion`` (one of :data:`pipeline.simulate.motions.MOTIONS`) on a
    default scaled subject and write (all or nothing) into ``out_dir``:

    ``imu/<imu frame>.csv`` per sensor (``time,gyr_x..acc_z,quat_w..quat_z``, SI units);
    ``truth/truth.json`` (sensor placements and misalignments, knee axis and joint centres in each
    sensor frame, noise, seed, motion), ``truth/model.urdf``, ``truth/landmarks.csv`` (world
    positions, m) and ``truth/configuration.csv`` (model q). ``standing_s``: the trial starts with
    that long still in the neutral standing pose (a calibration pose), then moves into the motion.
    Returns a summary listing the files.
    """
    out = Path(out_dir)
    duration_s = float(duration_s)
    if not np.isfinite(duration_s) or not 0 < duration_s <= MAX_DURATION_S:
        raise InputError(
            f"expected a duration in (0, {MAX_DURATION_S:g}] s, got {duration_s:g}",
            field="duration_s",
        )
    measures = Measures(sex="m", height_m=1.75)
    geometry, _ = geometry_from_measures(measures)
    skeleton = Skeleton.build(geometry, knee="hinge", root="freeflyer")
    standing_s = float(standing_s)
    if not np.isfinite(standing_s) or not 0 <= standing_s < duration_s:
        raise InputError(f"expected a standing time in [0, {duration_s:g}) s, got {standing_s:g}",
                         field="standing_s")
    trial = simulate_trial(skeleton, motion, duration_s=duration_s, seed=seed,
                           standing_s=standing_s)
    files = {name: f"{name}.csv" for name in trial.imus}
    truth = _truth(trial, files, measures.sex, measures.height_m)
    lm_names = list(trial.landmarks)
    lm = np.column_stack([trial.time] + [trial.landmarks[n] for n in lm_names])
    lm_header = ["time"] + [f"{n}_{c}" for n in lm_names for c in "xyz"]
    q_header = ["time", "root_x", "root_y", "root_z", "root_qx", "root_qy", "root_qz"]
    q_header += ["root_qw"] + skeleton.joint_names[1:]
    output_dir(out, create=False)
    imu, truth_dir = out / "imu", out / "truth"
    with output_set() as outs:
        for name, fname in files.items():
            write_imu_csv(outs.path(imu / fname), trial.imus[name].recording)
        with outs.open(truth_dir / "truth.json") as f:
            json.dump(jsonable(truth), f, indent=2)
            f.write("\n")
        with outs.open(truth_dir / "model.urdf") as f:
            f.write(skeleton.urdf)
        with outs.open(truth_dir / "landmarks.csv", newline="\n") as f:
            write_array_csv(f, lm_header, lm)
        with outs.open(truth_dir / "configuration.csv", newline="\n") as f:
            write_array_csv(f, q_header, np.column_stack([trial.time, trial.q]))
    written = [os.path.relpath(p, out) for p in outs.destinations]
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
