"""The raw-signal path against the simulator's truth: joint angles and landmarks, and the time.

For each motion and seed, ``simulate_trial`` (sensors misaligned by up to 15 deg and offset by up
to 2 cm, white noise and a constant gyro bias per sensor; see
:class:`pipeline.simulate.model.SensorNoise`) starts with 2 s still in the motion's rest pose
(standing; supine for ``supine_hip_flexion``, given as ``calibration_pose``) and runs 15 s of it.
Three inputs go through :func:`pipeline.process.process_recording` with its defaults:

* ``vqf`` / ``pi``: gyroscope, accelerometer and magnetometer (the quaternions removed),
  orientations by the attitude filter (VQF 9-D; PI is 6-D, it has no magnetometer input);
  ``--no-mag`` drops the magnetometer (VQF 6-D);
* ``orientations``: the simulated sensor orientations alone (what a vendor's fusion would give,
  without its raw signals): they cannot show the standing legs' lean (2-6 deg,
  :mod:`pipeline.process.posture` measures it from the accelerations), so hip and ankle flexion
  carry it.

Printed: RMS errors over the motion (after the standing phase) of the ISB joint angles
(flexion and the other two axes, hip, knee, ankle, both legs pooled) and of the landmarks, each
expressed in its own pelvis frame (what IMUs observe: no heading, no translation; leg landmarks
EFM, EFL, KJC, AJC, MM, LM and the foot's HEE, MT1, MT5, TOE apart), and the compute time of the
whole ``process_recording`` call (filtering included).

Two simulated worlds (issue 23: every estimator judged with and without what real data does):

* **ideal, hinge knee** (``--knee hinge``): a hinge about the population AoR, whose straight pose
  turns the tibia and foot by ~12 deg from the femur's frame; the standing calibration takes that
  pose as zero, so the knee's and ankle's other axes carry the turn unless ``--correction aor``
  (eq 9-12, the exact case for it) finds it and the foot follows
  (:func:`pipeline.calibration.correction.carried_correction`);
* **realistic, free knee** (``--knee free --realistic``): knee ab/adduction and rotation moving
  with flexion, the standing legs leaning, and :class:`pipeline.simulate.artefacts.Artefacts`
  (soft tissue, wandering biases, the floor's magnetic field).

``python scripts/bench_raw_path.py --all`` runs the standard set (both worlds, 9-D and 6-D, the
defaults and ``--correction aor``) and writes ``results/bench_raw_path.txt`` (~2 min); single
configurations print only: ``[--seeds 0 1 2] [--motions gait] [--no-mag] [--knee hinge|free]
[--realistic] [--correction none|aor|functional]``.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from pipeline.analysis.joint_angles import joint_angles
from pipeline.analysis.landmarks import frame_trajectories
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.process import process_recording
from pipeline.process.options import IKOptions
from pipeline.simulate.artefacts import Artefacts
from pipeline.simulate.model import simulate_trial

ROOT = Path(__file__).resolve().parents[1]

STANDING_S, MOTION_S = 2.0, 15.0
SUBJECT = Measures("m", 1.75)
NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}


def trial_and_inputs(motion: str, seed: int, *, mag: bool = True, knee: str = "hinge",
                     realistic: bool = False):
    geometry, _ = geometry_from_measures(SUBJECT)
    model = Skeleton.build(geometry, knee=knee, root="freeflyer")
    trial = simulate_trial(model, motion, duration_s=STANDING_S + MOTION_S, seed=seed,
                           standing_s=STANDING_S, artefacts=Artefacts() if realistic else None)
    raw, oriented = {}, {}
    for frame, imu in trial.imus.items():
        s = imu.recording.sensor
        raw[NAMES[frame]] = SensorSignals(gyr=s.gyr, acc=s.acc, mag=s.mag if mag else None)
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
            np.sum((a - b) ** 2, axis=1).tolist())
    res.update({k: 1e3 * float(np.sqrt(np.mean(v))) for k, v in sq.items()})
    return res


GROUPS = ("hip flexion", "hip other", "knee flexion", "knee other", "ankle flexion", "ankle other",
          "leg landmarks mm", "foot landmarks mm")
#: The standard set of --all: (title, options).
STANDARD = (
    ("ideal, hinge knee, 9-D, defaults", {}),
    ("ideal, hinge knee, 9-D, --correction aor", {"correction": "aor"}),
    ("ideal, hinge knee, 6-D, defaults", {"mag": False}),
    ("realistic, free knee, 9-D, defaults", {"knee": "free", "realistic": True}),
    ("realistic, free knee, 9-D, --correction aor", {"knee": "free", "realistic": True,
                                                    "correction": "aor"}),
    ("realistic, free knee, 6-D, defaults", {"knee": "free", "realistic": True, "mag": False}),
)


def table(seeds, motions, *, mag=True, knee="hinge", realistic=False, correction=None) -> str:
    """One configuration's table (Markdown)."""
    correction = correction or IKOptions().correction
    n0 = int(STANDING_S * 100)
    lines = ["| motion | seed | input | " + " | ".join(GROUPS) + " | s |",
             "|---|---|---|" + "---|" * (len(GROUPS) + 1)]
    for motion in motions:
        for seed in seeds:
            trial, raw, oriented = trial_and_inputs(motion, seed, mag=mag, knee=knee,
                                                    realistic=realistic)
            pose = {"supine_hip_flexion": "supine", "still_thigh": "seated"}.get(motion, "standing")
            for label, rec, kw in (("vqf", raw, {"filter": "vqf"}), ("pi", raw, {"filter": "pi"}),
                                   ("orientations", oriented,
                                    {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)})):
                t0 = time.perf_counter()
                run = process_recording(rec, SUBJECT, calibration_pose=pose,
                                        correction=correction, **kw)
                seconds = time.perf_counter() - t0
                e = errors(trial, run, n0)
                cells = " | ".join(f"{e.get(g, float('nan')):.2f}" for g in GROUPS)
                lines.append(f"| {motion} | {seed} | {label} | {cells} | {seconds:.2f} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--motions", nargs="+", default=["gait", "supine_hip_flexion"])
    ap.add_argument("--no-mag", action="store_true", help="gyroscope + accelerometer only (6-D)")
    ap.add_argument("--knee", choices=("hinge", "free"), default="hinge",
                    help="the simulated knee (the IK model's is the default free knee)")
    ap.add_argument("--realistic", action="store_true",
                    help="soft tissue, wandering biases, the floor's field (simulate/artefacts)")
    ap.add_argument("--correction", default=None, help="the knee correction (default: "
                    f"{IKOptions().correction}, as pipeline ik)")
    ap.add_argument("--all", action="store_true", help="the standard set, written to "
                    "results/bench_raw_path.txt")
    args = ap.parse_args()
    head = (f"raw path vs truth: {STANDING_S:g} s standing + {MOTION_S:g} s of motion at 100 Hz; "
            "RMS errors (deg; landmarks mm, pelvis frame); seconds of process_recording "
            "(the knees' joint-constraint calibration included)")
    if not args.all:
        print(head)
        print(table(args.seeds, args.motions, mag=not args.no_mag, knee=args.knee,
                    realistic=args.realistic, correction=args.correction))
        return
    parts = ["# The raw-signal path on the simulator: `python scripts/bench_raw_path.py --all`", "",
             head + ".", ""]
    for title, opts in STANDARD:
        print(title, flush=True)
        parts += [f"## {title}", "", table(args.seeds, args.motions, **opts)]
    (ROOT / "results" / "bench_raw_path.txt").write_text("\n".join(parts))
    print("\n".join(parts))


if __name__ == "__main__":
    main()
