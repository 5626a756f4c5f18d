"""Heading drift on a long trial without magnetometers: joint angles with and without the
joint-constraint heading alignment, against the simulator's truth.

``simulate_trial`` (hinge knee, sensors misaligned by up to 15 deg and offset by up to 2 cm,
white noise and a constant gyro bias of SD 0.005 rad/s = 0.29 deg/s per axis and sensor, the
simulator's default) gives 2 s standing and then ``--minutes`` of weaving gait. The gyroscope and
accelerometer signals (no magnetometer, no quaternions) go through
:func:`pipeline.process.process_recording` with VQF 6-D, once with ``drift='none'`` and once with
the default ``drift='auto'`` (each leg's sensors turned into the pelvis sensor's heading by the hip
and ankle centres and the knee's hinge axis, :mod:`pipeline.process.heading_alignment`); the 9-D
run (with the simulated, undisturbed magnetometer) is the reference a magnetometer would give.

Printed: the heading that each joint's alignment applied (its range over the trial: the
filter's heading difference between the two sensors, a constant from their starts plus the
drift), the knee angles' RMS error against the truth minute by minute (flexion and the other two
axes, both legs pooled), and the whole trial's errors (hip, knee, ankle; landmarks in the pelvis
frame, as ``scripts/bench_raw_path.py``) with the compute time.

Written: ``results/bench_drift.txt`` (also printed). With the default options (no knee correction)
the simulator's hinge knee, whose axis is the reference population's tilted AoR, shows in every
input alike as knee ab/adduction and rotation errors and leg landmark errors (``--correction aor``
finds it); the comparison here is between the inputs.

Usage: ``python scripts/bench_drift.py [--minutes 10] [--seed 0] [--out results]``
"""

from __future__ import annotations

import argparse
import contextlib
import io
import time
from pathlib import Path

import numpy as np
from bench_raw_path import NAMES, SUBJECT, errors

from pipeline.analysis.joint_angles import joint_angles
from pipeline.io.recording import Recording, SensorSignals
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.process import process_recording
from pipeline.simulate.model import simulate_trial

STANDING_S = 2.0


def knee_by_minute(trial, run, n0: int, rate: float) -> list[tuple[float, float]]:
    """(flexion, other) RMS error (deg) of both knees per minute of motion."""
    truth = joint_angles(trial.skeleton, trial.q)
    per = int(60 * rate)
    rows = []
    for start in range(n0, len(trial.time) - per // 2, per):
        sl = slice(start, min(start + per, len(trial.time)))
        flex, other = [], []
        for key, est in run.joint_angles.items():
            if "_knee_" not in key:
                continue
            e = np.degrees(est[sl] - truth[key][sl])
            (flex if key.endswith("flexion") else other).append(e)
        rms = [float(np.sqrt(np.mean(np.square(np.concatenate(x))))) for x in (flex, other)]
        rows.append((rms[0], rms[1]))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", type=Path, default=Path(__file__).resolve().parents[1] / "results")
    args = ap.parse_args()
    text = io.StringIO()
    with contextlib.redirect_stdout(text):
        report(args)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_drift.txt").write_text(text.getvalue())
    print(text.getvalue(), end="")


def report(args) -> None:
    geometry, _ = geometry_from_measures(SUBJECT)
    model = Skeleton.build(geometry, knee="hinge", root="freeflyer")
    t0 = time.perf_counter()
    trial = simulate_trial(model, "gait", duration_s=STANDING_S + 60 * args.minutes,
                           seed=args.seed, standing_s=STANDING_S)
    sim_s = time.perf_counter() - t0
    rate = 100.0
    n0 = int(STANDING_S * rate)
    runs = {}
    for label, mag, drift in (("6-D, no alignment", False, "none"),
                              ("6-D, joint alignment", False, "auto"),
                              ("9-D (magnetometer)", True, "auto")):
        sensors = {}
        for frame, imu in trial.imus.items():
            s = imu.recording.sensor
            sensors[NAMES[frame]] = SensorSignals(gyr=s.gyr, acc=s.acc, mag=s.mag if mag else None)
        rec = Recording(trial.time, rate, sensors)
        t0 = time.perf_counter()
        run = process_recording(rec, SUBJECT, filter="vqf", drift=drift)
        runs[label] = (run, time.perf_counter() - t0)

    bias = np.degrees([np.abs(i.gyro_bias).max() for i in trial.imus.values()])
    print(f"heading drift: {STANDING_S:g} s standing + {args.minutes:g} min of simulated gait at "
          f"100 Hz, seed {args.seed} (simulated in {sim_s:.1f} s); constant gyro bias per sensor "
          f"up to {bias.max():.2f} deg/s on an axis; VQF")
    print()
    run, _ = runs["6-D, joint alignment"]
    print("heading turned by each joint's alignment (6-D; deg, over the trial):")
    print("| joint | from | to | drift | constraint residual after | with a constant heading |")
    print("|---|---|---|---|---|---|")
    for key, d in run.heading_drifts.items():
        print(f"| {key.replace('_', ' ')} | {np.degrees(d.psi.min()):.1f} | "
              f"{np.degrees(d.psi.max()):.1f} | {d.drift_deg:.1f} | {d.residual_deg:.2f} | "
              f"{d.before_deg:.2f} |")
    skipped = [n for n in run.notes if "heading not aligned" in n]
    for n in skipped:
        print(f"- {n}")
    print()
    print("knee RMS error against the truth per minute of gait (deg, both legs):")
    labels = list(runs)
    minutes = {lab: knee_by_minute(trial, runs[lab][0], n0, rate) for lab in labels}
    print("| minute | " + " | ".join(f"{lab}: flexion | other" for lab in labels) + " |")
    print("|---|" + "---|---|" * len(labels))
    for m in range(len(minutes[labels[0]])):
        cells = " | ".join(f"{minutes[lab][m][0]:.2f} | {minutes[lab][m][1]:.2f}"
                           for lab in labels)
        print(f"| {m + 1} | {cells} |")
    print()
    groups = ["hip flexion", "hip other", "knee flexion", "knee other", "ankle flexion",
              "ankle other", "leg landmarks mm", "foot landmarks mm"]
    print("whole trial, RMS errors against the truth (deg; landmarks mm, pelvis frame):")
    print("| input | " + " | ".join(groups) + " | s |")
    print("|---|" + "---|" * (len(groups) + 1))
    for lab in labels:
        run, seconds = runs[lab]
        e = errors(trial, run, n0)
        print(f"| {lab} | " + " | ".join(f"{e[g]:.2f}" for g in groups) + f" | {seconds:.1f} |")


if __name__ == "__main__":
    main()
