"""The simulated walk against the real ones, in what the estimators see (issue 23 item 6: a
simulator that looks like the data): per stride of straight walking, each segment's swing and
speed from its gyroscope, and the joints' rigid-body constraints' residuals.

    python scripts/bench_sim_realism.py [--data ../shared/data] [--out FILE]

Recordings: S02 (Xsens MTw, Vicon's lab; its walk), the x-IMU3 walk shipped with the package (a
slow walk with turns on the spot), and the simulated walk (``pipeline.simulate.walk``, free knee
and ankle, seeds 0-2) ideal and with its artefacts (``pipeline.simulate.artefacts``: soft tissue,
wandering biases, the floor's field). Per quantity the median over both legs' (and the seeds')
values; strides from `pipeline ik`'s gait step, those turning less than 20 deg:

* **swing** (deg): the range of the segment's angle about its sensor's principal axis of angular
  velocity (its flexion axis) over each stride, the gyroscope integrated and its drift over the
  stride removed;
* **speed** (rad/s): the sensor's RMS angular speed over the strides;
* **residual**: Hu 2021 eq 1-3 (the spherical joint's centre force, m/s^2) for the hip, knee and
  ankle, and eq 4-6 (the hinge, rad/s) for the knee, fitted on the whole recording low-passed at
  6 Hz as the heading alignment and the swap check fit them.

The last column says whether the simulated walk with its artefacts lies within the two real walks'
range (two subjects, two sensor makes: a quantity is not tuned to one recording), or its ratio to
the nearer of them (default output: ``results/bench_sim_realism.txt``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pipeline.io.formats import read_recording
from pipeline.io.recording import Recording
from pipeline.model.measures import Measures
from pipeline.process.functional import joint_residual
from pipeline.process.gait import gait_of

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
SEEDS = (0, 1, 2)
SEGMENTS = ("pelvis", "femur", "tibia", "calcn")
#: Joint -> its two sensors' segments (``pelvis`` has no side).
JOINTS = {"hip": ("pelvis", "femur"), "knee": ("femur", "tibia"), "ankle": ("tibia", "calcn")}
MAX_TURN_DEG = 20.0


def _sensor(segment: str, side: str) -> str:
    return "pelvis_imu" if segment == "pelvis" else f"{segment}_{side[0]}_imu"


def _strides(rec: Recording) -> list[tuple[str, int, int]]:
    return [(s.side, int(round(s.start_s * rec.rate_hz)), int(round(s.end_s * rec.rate_hz)))
            for s in gait_of(rec, []).strides if abs(s.turn_deg) < MAX_TURN_DEG]


def swing_and_speed(rec: Recording, strides) -> dict[str, tuple[float, float]]:
    """Segment -> (median swing per stride, deg; RMS angular speed over the strides, rad/s)."""
    out = {}
    for seg in SEGMENTS:
        swings, speeds = [], []
        for side in ("right", "left"):
            w = rec.sensors[_sensor(seg, side)].gyr
            mine = [(a, b) for s, a, b in strides if s == side]
            if not mine:
                continue
            walking = np.concatenate([w[a:b] for a, b in mine])
            axis = np.linalg.svd(walking, full_matrices=False)[2][0]
            for a, b in mine:
                angle = np.cumsum(w[a:b] @ axis) / rec.rate_hz
                angle -= np.linspace(0.0, angle[-1], len(angle))
                swings.append(np.degrees(np.ptp(angle)))
            speeds.append(float(np.sqrt(np.mean(np.sum(walking**2, axis=1)))))
        out[seg] = (float(np.median(swings)), float(np.median(speeds)))
    return out


def residuals(rec: Recording) -> dict[str, float]:
    """``<joint>`` (eq 1-3, m/s^2) and ``knee hinge`` (eq 4-6, rad/s), median over the legs."""
    out: dict[str, list[float]] = {}
    for joint, (prox, dist) in JOINTS.items():
        for side in ("right", "left"):
            s1, s2 = (rec.sensors[_sensor(seg, side)] for seg in (prox, dist))
            for kind in ("spherical", "hinge") if joint == "knee" else ("spherical",):
                key = joint if kind == "spherical" else "knee hinge"
                out.setdefault(key, []).append(joint_residual(
                    rec.time, rec.rate_hz, s1, s2, joint=kind, cutoff_hz=6.0, step=4))
    return {k: float(np.median(v)) for k, v in out.items()}


def measure(rec: Recording) -> dict[str, float]:
    strides = _strides(rec)
    row = {"strides": float(len(strides)),
           "stride time (s)": float(np.median([(b - a) / rec.rate_hz for _, a, b in strides]))}
    for seg, (swing, speed) in swing_and_speed(rec, strides).items():
        row[f"{seg} swing (deg)"], row[f"{seg} speed (rad/s)"] = swing, speed
    for joint, e in residuals(rec).items():
        unit = "rad/s" if "hinge" in joint else "m/s^2"
        row[f"{joint} residual ({unit})"] = e
    return row


def simulated(artefacts: bool) -> dict[str, float]:
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.artefacts import Artefacts
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(Measures("m", 1.75))[0], knee="free",
                        root="freeflyer", ankle="free")
    rows = [measure(simulate_trial(sk, "walk", duration_s=20.0, seed=seed, standing_s=3.0,
                                   artefacts=Artefacts() if artefacts else None).raw_recording())
            for seed in SEEDS]
    return {k: float(np.median([r[k] for r in rows])) for k in rows[0]}


def against_real(value: float, real: list[float]) -> str:
    """``within`` the real walks' range, or the ratio to the nearer real walk and which side."""
    low, high = min(real), max(real)
    if low <= value <= high:
        return "within"
    return f"{value / low:.2f} below" if value < low else f"{value / high:.2f} above"


def report(columns: dict[str, dict[str, float]]) -> str:
    names = list(columns)
    real = ("S02", "x-IMU3 walk")
    lines = ["# The simulated walk against the real ones (`scripts/bench_sim_realism.py`)", "",
             "Per stride of straight walking (module docstring); simulated: median over seeds "
             f"{', '.join(map(str, SEEDS))}. Last column: the simulated walk (with its artefacts) "
             "within the two real walks' range, or its ratio to the nearer of them.", "",
             "| quantity | " + " | ".join(names) + " | simulated against the real walks |",
             "|---" * (len(names) + 2) + "|"]
    sim = columns["simulated walk"]
    outside = []
    for key in columns[names[0]]:
        cells = [f"{columns[n][key]:.2f}" if key != "strides" else f"{columns[n][key]:.0f}"
                 for n in names]
        shown = "-"  # the recordings' lengths differ
        if key != "strides":
            shown = against_real(sim[key], [columns[r][key] for r in real])
            if shown != "within":
                outside.append(f"{key} {shown}")
        lines.append(f"| {key} | " + " | ".join(cells) + f" | {shown} |")
    lines += ["", "Outside the real walks' range: " + "; ".join(outside) + "."]
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "bench_sim_realism.txt")
    args = ap.parse_args()
    import sys

    sys.path.insert(0, str(ROOT / "scripts"))
    from bench_gait import S02_MAP

    s02 = read_recording(args.data / "gaittoolbox_s02" / "imu", S02_MAP)
    ximu3 = read_recording("example:ximu3_lower_body")
    columns = {"S02": measure(s02), "x-IMU3 walk": measure(ximu3),
               "simulated walk, ideal": simulated(False), "simulated walk": simulated(True)}
    text = report(columns)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(text)
    print(text)


if __name__ == "__main__":
    main()
