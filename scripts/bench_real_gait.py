"""A real walk against optical truth: joint angles and joint centres of ``gaittoolbox_s02``.

The sample S02 of the public gait-tech/gaittoolbox (7 Xsens MTw sensors as MT Manager writes
them, raw signals and the vendor's orientations; Vicon truth; ``../shared/data/gaittoolbox_s02``,
read its README): 11 s standing, then walking in a 4 x 4 m room with a 180 deg turn. Each input
path goes through :func:`pipeline.process.process_recording` as ``pipeline ik`` runs it:

* ``vendor``: the vendor's orientations (and raw signals) as the files hold them;
* ``vqf9``: ``--filter vqf`` with the magnetometers (9-D where a sensor's field is trusted);
* ``vqf6`` / ``pi6``: VQF and Hu's PI filter without magnetometers (the ``Mag_`` columns dropped);

each with the default options and with each other option of the correction, the knee, the
standing posture and the heading alignment. Scored over samples 1120-2075 (the walk) against
``vicon/S02-Trial-Walk-1_vicon_ik.mot`` (and the marker-based ``_markers_ik.mot``): per
coordinate the RMSE, the offset-removed RMSE (offset = mean difference over the standing samples
200-1000), Pearson's r and the range of motion; the knee and ankle joint centres relative to the
hip centres' midpoint (mm), in each system's pelvis frame and in the pelvis's heading frame
(vertical and forward; the two systems' pelvis frames differ by their tilt at standing); and,
as the centres' limit, the same centres of the scaled model with its legs set to the optical
references' own joint angles (what the model's dimensions and frames leave, angles aside). Then
the recordings users bring (``scripts/real_gait_cuts.py``): S02 cut to start as the walk starts
or mid-walk, and with its other shank sensors, on every input path.

Written: ``results/bench_real_gait.txt`` and ``results/bench_real_gait.png`` (each sagittal
angle over the walk, ours against Vicon, per input path with the default options).

Usage: ``python scripts/bench_real_gait.py [--data ../shared/data/gaittoolbox_s02] [--quick]``
(``--quick``: the default options only).
"""

from __future__ import annotations

import argparse
import dataclasses
import functools
import time
from pathlib import Path

import numpy as np
from real_gait_cuts import section

from pipeline.analysis.joint_angles import joint_angles
from pipeline.analysis.landmarks import frame_trajectories, landmark_trajectories
from pipeline.io.formats import read_recording
from pipeline.io.mot import read_mot
from pipeline.model.measures import Measures
from pipeline.process import MOT_NAMES, mot_columns, process_recording
from pipeline.process.options import IKOptions

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data" / "gaittoolbox_s02"
SUBJECT = Measures("m", 1.72)  # the dataset's README: height from the Vicon segments
SENSOR_MAP = {"pelvis_imu": "00B40B91", "femur_l_imu": "00B40C45", "femur_r_imu": "00B40C3C",
              "tibia_l_imu": "00B40C44", "tibia_r_imu": "00B40C47", "calcn_l_imu": "00B40C55",
              "calcn_r_imu": "00B40C48"}
WALK, STANDING = slice(1120, 2075), slice(200, 1000)
SAGITTAL = ("hip_flexion_r", "hip_flexion_l", "knee_angle_r", "knee_angle_l", "ankle_angle_r",
            "ankle_angle_l")
FRONTAL = ("hip_adduction_r", "hip_adduction_l", "hip_rotation_r", "hip_rotation_l")
INPUTS = {"vendor": "the vendor's orientations", "vqf9": "VQF with magnetometers",
          "vqf6": "VQF without magnetometers", "pi6": "PI filter without magnetometers"}
#: The options varied, each value besides the default one at a time.
OPTIONS = (("correction", ("none", "aor", "functional")), ("knee", ("free", "hinge")),
           ("posture", ("measured", "neutral")), ("drift", ("auto", "joints", "none")))
#: Option sets: the defaults, then (label, changes) for each other value; last, the subject's
#: measured pelvis width (``--pelvis-width-m``, from the Vicon ASIS markers: asis_width).
VARIANTS = (("defaults", {}), *((f"{name} {v}", {name: v}) for name, values in OPTIONS
                                for v in values if v != getattr(IKOptions(), name)),
            ("pelvis width measured", {"pelvis_width_m": "measured"}))
#: Issue 23's targets (deg, mm): the median of the six sagittal RMSEs per input, each knee's and
#: ankle's RMSE, the hip ab/adduction's r, the knee and ankle centres' RMS error.
MEDIAN_TARGET = {"vendor": 3.5, "vqf9": 3.5, "vqf6": 4.0, "pi6": 4.0}
KNEE_TARGET, ANKLE_TARGET, ADDUCTION_R_TARGET = 3.5, 5.0, 0.8
KJC_TARGET_MM, AJC_TARGET_MM = 25.0, 35.0
#: Our model's segment frames -> the Vicon segments (every Vicon segment's z axis is anterior).
SEGMENTS = {"pelvis": "Root", "right_femur": "R_Femur", "left_femur": "L_Femur",
            "right_tibia": "R_Tibia", "left_tibia": "L_Tibia", "right_foot": "R_Foot",
            "left_foot": "L_Foot"}


def recording(data: Path, path: str):
    rec = read_recording(data / "imu", SENSOR_MAP)
    if path == "vendor":
        return rec, {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)}
    keep_mag = path == "vqf9"
    sensors = {n: s.replace(quat=None, mag=s.mag if keep_mag else None)
               for n, s in rec.sensors.items()}
    return rec.with_sensors(sensors), {"filter": "pi" if path == "pi6" else "vqf"}


def angle_scores(ours: np.ndarray, truth: np.ndarray) -> dict[str, float]:
    e = np.degrees(ours[WALK] - truth[WALK])
    offset = np.degrees(np.mean(ours[STANDING] - truth[STANDING]))
    return {"rmse": float(np.sqrt(np.mean(e**2))),
            "rmse_offset": float(np.sqrt(np.mean((e - offset) ** 2))),
            "rmse_walk_mean": float(np.sqrt(np.mean((e - np.mean(e)) ** 2))),
            "mean": float(np.mean(e)),
            "r": float(np.corrcoef(ours[WALK], truth[WALK])[0, 1]),
            "rom": float(np.degrees(np.ptp(ours[WALK]))),
            "rom_truth": float(np.degrees(np.ptp(truth[WALK])))}


@functools.cache
def vicon_mat(data: Path) -> dict:
    """The S02 Vicon export (markers, joint centres, segments), read once."""
    import scipy.io as sio

    return sio.loadmat(data / "vicon" / "S02-Trial-Walk-1.mat", squeeze_me=True,
                       struct_as_record=False)


def vicon_rotations(data: Path, segment: str) -> np.ndarray:
    """A Vicon segment's rotation (segment -> lab) per frame, (N, 3, 3)."""
    from scipy.spatial.transform import Rotation

    angles = np.radians(np.asarray(vicon_mat(data)[segment], float)[:, :3])
    return Rotation.from_rotvec(angles).as_matrix()


def vicon_centres(data: Path) -> dict[str, np.ndarray]:
    """Knee and ankle centres relative to the hip centres' midpoint, (N, 3) m, in the Vicon
    pelvis frame (OpenSim axes) and in its heading frame (forward, up, right)."""
    rows = np.genfromtxt(data / "vicon" / "S02-Trial-Walk-1_joint_centres_pelvis.csv",
                         delimiter=",", names=True)
    out = {}
    mid = 0.5 * np.stack([np.stack([rows[f"hjc_{s}_os_{a}"] for a in "xyz"], 1) for s in "rl"]
                         ).sum(0)
    for s in "rl":
        for j in ("kjc", "ajc"):
            out[f"pelvis {j}_{s}"] = np.stack([rows[f"{j}_{s}_os_{a}"] for a in "xyz"], 1) - mid
    m = vicon_mat(data)
    root = vicon_rotations(data, "Root")
    fwd = root[:, :, 2].copy()
    fwd[:, 2] = 0.0
    fwd /= np.linalg.norm(fwd, axis=1, keepdims=True)
    up = np.array([0.0, 0.0, 1.0])
    right = np.cross(fwd, up)
    hjc = 0.5 * (np.asarray(m["RHJC"], float) + np.asarray(m["LHJC"], float)) / 1000.0
    for s, S in (("r", "R"), ("l", "L")):
        for j, J in (("kjc", "KJC"), ("ajc", "AJC")):
            v = np.asarray(m[f"{S}{J}"], float) / 1000.0 - hjc
            out[f"heading {j}_{s}"] = np.stack([np.sum(v * fwd, 1), v @ up, np.sum(v * right, 1)],
                                               1)
    return out


def our_centres(run) -> dict[str, np.ndarray]:
    """As :func:`vicon_centres`, ours: the model's KJC and AJC landmarks."""
    return model_centres(run.skeleton, run.q, run.landmarks)


def model_centres(skeleton, Q: np.ndarray, lm: dict) -> dict[str, np.ndarray]:
    """:func:`our_centres` of any configurations ``Q`` of ``skeleton`` with its landmark
    trajectories ``lm`` (the hip centres' computed where ``lm`` lacks them)."""
    (R, p), = frame_trajectories(skeleton, Q, ["pelvis"]).values()
    mid = 0.5 * (lm["right_HJC"] + lm["left_HJC"]) if "right_HJC" in lm else None
    if mid is None:
        h = landmark_trajectories(skeleton, Q, ["right_HJC", "left_HJC"])
        mid = 0.5 * (h["right_HJC"] + h["left_HJC"])
    fwd = R[:, :, 0].copy()
    fwd[:, 1] = 0.0
    fwd /= np.linalg.norm(fwd, axis=1, keepdims=True)
    up = np.array([0.0, 1.0, 0.0])
    right = np.cross(fwd, up)
    out = {}
    for s, side in (("r", "right"), ("l", "left")):
        for j, J in (("kjc", "KJC"), ("ajc", "AJC")):
            v = lm[f"{side}_{J}"] - mid
            out[f"pelvis {j}_{s}"] = np.einsum("nji,nj->ni", R, v)
            out[f"heading {j}_{s}"] = np.stack([np.sum(v * fwd, 1), v @ up, np.sum(v * right, 1)],
                                               1)
    return out


def _elevation(anterior: np.ndarray, up: np.ndarray) -> np.ndarray:
    return np.degrees(np.arcsin(np.clip(anterior @ up, -1.0, 1.0)))


#: ISB axis (0 anterior, 2 the subject's right) -> the Vicon segment's column and sign (Vicon's
#: axes: x the subject's left, z anterior, for both legs).
VICON_AXIS = {0: (2, 1.0), 2: (0, -1.0)}


def our_inclinations(run, axis: int = 0) -> dict[str, np.ndarray]:
    """Each segment's sagittal inclination (deg): its anterior axis's elevation above the
    horizontal (positive: the segment's front up), free of the heading; ``axis=2``: its
    frontal roll, the elevation of its axis to the subject's right (the pelvis's obliquity)."""
    frames = frame_trajectories(run.skeleton, run.q, list(SEGMENTS))
    return {s: _elevation(R[:, :, axis], np.array([0.0, 1.0, 0.0]))
            for s, (R, _) in frames.items()}


def vicon_inclinations(data: Path, axis: int = 0) -> dict[str, np.ndarray]:
    """As :func:`our_inclinations`, of the Vicon segments (lab ``z`` up)."""
    column, sign = VICON_AXIS[axis]
    return {ours: _elevation(sign * vicon_rotations(data, seg)[:, :, column],
                             np.array([0.0, 0.0, 1.0])) for ours, seg in SEGMENTS.items()}


def inclination_errors(ours: np.ndarray, truth: np.ndarray) -> tuple[float, float, float]:
    """The standing offset, the walk's mean error beyond it, and the walk's RMSE with the
    standing offset removed (deg)."""
    e = ours - truth
    offset = float(np.nanmean(e[STANDING]))
    walk = e[WALK] - offset
    return offset, float(np.nanmean(walk)), float(np.sqrt(np.nanmean(walk**2)))


def vicon_lengths(data: Path) -> dict[str, float]:
    """Mean thigh (HJC-KJC) and shank (KJC-AJC) lengths per side and the hip centres' distance
    (m) of the Vicon model over the walk."""
    m = vicon_mat(data)
    c = {k: np.asarray(m[k], float)[WALK] / 1000.0 for k in
         ("RHJC", "RKJC", "RAJC", "LHJC", "LKJC", "LAJC")}
    return _lengths({f"{side}_{j}": c[f"{side[0].upper()}{j}"] for side in ("right", "left")
                     for j in ("HJC", "KJC", "AJC")})


def our_lengths(run) -> dict[str, float]:
    """As :func:`vicon_lengths`, of the scaled model."""
    names = [f"{side}_{j}" for side in ("right", "left") for j in ("HJC", "KJC", "AJC")]
    return _lengths(landmark_trajectories(run.skeleton, run.q[WALK], names))


def _lengths(p: dict) -> dict[str, float]:
    def dist(a, b):
        return float(np.nanmean(np.linalg.norm(p[a] - p[b], axis=1)))

    out = {"hip width": dist("right_HJC", "left_HJC")}
    for side in ("right", "left"):
        out[f"{side} thigh"] = dist(f"{side}_HJC", f"{side}_KJC")
        out[f"{side} shank"] = dist(f"{side}_KJC", f"{side}_AJC")
    return out


#: The model's leg joints (``q`` coordinates) -> the optical references' columns; the knee's
#: adduction and rotation and the ankle's inversion are not in the references (Vicon's knee is a
#: hinge): driven, they stay at zero.
DRIVEN = {"hip_Z": "hip_flexion", "hip_X": "hip_adduction", "hip_Y": "hip_rotation",
          "knee_Z": "knee_angle", "ankle_Z": "ankle_angle"}


def driven_centres(run, table) -> dict[str, np.ndarray]:
    """As :func:`our_centres`, pelvis frame only, of ``run``'s scaled model with its legs' joints
    set to an optical reference's angles (``table``, a read ``.mot``): what the model's
    dimensions and frames leave of the centres' error when the angles are the optical ones (the
    model's JCS angles are its ``q`` coordinates, Z-X-Y)."""
    sk = run.skeleton
    n = min(len(run.q), len(table.columns["hip_flexion_r"]))
    Q = run.q[:n].copy()
    for side, x in (("right", "r"), ("left", "l")):
        for joint in (j for g in ("hip", "knee", "ankle") for j in sk.leg_joints(side, g)):
            Q[:, sk.q_index(joint)] = 0.0
        for joint, column in DRIVEN.items():
            Q[:, sk.q_index(f"{side}_{joint}")] = table.columns[f"{column}_{x}"][:n]
    check = joint_angles(sk, Q[WALK])  # the JCS angles are the q coordinates, checked
    for side, x in (("right", "r"), ("left", "l")):
        for ours, theirs in MOT_NAMES.items():
            if f"{theirs}_{x}" in table.columns:
                gap = np.abs(check[f"{side}_{ours}"] - table.columns[f"{theirs}_{x}"][:n][WALK])
                assert np.nanmax(gap) < 1e-6, (side, ours, np.nanmax(gap))
    names = [f"{side}_{j}" for side in ("right", "left") for j in ("HJC", "KJC", "AJC")]
    centres = model_centres(sk, Q, landmark_trajectories(sk, Q, names))
    return {k: v for k, v in centres.items() if k.startswith("pelvis")}


def centre_offsets(ours: dict, truth: dict) -> dict[str, tuple[float, float]]:
    """Per centre, the walk's mean error's length and the RMS of the error about it (mm): the
    constant part (the model's dimensions and frame definitions) and the moving part."""
    out = {}
    for k in truth:
        e = ours[k][WALK] - truth[k][WALK]
        mean = np.nanmean(e, axis=0)
        out[k] = (float(1000 * np.linalg.norm(mean)),
                  float(1000 * np.sqrt(np.nanmean(np.sum((e - mean) ** 2, 1)))))
    return out


def centre_errors(ours: dict, truth: dict) -> dict[str, float]:
    return {k: float(1000 * np.sqrt(np.mean(np.sum((ours[k][WALK] - truth[k][WALK]) ** 2, 1))))
            for k in truth if k in ours}


def asis_width(data: Path) -> float:
    """The distance (m) between the Vicon ASIS markers, median over the standing samples: what a
    lab measures for ``--pelvis-width-m``."""
    d = vicon_mat(data)
    left, right = (np.asarray(d[m], float)[STANDING, :3] for m in ("LASI", "RASI"))
    return float(np.nanmedian(np.linalg.norm(left - right, axis=1))) / 1000.0


def run_one(data: Path, path: str, changes: dict, refs: dict):
    rec, base = recording(data, path)
    subject, changes = SUBJECT, dict(changes)
    if changes.pop("pelvis_width_m", None):
        subject = dataclasses.replace(SUBJECT, pelvis_width_m=asis_width(data))
    t0 = time.perf_counter()
    run = process_recording(rec, subject, **base, **changes)
    seconds = time.perf_counter() - t0
    cols = mot_columns(run)
    scores = {ref: {c: angle_scores(cols[c], table.columns[c]) for c in SAGITTAL + FRONTAL}
              for ref, table in refs["angles"].items()}
    return run, cols, scores, centre_errors(our_centres(run), refs["centres"]), seconds


def figure(curves: dict, truth, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(SAGITTAL), 1, figsize=(12, 15), sharex=True)
    t = truth.time
    for ax, c in zip(axes, SAGITTAL, strict=True):
        ax.plot(t, np.degrees(truth.columns[c]), color="k", lw=2, label="Vicon")
        for label, cols in curves.items():
            ax.plot(t, np.degrees(cols[c]), lw=1, label=label)
        ax.set_ylabel(f"{c} (deg)")
        ax.axvspan(t[WALK.start], t[WALK.stop - 1], color="0.93", zorder=0)
        ax.grid(alpha=0.3)
    axes[0].legend(ncol=5, fontsize=8, loc="upper left")
    axes[-1].set_xlabel("time (s); shaded: the scored walk")
    fig.tight_layout()
    fig.savefig(path, dpi=90)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--data", type=Path, default=DATA)
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=ROOT / "results")
    args = ap.parse_args()
    vicon = read_mot(args.data / "vicon" / "S02-Trial-Walk-1_vicon_ik.mot")
    markers = read_mot(args.data / "vicon" / "S02-Trial-Walk-1_markers_ik.mot")
    refs = {"angles": {"vicon": vicon, "markers": markers}, "centres": vicon_centres(args.data),
            "lengths": vicon_lengths(args.data), "inclinations": vicon_inclinations(args.data),
            "rolls": vicon_inclinations(args.data, axis=2)}
    variants = VARIANTS[:1] if args.quick else VARIANTS
    rows, curves = [], {}
    for path in INPUTS:
        for label, changes in variants:
            run, cols, scores, centres, seconds = run_one(args.data, path, changes, refs)
            rows.append((path, label, scores, centres, seconds, run))
            if label == "defaults":
                curves[path] = cols
            med = np.median([scores["vicon"][c]["rmse"] for c in SAGITTAL])
            print(f"{path:7s} {label:22s} median sagittal RMSE {med:.1f} deg ({seconds:.1f} s)",
                  flush=True)
    text = report(rows) + section(args.data, SENSOR_MAP, SUBJECT, INPUTS, SAGITTAL,
                                  refs["angles"]) + limits(rows, refs)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench_real_gait.txt").write_text(text)
    figure(curves, vicon, args.out / "bench_real_gait.png")
    print(text)


def _short(c: str) -> str:
    return c.replace("_angle", "").replace("_flexion", "").replace("_adduction", " add").replace(
        "_rotation", " rot").replace("_r", " r").replace("_l", " l")


def report(rows) -> str:
    lines = ["# S02 real walk against Vicon (gaittoolbox_s02): `python scripts/bench_real_gait.py`",
             "", "Joint angles over samples 1120-2075 (the walk). Per coordinate: RMSE / RMSE with "
             "the standing offset removed / Pearson r (deg). Sagittal against "
             "`_vicon_ik.mot`; `median` is the median of the six sagittal RMSEs.", "",
             "| input | options | " + " | ".join(_short(c) for c in SAGITTAL) + " | median |",
             "|---|---|" + "---|" * (len(SAGITTAL) + 1)]
    for path, label, scores, _, _, _ in rows:
        s = scores["vicon"]
        cells = [f"{s[c]['rmse']:.1f} / {s[c]['rmse_offset']:.1f} / {s[c]['r']:.2f}"
                 for c in SAGITTAL]
        med = np.median([s[c]["rmse"] for c in SAGITTAL])
        lines.append(f"| {path} | {label} | " + " | ".join(cells) + f" | **{med:.1f}** |")
    lines += ["", "Range of motion over the walk (deg), defaults, ours / Vicon:", "",
              "| input | " + " | ".join(_short(c) for c in SAGITTAL) + " |",
              "|---|" + "---|" * len(SAGITTAL)]
    for path, label, scores, _, _, _ in rows:
        if label == "defaults":
            s = scores["vicon"]
            lines.append(f"| {path} | " + " | ".join(
                f"{s[c]['rom']:.0f} / {s[c]['rom_truth']:.0f}" for c in SAGITTAL) + " |")
    lines += ["", "Hip ab/adduction and rotation, defaults: RMSE / offset-removed / r against each "
              "optical reference (the two optical methods disagree most here: the marker-based "
              "fit and the Vicon segments' rotation about the femur):", "",
              "| input | reference | " + " | ".join(_short(c) for c in FRONTAL) + " |",
              "|---|---|" + "---|" * len(FRONTAL)]
    for path, label, scores, _, _, _ in rows:
        if label != "defaults":
            continue
        for ref in ("vicon", "markers"):
            s = scores[ref]
            lines.append(f"| {path} | {ref} | " + " | ".join(
                f"{s[c]['rmse']:.1f} / {s[c]['rmse_offset']:.1f} / {s[c]['r']:.2f}"
                for c in FRONTAL) + " |")
    lines += ["", "Sagittal against the marker-based reference (`_markers_ik.mot`), defaults:", "",
              "| input | " + " | ".join(_short(c) for c in SAGITTAL) + " | median |",
              "|---|" + "---|" * (len(SAGITTAL) + 1)]
    for path, label, scores, _, _, _ in rows:
        if label == "defaults":
            s = scores["markers"]
            med = np.median([s[c]["rmse"] for c in SAGITTAL])
            lines.append(f"| {path} | " + " | ".join(
                f"{s[c]['rmse']:.1f} / {s[c]['rmse_offset']:.1f} / {s[c]['r']:.2f}"
                for c in SAGITTAL) + f" | {med:.1f} |")
    keys = ["pelvis kjc_r", "pelvis kjc_l", "pelvis ajc_r", "pelvis ajc_l", "heading kjc_r",
            "heading kjc_l", "heading ajc_r", "heading ajc_l"]
    lines += ["", "Knee and ankle centres relative to the hip centres' midpoint, RMS 3-D error "
              "(mm) over the walk: in each system's pelvis frame, and in the pelvis's heading "
              "frame (the vertical and the pelvis's forward direction: free of the two pelvis "
              "frames' different tilt):", "",
              "| input | options | " + " | ".join(keys) + " | seconds |",
              "|---|---|" + "---|" * (len(keys) + 1)]
    for path, label, _, centres, seconds, _ in rows:
        lines.append(f"| {path} | {label} | " + " | ".join(f"{centres[k]:.0f}" for k in keys)
                     + f" | {seconds:.1f} |")
    lines += ["", "What each default run did (its notes on headings, magnetometers, posture):", ""]
    for path, label, _, _, _, run in rows:
        if label != "defaults":
            continue
        lines.append(f"- **{path}**:")
        for n in run.notes:
            if any(w in n for w in ("magnetometer", "heading", "standing", "orientations est")):
                lines.append(f"  - {n}")
    return "\n".join(lines) + "\n"


def _met(value: float, target: float, higher: bool = False) -> str:
    ok = value >= target if higher else value <= target
    return f"{value:.2f}" + (" ok" if ok else " **no**") if higher else \
        f"{value:.1f}" + (" ok" if ok else " **no**")


def limits(rows, refs) -> str:
    """The targets of issue 23 per input with the defaults, then what limits them, measured."""
    lines = ["", "## Targets (defaults)", "",
             "| input | median (target) | knee r | knee l | ankle r | ankle l | hip add r: r vs "
             "Vicon / markers | KJC r / l (mm) | AJC r / l (mm) |", "|---|" + "---|" * 8]
    defaults = [r for r in rows if r[1] == "defaults"]
    for path, _, scores, centres, _, _ in defaults:
        v, m = scores["vicon"], scores["markers"]
        med = np.median([v[c]["rmse"] for c in SAGITTAL])
        add = [f"{v[f'hip_adduction_{x}']['r']:.2f} / {m[f'hip_adduction_{x}']['r']:.2f}"
               + (" ok" if max(v[f"hip_adduction_{x}"]["r"], m[f"hip_adduction_{x}"]["r"])
                  >= ADDUCTION_R_TARGET else " **no**") for x in "rl"]
        lines.append(
            f"| {path} | {_met(med, MEDIAN_TARGET[path])} ({MEDIAN_TARGET[path]:g}) | "
            + " | ".join(_met(v[c]["rmse"], KNEE_TARGET if "knee" in c else ANKLE_TARGET)
                         for c in SAGITTAL[2:]) + f" | {'; '.join(add)} | "
            + " / ".join(_met(centres[f"pelvis kjc_{x}"], KJC_TARGET_MM) for x in "rl") + " | "
            + " / ".join(_met(centres[f"pelvis ajc_{x}"], AJC_TARGET_MM) for x in "rl") + " |")
    lines += ["", "## What limits them (measured)", "",
              "**The optical floor**: the two optical references against each other over the "
              "walk (markers' IK as 'ours', Vicon's segments as truth): RMSE / offset-removed / r "
              "(deg). A difference from Vicon smaller than this cannot be told from the "
              "references' own disagreement.", "",
              "| " + " | ".join(_short(c) for c in SAGITTAL + FRONTAL) + " |",
              "|" + "---|" * len(SAGITTAL + FRONTAL)]
    vic, mar = refs["angles"]["vicon"], refs["angles"]["markers"]
    floor = {c: angle_scores(mar.columns[c], vic.columns[c]) for c in SAGITTAL + FRONTAL}
    lines.append("| " + " | ".join(f"{floor[c]['rmse']:.1f} / {floor[c]['rmse_offset']:.1f} / "
                                   f"{floor[c]['r']:.2f}" for c in SAGITTAL + FRONTAL) + " |")
    lines += ["", "**Constant offsets**: the six sagittal RMSEs' median as scored, with the "
              "standing offset removed (the difference is what the standing calibration's "
              "definition of zero contributes: the pelvis's tilt, the ankle's neutral) and with "
              "the walk's own mean error removed (what no constant offset explains: a perfect "
              "calibration of every joint's zero for the walk would leave this; between the two, "
              "what changes from standing to walking: the sensors or the markers shifting on the "
              "skin, the two models' joint definitions as the joints flex), per input (defaults), "
              "and the same of the two optical references:", "",
              "| input | as scored | standing offset removed | walk's mean removed |",
              "|---|---|---|---|"]
    for path, scores in [(p, sc["vicon"]) for p, _, sc, _, _, _ in defaults] + [
            ("optical floor", floor)]:
        lines.append(f"| {path} | " + " | ".join(
            f"{np.median([scores[c][key] for c in SAGITTAL]):.1f}"
            for key in ("rmse", "rmse_offset", "rmse_walk_mean")) + " |")
    lines += ["", "Each sagittal angle's mean error over the walk (deg, ours less the reference; "
              "defaults) against Vicon / the markers, and the markers' against Vicon. The "
              "references' ankle zero comes from their foot segments' frames (built on markers "
              "on the heel and toes), ours from the sole flat on the floor with the tibia "
              "upright: the ankles' offsets are partly a matter of definition.", "",
              "| input | " + " | ".join(_short(c) for c in SAGITTAL) + " |",
              "|---|" + "---|" * len(SAGITTAL)]
    for path, _, sc, _, _, _ in defaults:
        lines.append(f"| {path} | " + " | ".join(
            f"{sc['vicon'][c]['mean']:+.1f} / {sc['markers'][c]['mean']:+.1f}"
            for c in SAGITTAL) + " |")
    lines.append("| markers | " + " | ".join(f"{floor[c]['mean']:+.1f}" for c in SAGITTAL) + " |")
    lines += ["", "**Segments**: each segment's sagittal inclination (its anterior axis's "
              "elevation, free of the heading) against the Vicon segment's: standing offset / "
              "the walk's mean error beyond it / the walk's RMSE with the standing offset "
              "removed (deg), defaults. A joint's sagittal error is the difference of its two "
              "segments' (hip = femur - pelvis, knee = femur - tibia, ankle = foot - tibia); a "
              "segment whose error changes between standing and walking on every input moves "
              "against Vicon's markers (the sensor on the skin, or the markers), which no "
              "filter removes.", "",
              "| segment | " + " | ".join(p for p, *_ in defaults) + " |",
              "|---|" + "---|" * len(defaults)]
    incl = {p: our_inclinations(run) for p, _, _, _, _, run in defaults}
    for seg, truth in refs["inclinations"].items():
        lines.append(f"| {seg} | " + " | ".join(
            "{:+.1f} / {:+.1f} / {:.1f}".format(*inclination_errors(incl[p][seg], truth))
            for p in incl) + " |")
    lines += ["", "**Frontal plane** (the hip ab/adduction's r target): each segment's frontal "
              "roll (its lateral axis's elevation, free of the heading; the pelvis's obliquity) "
              "against the Vicon segment's over the walk: Pearson r and range, ours / Vicon "
              "(deg), defaults. Hip ab/adduction is the femur's roll less the pelvis's (near "
              "the standing pose); a segment that correlates weakly on every input disagrees "
              "with the markers in the frontal plane whatever the filter. The roll also takes in "
              "a segment's axial rotation as it flexes, and Vicon's femur and tibia share their "
              "lateral axis (its knee is a hinge): the pelvis's row is the cleanest.", "",
              "| segment | " + " | ".join(p for p, *_ in defaults) + " |",
              "|---|" + "---|" * len(defaults)]
    rolls = {p: our_inclinations(run, axis=2) for p, _, _, _, _, run in defaults}
    for seg in ("pelvis", "right_femur", "left_femur", "right_tibia", "left_tibia"):
        truth = refs["rolls"][seg][WALK]
        lines.append(f"| {seg} | " + " | ".join(
            f"{np.corrcoef(rolls[p][seg][WALK], truth)[0, 1]:.2f}, "
            f"{np.ptp(rolls[p][seg][WALK]):.1f} / {np.ptp(truth):.1f}" for p in rolls) + " |")
    lines += ["", "**Joint centres**: the walk's mean error (length, mm) and the RMS about it, "
              "pelvis frame, defaults; then the dimensions (m) of the scaled model (from height "
              "and sex, no measurement of this subject) against Vicon's:", "",
              "| input | " + " | ".join(f"{j}_{x}" for j in ("kjc", "ajc") for x in "rl") + " |",
              "|---|" + "---|" * 4]
    for path, _, _, _, _, run in defaults:
        off = centre_offsets(our_centres(run), refs["centres"])
        lines.append(f"| {path} | " + " | ".join(
            f"{off[f'pelvis {j}_{x}'][0]:.0f} + {off[f'pelvis {j}_{x}'][1]:.0f}"
            for j in ("kjc", "ajc") for x in "rl") + " |")
    lines += ["", "The same centres (RMS 3-D error, pelvis frame, mm) of the scaled model with its "
              "legs' joints set to each optical reference's angles (the knee a hinge, as Vicon's): "
              "what the model's dimensions and frames leave when the angles are the optical ones, "
              "with the template's hip width (defaults) and with the measured one:", "",
              "| model | angles | kjc_r | kjc_l | ajc_r | ajc_l |", "|---|---|---|---|---|---|"]
    for label, run in ((r[1], r[5]) for r in rows if r[0] == "vendor"
                       and r[1] in ("defaults", "pelvis width measured")):
        for ref, table in refs["angles"].items():
            err = centre_errors(driven_centres(run, table), refs["centres"])
            lines.append(f"| {label} | {ref} | " + " | ".join(
                f"{err[f'pelvis {j}_{x}']:.0f}" for j in ("kjc", "ajc") for x in "rl") + " |")
    side = {k: abs(float(np.nanmean(v[STANDING, 2]))) for k, v in refs["centres"].items()
            if k.startswith("heading")}
    lines += ["", "The same centres' mean error over the walk in the pelvis's heading frame, "
              "forward / up / right (mm), defaults. The lateral part is the stance's width: "
              "standing, Vicon puts the hip centres {:.0f} mm, the knees {:.0f} / {:.0f} mm and "
              "the ankles {:.0f} / {:.0f} mm (right / left) from their midpoint; the model's "
              "standing pose has the knees and ankles below the hips.".format(
                  500 * refs["lengths"]["hip width"], *(1000 * side[f"heading {j}_{x}"]
                                                        for j in ("kjc", "ajc") for x in "rl")),
              "", "| input | " + " | ".join(f"{j}_{x}" for j in ("kjc", "ajc") for x in "rl")
              + " |", "|---|" + "---|" * 4]
    for path, _, _, _, _, run in defaults:
        ours = our_centres(run)
        cells = []
        for j in ("kjc", "ajc"):
            for x in "rl":
                k = f"heading {j}_{x}"
                mean = 1000 * np.nanmean(ours[k][WALK] - refs["centres"][k][WALK], axis=0)
                cells.append(" / ".join(f"{v:+.0f}" for v in mean))
        lines.append(f"| {path} | " + " | ".join(cells) + " |")
    ours = our_lengths(defaults[0][5])
    lines += ["", "| dimension | scaled model | Vicon |", "|---|---|---|"]
    lines += [f"| {k} | {ours[k]:.3f} | {refs['lengths'][k]:.3f} |" for k in refs["lengths"]]
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    main()
