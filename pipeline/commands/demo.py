"""``pipeline demo``: the whole product on an embedded, simulated subject (no external data).

1. scale: a 1.62 m female with measured knee and ankle widths -> Table I landmark positions and
   the population knee AoR -> URDF (hinge knee);
2. simulate one recording on that model, 2 s standing still then gait: gyroscope, accelerometer
   and magnetometer signals (and orientations) of sensors mounted with unknown misalignments and
   offsets, with noise and gyro bias (the truth is kept);
3. calibrate: the knee hinge axis in the thigh and shank sensor frames from gyro + acc alone
   (Hu 2021 eq 4-6, IPOPT), compared with the truth;
4. IK from the raw signals, as a lab's data: VQF orientations, then the ``pipeline ik`` path
   (calibration pose, anatomical heading, standing posture, orientation IK on a free-knee model,
   the defaults: no AoR correction),
   compared with the simulated joint angles and landmark trajectories, beside the same path on
   the simulated orientations;
5. outputs: ``demo_report.md``, ``demo_ik.mot``, ``demo_landmarks.csv``, ``subject.urdf``,
   ``demo.rrd`` (the moving model, estimated and true landmarks, joint-angle plots).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from pipeline.analysis.joint_angles import jcs_angles, joint_angles
from pipeline.calibration.calibrate import calibrate
from pipeline.calibration.joint_constraints import joint_data
from pipeline.commands.ik import write_landmarks_csv
from pipeline.errors import InputError
from pipeline.io.atomic import output_dir, output_set
from pipeline.io.mot import write_mot
from pipeline.io.opensim import sensor_to_opensim_matrix
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.io.tables import markdown_table
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.process import mot_columns, process_recording
from pipeline.rotations import angle_between
from pipeline.simulate.conventions import STANDING_S
from pipeline.simulate.model import simulate_trial
from pipeline.viz.model import SceneOptions, log_motion

__all__ = ["DEMO_FILES", "SUBJECT", "DemoResult", "demo", "run_demo"]

SUBJECT = Measures("f", 1.62, knee_width_m=0.095, ankle_width_m=0.066)
#: The standing time the demo accepts (s): the calibration pose needs half a second of rest.
MIN_STANDING_S, MAX_STANDING_S = 0.5, 10.0
#: The simulator's world is z-up (like Xsens); OpenSense's rotation to a y-up world.
Z_UP_TO_Y_UP = (-np.pi / 2, 0.0, 0.0)


@dataclass(frozen=True)
class DemoResult:
    """What the demo measured against the simulator's truth (degrees and metres)."""

    report: str
    axis_error_deg: tuple[float, float]
    angle_rms_deg: dict[str, float]
    landmark_rms_m: dict[str, float]
    knee_neutral_offset_deg: tuple[float, float, float]
    files: tuple[Path, ...]
    seconds: float


#: The files the demo writes.
DEMO_FILES = ("subject.urdf", "demo_ik_model.urdf", "demo_ik.mot", "demo_landmarks.csv",
              "demo.rrd", "demo_report.md")


def run_demo(out_dir: str | Path = "out/demo", seed: int = 0, standing_s: float = STANDING_S,
             overwrite: bool = False) -> str:
    """``pipeline demo``: run and return the text to print (the report and where files went); a
    previous demo's files in ``out_dir`` are refused, as ``pipeline ik`` refuses a previous run's,
    unless ``overwrite``."""
    previous = [n for n in DEMO_FILES if (Path(out_dir) / n).exists()]
    if previous and not overwrite:
        raise InputError(f"a previous demo's outputs are there ({', '.join(previous)}): give "
                         "another --out, or --overwrite to replace them", file=out_dir,
                         field="out")
    res = demo(out_dir, seed, standing_s=standing_s)
    names = ", ".join(p.name for p in res.files)
    return (
        f"{res.report}\nwrote {names} to {Path(out_dir)}\nview it with: pipeline view "
        f"{Path(out_dir) / 'demo.rrd'}\n"
    )


def demo(out_dir: str | Path = "out/demo", seed: int = 0,
         standing_s: float = STANDING_S) -> DemoResult:
    """Run the demo (``standing_s`` of standing still first: the calibration pose, at least
    :data:`MIN_STANDING_S`); every output is written all-or-nothing into ``out_dir``."""
    standing_s = float(standing_s)
    if not MIN_STANDING_S <= standing_s <= MAX_STANDING_S:
        raise InputError(f"expected {MIN_STANDING_S:g}-{MAX_STANDING_S:g} s of standing still (the "
                         f"calibration pose), got {standing_s:g}", field="standing_s")
    t_start = time.perf_counter()
    out_dir = Path(out_dir)
    output_dir(out_dir, create=False)
    timings: dict[str, float] = {}
    with output_set() as out:
        # 1. scale
        t0 = time.perf_counter()
        geometry, predicted = geometry_from_measures(SUBJECT)
        truth_model = Skeleton.build(geometry, knee="hinge")
        truth_model.write_urdf(out.path(out_dir / "subject.urdf"))
        timings["scale"] = time.perf_counter() - t0

        # 2. simulate one continuous recording: 2 s standing still (the calibration pose), a
        #    1.5 s transition, then gait; the simulator's world is z-up like an Xsens recording
        t0 = time.perf_counter()
        trial = simulate_trial(truth_model, "gait", duration_s=15.0 + standing_s, seed=seed,
                               standing_s=standing_s)
        n0 = int(round(standing_s * 100))
        timings["simulate"] = time.perf_counter() - t0

        # 3. calibrate the right knee hinge from raw gyro + acc
        t0 = time.perf_counter()
        thigh = trial.imus["right_femur_imu"].recording
        shank = trial.imus["right_tibia_imu"].recording
        moving = slice(n0, None)
        data = joint_data(trial.time[moving], thigh.gyr[moving], thigh.acc[moving],
                          shank.gyr[moving], shank.acc[moving])
        cal = calibrate(data, "hinge", "ipopt", quat_1=thigh.quat[moving],
                        quat_2=shank.quat[moving], seed=seed)
        timings["calibrate"] = time.perf_counter() - t0
        true_1, true_2 = trial.knee_axis["right_femur_imu"], trial.knee_axis["right_tibia_imu"]
        axis_err = [
            np.degrees(min(angle_between(cal.axis_1, true_1), angle_between(-cal.axis_1, true_1))),
            np.degrees(min(angle_between(cal.axis_2, true_2), angle_between(-cal.axis_2, true_2))),
        ]

        # 4. IK from the raw signals, as a lab's raw data: gyroscope, accelerometer and
        #    magnetometer -> VQF orientations -> calibration pose, heading, posture -> IK;
        #    the simulated (perfect-fusion) orientations through the same path for comparison
        t0 = time.perf_counter()
        names = {f"{seg}_imu": s for s, seg in SENSOR_TO_SEGMENT.items()}
        raw = {names[f]: SensorSignals(gyr=imu.recording.gyr, acc=imu.recording.acc,
                                       mag=imu.recording.mag)
               for f, imu in trial.imus.items() if f in names}
        run = process_recording(Recording(trial.time, 100.0, raw), SUBJECT, filter="vqf")
        run.skeleton.write_urdf(out.path(out_dir / "demo_ik_model.urdf"))
        timings["ik"] = time.perf_counter() - t0
        fused = process_recording(
            Recording.from_orientations(trial.time, 100.0, {names[f]: imu.recording.quat
                                                            for f, imu in trial.imus.items()}),
            SUBJECT, sensor_to_model=Z_UP_TO_Y_UP)
        truth_angles = joint_angles(trial.skeleton, trial.q)
        angle_rows, angle_rms, landmark_rms = [], {}, {}
        for key in ("right_hip_flexion", "right_hip_adduction", "right_hip_rotation",
                    "right_knee_flexion", "right_knee_adduction", "right_knee_rotation",
                    "right_ankle_flexion", "left_hip_flexion", "left_knee_flexion"):
            e = np.degrees(run.joint_angles[key][n0:] - truth_angles[key][n0:])
            e2 = np.degrees(fused.joint_angles[key][n0:] - truth_angles[key][n0:])
            angle_rms[key] = float(np.sqrt(np.mean(e**2)))
            angle_rows.append([key, f"{angle_rms[key]:.2f}", f"{np.abs(e).max():.2f}",
                               f"{np.sqrt(np.mean(e2**2)):.2f}"])
        # landmarks relative to the mid-hip point; the 9-D filter's world is the simulator's
        # (east, north, up), turned y-up like the estimate's
        W = sensor_to_opensim_matrix(Z_UP_TO_Y_UP)
        lm_rows, reference = [], {}
        hip_mid = 0.5 * (trial.landmarks["right_HJC"] + trial.landmarks["left_HJC"])
        est_mid = 0.5 * (run.landmarks["right_HJC"] + run.landmarks["left_HJC"])
        for name in ("right_EFM", "right_EFL", "right_KJC", "right_MM", "right_LM", "right_TOE"):
            true_rel = (trial.landmarks[name] - hip_mid) @ W.T
            est_rel = run.landmarks[name] - est_mid
            e = np.linalg.norm(est_rel - true_rel, axis=1)[n0:]
            landmark_rms[name] = float(np.sqrt(np.mean(e**2)))
            lm_rows.append([name, f"{1e3 * np.sqrt(np.mean(e**2)):.1f}",
                            f"{1e3 * e.max():.1f}"])
            world = true_rel + est_mid
            world[:n0] = np.nan
            reference[name] = world

        # 5. outputs
        t0 = time.perf_counter()
        write_mot(out.path(out_dir / "demo_ik.mot"), run.time, mot_columns(run))
        with out.open(out_dir / "demo_landmarks.csv") as fh:
            write_landmarks_csv(fh, run)
        # the simulator's truth beside the estimate (NaN over the standing calibration pose)
        truth_curves = {k: np.where(np.arange(len(trial.time)) < n0, np.nan, truth_angles[k])
                        for k in run.joint_angles if k in truth_angles}
        log_motion(out.path(out_dir / "demo.rrd"), run.time, run.skeleton, run.q,
                   SceneOptions(reference_angles=truth_curves, reference_landmarks=reference,
                                recording_name="pipeline demo"))
        timings["write"] = time.perf_counter() - t0
        total = time.perf_counter() - t_start
        offset = _knee_neutral_offset(trial.skeleton)
        report = _report(predicted, geometry, trial, cal, axis_err, run, angle_rows, lm_rows,
                         timings, total, offset, standing_s)
        with out.open(out_dir / "demo_report.md") as fh:
            fh.write(report)
    files = tuple(out_dir / n for n in DEMO_FILES)
    return DemoResult(report, tuple(axis_err), angle_rms, landmark_rms, tuple(offset), files,
                      total)


def _knee_neutral_offset(sk) -> np.ndarray:
    """ISB knee angles (flexion, adduction, rotation; deg) of a model at its neutral pose."""
    q = sk.neutral()
    R_F = sk.relative_pose("right_femur", "pelvis", q)[:3, :3]
    R_T = sk.relative_pose("right_tibia", "pelvis", q)[:3, :3]
    return np.degrees(jcs_angles(R_F[None], R_T[None], "knee", "right")[0])


def _report(predicted, geometry, trial, cal, axis_err, run, angle_rows, lm_rows, timings, total,
            knee_offset, standing_s) -> str:
    fps = len(run.time) / max(timings["ik"], 1e-9)
    lines = [
        "# pipeline demo",
        "",
        f"Simulated subject: sex {SUBJECT.sex}, height {SUBJECT.height_m} m, knee width "
        f"{SUBJECT.knee_width_m} m, ankle width {SUBJECT.ankle_width_m} m; one recording at 100 "
        f"Hz: {standing_s:g} s standing still, then a 1.5 s transition into gait "
        f"({15 + standing_s:g} s in all); "
        f"IMUs misaligned up to 15 deg and offset up to 2 cm on their segments; gyro noise "
        f"{trial.noise.gyro_sd} rad/s, accelerometer noise {trial.noise.acc_sd} m/s².",
        "",
        "## 1. Scaled model (Wang 2023 Table I, population knee AoR)",
        "",
        f"thigh {1e3 * geometry.thigh_length:.0f} mm, shank {1e3 * geometry.shank_length:.0f} mm, "
        f"knee width {1e3 * geometry.knee_width:.0f} mm, ankle width "
        f"{1e3 * geometry.ankle_width:.0f} mm.",
        "",
        "## 2-3. Knee hinge calibration from gyro + accelerometer (Hu 2021, IPOPT)",
        "",
        f"axis error vs truth: thigh sensor {axis_err[0]:.3f} deg, shank sensor "
        f"{axis_err[1]:.3f} deg; {cal.iterations} iterations, {1e3 * cal.seconds:.0f} ms with an "
        "independent verification start "
        "(the paper reports 10-25 minutes per calibration).",
        "",
        "## 4. IK from the raw signals (VQF, calibration pose, anatomical heading, posture)",
        "",
        f"Gyroscope, accelerometer and magnetometer: VQF orientations (9-D), then the "
        f"`pipeline ik` path; "
        f"{len(run.time)} frames in {timings['ik']:.2f} s ({fps:.0f} frames/s, filtering and "
        f"model building included); residual median "
        f"{np.degrees(np.nanmedian(run.residual_rms)):.2f} deg.",
        "",
        markdown_table(["joint angle", "RMS error (deg)", "max error (deg)",
                        "RMS error, simulated orientations (deg)"], angle_rows),
        "",
        markdown_table(
            ["landmark (relative to mid-hip)", "RMS error (mm)", "max error (mm)"], lm_rows
        ),
        "",
        "Errors are over the gait after the standing pose (sensor placements from it), for a "
        "free-knee IK model of the same regression geometry. Landmarks are compared relative to "
        "the mid-hip point (IMUs observe no translation). The simulated hinge's neutral pose "
        "is not the ISB zero (knee rotation / "
        f"adduction {knee_offset[2]:.1f} / {knee_offset[1]:.1f} deg: the hinge turns the tibia "
        "by the rotation that aligns the tibial AoR onto the femoral one): a standing "
        "calibration takes the standing knee as zero, so the knee's adduction and rotation "
        "errors are that offset. `--correction aor` (Wang eq 9-13) would find the turn of a "
        "hinge about the population axis, as this one is; it is not the default because real "
        "knees are not (results/bench_defaults.txt). The gap between the raw and the "
        "orientation column is the filter's. Without magnetometers (6-D) each sensor's filter "
        "has a heading of its own, which the joints align "
        "(--drift; scripts/bench_raw_path.py --no-mag, results/bench_raw_path.txt).",
        "",
        f"Total {total:.1f} s (scale {timings['scale']:.2f} s, simulate "
        f"{timings['simulate']:.2f} s, calibrate {timings['calibrate']:.2f} s, IK "
        f"{timings['ik']:.2f} s, write {timings['write']:.2f} s).",
    ]
    return "\n".join(lines) + "\n"
