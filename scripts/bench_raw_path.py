"""The raw-signal path against the simulator's truth: joint angles and landmarks, and the time.

For each motion and seed, ``simulate_trial`` (hinge knee, sensors misaligned by up to 15 deg and
offset by up to 2 cm, white noise and a constant gyro bias per sensor; see
:class:`pipeline.simulate.model.SensorNoise`) starts with 2 s still in the motion's rest pose
(standing; supine for ``supine_hip_flexion``, given as ``calibration_pose``) and runs 15 s of it.
Three inputs go through :func:`pipeline.process.process_recording`
with its defaults (free knee, AoR correction):

* ``vqf`` / ``pi``: gyroscope, accelerometer and magnetometer (the quaternions removed),
  orientations by the attitude filter (VQF 9-D; PI is 6-D, it has no magnetometer input);
  ``--no-mag`` drops the magnetometer (VQF 6-D);
* ``orientations``: the simulated sensor orientations (what a vendor's fusion would give).

Printed: RMS errors over the motion (after the standing phase) of the ISB joint angles
(flexion and the other two axes, hip, knee, ankle, both legs pooled) and of the landmarks, each
expressed in its own pelvis frame (what IMUs observe: no heading, no translation; leg landmarks
EFM, EFL, KJC, AJC, MM, LM and the foot's HEE, MT1, MT5, TOE apart), and the compute time of the
whole ``process_recording`` call (filtering included). The simulated subject stands upright with
the joints at zero; its knee is a hinge about the population AoR, whose straight pose turns the
tibia and foot by ~12 deg from the femur's frame: the default free knee assumes them aligned, the
AoR correction (eq 9-12) finds the tibia's turn and the foot follows it
(:func:`pipeline.calibration.correction.carried_correction`). In ``supine_hip_flexion`` the left
leg lies still (its knee moves 5 deg): its AoR cannot be seen and it is corrected as the reference
population's knee (:func:`pipeline.calibration.correction.population_correction`). The
"orientations" rows are the floor the calibration leaves with exact sensor orientations (1-3 mm).

Usage: ``python scripts/bench_raw_path.py [--seeds 0 1 2] [--motions gait] [--no-mag]
[--correction aor|functional]``
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pipeline.analysis.joint_angles import joint_angles
from pipeline.analysis.landmarks import frame_trajectories
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.process import process_recording
from pipeline.simulate.model import simulate_trial

STANDING_S, MOTION_S = 2.0, 15.0
SUBJECT = Measures("m", 1.75)
MAG = True  # with the simulated magnetometer (9-D for VQF); --no-mag: 6-D
NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}


def trial_and_inputs(motion: str, seed: int):
    geometry, _ = geometry_from_measures(SUBJECT)
    model = Skeleton.build(geometry, knee="hinge", root="freeflyer")
    trial = simulate_trial(model, motion, duration_s=STANDING_S + MOTION_S, seed=seed,
                           standing_s=STANDING_S)  # fmt: skip
    raw, oriented = {}, {}
    for frame, imu in trial.imus.items():
        s = imu.recording.sensor
        raw[NAMES[frame]] = SensorSignals(gyr=s.gyr, acc=s.acc, mag=s.mag if MAG else None)
        oriented[NAMES[frame]] = SensorSignals(quat=s.quat)
    t = trial.time
    return trial, Recording(t, 100.0, raw), Recording(t, 100.0, oriented)


def errors(trial, run, n0: int) -> dict[str, float]:
    truth = joint_angles(trial.skeleton, trial.q)
    out: dict[str, list[float]] = {}
    for key, est in run.joint_angles.items():
        if key.startswith("pelvis") or key not in truth:
            continue
        joint, axis = key.split("_")[1], key.split("_")[-1]
        group = f"{joint} {'flexion' if axis == 'flexion' else 'other'}"
        e = np.degrees(est[n0:] - truth[key][n0:])
        out.setdefault(group, []).extend(e.tolist())
    res = {k: float(np.sqrt(np.mean(np.square(v)))) for k, v in out.items()}
    # landmarks in each model's own pelvis frame
    Rt, pt = frame_trajectories(trial.skeleton, trial.q, ["pelvis"])["pelvis"]
    Re, pe = frame_trajectories(run.skeleton, run.q, ["pelvis"])["pelvis"]
    sq: dict[str, list[float]] = {"leg landmarks mm": [], "foot landmarks mm": []}
    for name, est in run.landmarks.items():
        if name not in trial.landmarks or name.endswith("HJC"):
            continue
        a = np.einsum("nji,nj->ni", Rt, trial.landmarks[name] - pt)[n0:]
        b = np.einsum("nji,nj->ni", Re, est - pe)[n0:]
        foot = name.split("_", 1)[1] in ("HEE", "MT1", "MT5", "TOE")
        sq["foot landmarks mm" if foot else "leg landmarks mm"].extend(
            np.sum((a - b) ** 2, axis=1).tolist())  # fmt: skip
    res.update({k: 1e3 * float(np.sqrt(np.mean(v))) for k, v in sq.items()})
    return res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--motions", nargs="+", default=["gait"])
    ap.add_argument("--no-mag", action="store_true", help="gyroscope + accelerometer only (6-D)")
    ap.add_argument("--correction", default="aor", help="the knee correction (default aor; "
                    "functional: towards the trusted joint-constraint hinge axis)")
    args = ap.parse_args()
    global MAG
    MAG = not args.no_mag
    n0 = int(STANDING_S * 100)
    rows = []
    for motion in args.motions:
        for seed in args.seeds:
            trial, raw, oriented = trial_and_inputs(motion, seed)
            pose = {"supine_hip_flexion": "supine", "still_thigh": "seated"}.get(motion, "standing")
            for label, rec, kw in (("vqf", raw, {"filter": "vqf"}), ("pi", raw, {"filter": "pi"}),
                                   ("orientations", oriented,
                                    {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)})):  # fmt: skip
                t0 = time.perf_counter()
                run = process_recording(rec, SUBJECT, calibration_pose=pose,
                                        correction=args.correction, **kw)  # fmt: skip
                seconds = time.perf_counter() - t0
                rows.append((motion, seed, label, errors(trial, run, n0), seconds))
    groups = ["hip flexion", "hip other", "knee flexion", "knee other", "ankle flexion",
              "ankle other", "leg landmarks mm", "foot landmarks mm"]  # fmt: skip
    print(f"raw path vs truth: {STANDING_S:g} s standing + {MOTION_S:g} s of motion at 100 Hz; "
          f"{'9-D' if MAG else '6-D (no magnetometer)'}; correction {args.correction}; "
          "RMS errors (deg; landmarks mm, pelvis frame); seconds of process_recording "
          "(the knees' joint-constraint calibration included)")
    print("| motion | seed | input | " + " | ".join(groups) + " | s |")
    print("|---|---|---|" + "---|" * (len(groups) + 1))
    for motion, seed, label, e, s in rows:
        cells = " | ".join(f"{e.get(g, float('nan')):.2f}" for g in groups)
        print(f"| {motion} | {seed} | {label} | {cells} | {s:.2f} |")


if __name__ == "__main__":
    main()
