"""Which options are the defaults: each candidate measured on real walks and on the simulator.

For each option of ``pipeline ik`` that changes the result of a walk (the knee-AoR correction,
the knee model, the standing posture, the heading alignment, the attitude filter of raw signals),
the default and each alternative, one at a time, on three sources of evidence:

* **S02** (``../shared/data/gaittoolbox_s02``, a real walk with Vicon truth; as
  ``scripts/bench_real_gait.py``): the median of the six sagittal angles' RMSE over the walk,
  against Vicon's segments (``_vicon_ik.mot``) and against the marker-based reference
  (``_markers_ik.mot``), over the four inputs (vendor orientations, VQF 9-D, VQF 6-D, PI 6-D);
* **simulator** (``pipeline.simulate``: gait with a standing start, free knee, the real world's
  artefacts of :class:`pipeline.simulate.artefacts.Artefacts`: soft tissue, wandering bias, the
  floor's field; three seeds; and the ideal simulator without them): the median over the seeds
  and inputs (the sensors' orientations, VQF 9-D, VQF 6-D) of the median sagittal RMSE against
  the truth, and of the other axes' (ab/adduction, rotation); and the same for the realistic
  ``walk`` motion with the artefacts (its gait events, pelvis list and turns as a walk has them,
  where the sinusoidal gait's thighs swing about lines 31 deg apart; a free ankle, its tibia
  turning on the planted foot: :mod:`pipeline.simulate.subtalar`);
* **OpenSense's walking file** (``../shared/data/opensim/xsens_walking_orientations.sto``,
  orientations only: the posture and the heading alignment need raw signals and do not apply):
  the median RMS difference of hip and knee angles from OpenSense's own result (run here, with
  the pelvis axis nearest our anatomical heading, ``+z``, like for like; skipped without
  ``opensim``).

Each option's rank (1 = best) per score, options equal as printed (two decimals) sharing their
mean rank; the default should have the best mean rank. The filter
applies to raw signals only: its rows are scored over the raw inputs (S02's 9-D and 6-D signals,
the simulator's VQF 9-D and 6-D inputs), each filter named. Then, per knee and input, how far
apart the AoR corrections (eq 9-12) of the two halves of the walk are, against
:data:`pipeline.process.knee_correction.MAX_SPREAD_DEG` (the support test of ``--correction aor``).
Written: ``results/bench_defaults.txt``.

Usage: ``python scripts/bench_defaults.py`` (~5 min; run alone).
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import bench_real_gait as real  # noqa: E402

from pipeline.analysis.joint_angles import joint_angles  # noqa: E402
from pipeline.calibration.conventions import DEFAULT_FILTER  # noqa: E402
from pipeline.io.recording import Recording, SensorSignals  # noqa: E402
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT  # noqa: E402
from pipeline.model.measures import Measures  # noqa: E402
from pipeline.model.scaling import geometry_from_measures  # noqa: E402
from pipeline.model.skeleton import Skeleton  # noqa: E402
from pipeline.process import mot_columns, process_recording  # noqa: E402
from pipeline.process.knee_correction import MAX_SPREAD_DEG  # noqa: E402
from pipeline.process.options import IKOptions  # noqa: E402
from pipeline.simulate.artefacts import Artefacts  # noqa: E402
from pipeline.simulate.model import simulate_trial  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
OPENSIM_WALK = ROOT.parent / "shared" / "data" / "opensim" / "xsens_walking_orientations.sto"
SIM_SUBJECT = Measures("m", 1.75)
SEEDS = (0, 1, 2)
NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}
SAGITTAL = ("hip_flexion", "knee_flexion", "ankle_flexion")
#: (factor, option name, candidates); the default is IKOptions()'s value.
FACTORS = (("correction", ("none", "aor", "functional")), ("knee", ("free", "hinge")),
           ("posture", ("measured", "neutral")), ("drift", ("auto", "joints")),
           ("filter", ("vqf", "pi")))


def default_of(name: str):
    """The option's default; the filter's is the one used where a recording has no orientations."""
    return DEFAULT_FILTER if name == "filter" else getattr(IKOptions(), name)


def candidates() -> list[tuple[str, dict]]:
    """``(label, changes)``: the defaults, then each other value of each factor (each filter
    named: its rows are scored over raw inputs only)."""
    out = [("defaults", {})]
    for name, values in FACTORS:
        out += [(f"{name} {v}", {name: v}) for v in values
                if v != default_of(name) or name == "filter"]
    return out


def applies(changes: dict, base: dict) -> bool:
    """Whether an input is scored for ``changes``: a filter only for raw signals."""
    return "filter" not in changes or "filter" in base


def label_of(name: str, value) -> str:
    return f"{name} {value}" if value != default_of(name) or name == "filter" else "defaults"


#: (source, knee, the halves' corrections apart in deg or None) of the ``correction aor`` runs.
HALVES: list[tuple[str, str, float | None]] = []


def note_halves(source: str, changes: dict, run) -> None:
    if changes.get("correction") == "aor":
        for side, c in run.corrections.items():
            HALVES.append((source, side, None if c.halves_apart is None
                           else float(np.degrees(c.halves_apart))))


# ---- simulator ---------------------------------------------------------------------------------
def sim_inputs(seed: int, artefacts: Artefacts | None, motion: str = "gait"):
    geometry, _ = geometry_from_measures(SIM_SUBJECT)
    sk = Skeleton.build(geometry, knee="free", root="freeflyer",
                        ankle="free" if motion == "walk" else "universal")
    trial = simulate_trial(sk, motion, duration_s=20.0, seed=seed, standing_s=3.0,
                           artefacts=artefacts)

    def rec(**keep):
        return Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(**{
            k: getattr(i.recording, k) for k, on in keep.items() if on})
            for f, i in trial.imus.items()})

    return trial, {
        "orientations": (rec(quat=1, gyr=1, acc=1, mag=1), {"sensor_to_model": (-np.pi / 2, 0, 0)}),
        "vqf9": (rec(gyr=1, acc=1, mag=1), {"filter": "vqf"}),
        "vqf6": (rec(gyr=1, acc=1), {"filter": "vqf"}),
    }


def sim_scores(changes: dict, sims, kind: str) -> tuple[float, float]:
    sag, other = [], []
    for seed, (trial, inputs) in enumerate(sims):
        truth = joint_angles(trial.skeleton, trial.q)
        for name, (rec, base) in inputs.items():
            if not applies(changes, base):
                continue
            run = process_recording(rec, SIM_SUBJECT, **{**base, **changes})
            note_halves(f"sim {kind} seed {seed} {name}", changes, run)
            s, o = median_errors(run, truth, 400)
            sag.append(s)
            other.append(o)
    return float(np.median(sag)), float(np.median(other))


def median_errors(run, truth: dict, start: int, skip: tuple[str, ...] = ()) -> tuple[float, float]:
    """The median RMSE (deg) against the simulator's truth from sample ``start`` on, over the
    sagittal angles and over the other axes (joints whose name starts with ``skip`` left out)."""
    rms = {k: float(np.sqrt(np.mean(np.degrees(run.joint_angles[k] - truth[k])[start:] ** 2)))
           for k in run.joint_angles if k in truth and not k.startswith(skip)}
    return (float(np.median([v for k, v in rms.items() if k.endswith(SAGITTAL)])),
            float(np.median([v for k, v in rms.items() if not k.endswith(SAGITTAL)])))


# ---- S02 ---------------------------------------------------------------------------------------
def s02_scores(changes: dict) -> tuple[float, float]:
    vicon = real.read_mot(real.DATA / "vicon" / "S02-Trial-Walk-1_vicon_ik.mot")
    markers = real.read_mot(real.DATA / "vicon" / "S02-Trial-Walk-1_markers_ik.mot")
    meds = {"vicon": [], "markers": []}
    for path in real.INPUTS:
        rec, base = real.recording(real.DATA, path)
        if not applies(changes, base):
            continue
        run = process_recording(rec, real.SUBJECT, **{**base, **changes})
        note_halves(f"S02 {path}", changes, run)
        cols = mot_columns(run)
        for ref, table in (("vicon", vicon), ("markers", markers)):
            meds[ref].append(np.median([real.angle_scores(cols[c], table.columns[c])["rmse"]
                                        for c in real.SAGITTAL]))
    return float(np.median(meds["vicon"])), float(np.median(meds["markers"]))


# ---- OpenSense ---------------------------------------------------------------------------------
def opensense_reference(work: Path):
    """OpenSense's result on the walking file, run in a child process (opensim and casadi ship
    CasADi libraries that clash in one process); None without opensim or the file."""
    import subprocess

    out = work / "opensense.npz"
    done = subprocess.run([sys.executable, __file__, "--opensense", str(out)],
                          capture_output=True, text=True)
    if done.returncode != 0 or not out.exists():
        return None
    z = np.load(out)
    return {"time": z["time"], "columns": {k[4:]: z[k] for k in z.files if k.startswith("col_")}}


def _opensense_child(out: Path) -> int:
    try:
        import opensim as osim
    except ImportError:
        return 1
    if not OPENSIM_WALK.exists():
        return 1
    import bench_opensense as bo

    geometry, _ = geometry_from_measures(Measures(bo.SEX, bo.HEIGHT_M))
    model = bo.build_opensim_model(osim, geometry)
    res = bo.run_opensense(osim, model, OPENSIM_WALK, (-np.pi / 2, 0.0, 0.0), out.parent, "z")
    np.savez(out, time=res["time"], **{f"col_{k}": v for k, v in res["columns"].items()})
    return 0


def opensense_score(changes: dict, ref) -> float:
    import bench_opensense as bo

    from pipeline.io.opensim import read_orientations_sto

    if ref is None or any(k in changes for k in ("posture", "drift", "filter")):
        return float("nan")
    trial = read_orientations_sto(OPENSIM_WALK)
    run = process_recording(trial, Measures(bo.SEX, bo.HEIGHT_M),
                            sensor_to_model=(-np.pi / 2, 0.0, 0.0), **changes)
    note_halves("OpenSense walk", changes, run)
    ours = {"time": run.time, "columns": mot_columns(run)}
    diffs = [bo.agreement(ref, ours, f"{c}_{s}")[0] for c in bo.COMPARED for s in "rl"]
    return float(np.nanmedian(diffs))


def main() -> None:
    cands = candidates()
    sims_real = [sim_inputs(s, Artefacts()) for s in SEEDS]
    sims_ideal = [sim_inputs(s, None) for s in SEEDS]
    sims_walk = [sim_inputs(s, Artefacts(), "walk") for s in SEEDS]
    with tempfile.TemporaryDirectory() as tmp:
        os_ref = opensense_reference(Path(tmp))
        rows = []
        for label, changes in cands:
            sv, sm = s02_scores(changes)
            rs, ro = sim_scores(changes, sims_real, "real")
            is_, io = sim_scores(changes, sims_ideal, "ideal")
            ws, wo = sim_scores(changes, sims_walk, "walk")
            osd = opensense_score(changes, os_ref)
            rows.append((label, [sv, sm, rs, ro, is_, io, ws, wo, osd]))
            print(f"{label:24s} " + " ".join(f"{x:5.2f}" for x in rows[-1][1]), flush=True)
    text = report(rows, os_ref is not None)
    (ROOT / "results" / "bench_defaults.txt").write_text(text)
    print(text)


SCORES = ("S02 vs Vicon", "S02 vs markers", "sim real: sagittal", "sim real: other axes",
          "sim ideal: sagittal", "sim ideal: other axes", "sim walk: sagittal",
          "sim walk: other axes", "OpenSense walk: vs OpenSense")


def report(rows, with_opensense: bool) -> str:
    d = IKOptions()
    filt = f"filter {DEFAULT_FILTER} (raw signals)"
    lines = ["# Defaults by evidence: `python scripts/bench_defaults.py`", "",
             "Median RMSE (deg): S02 the six sagittal angles' median, median over its four "
             "inputs; simulator (3 seeds, free knee) over the sensors' orientations, VQF 9-D and "
             "6-D, realistic (soft tissue, wandering bias, the floor's field) and ideal, on the "
             "sinusoidal gait; and the realistic walk (`sim walk`: the walk motion, its pelvis "
             "listing, a free ankle, with the same artefacts); "
             "OpenSense's walking file the median RMS difference of hip and knee angles from "
             "OpenSense's own result (orientations only: posture and drift do not apply).", "",
             f"Defaults: correction {d.correction}, knee {d.knee}, posture {d.posture}, "
             f"drift {d.drift}, {filt}.", "",
             "| options | " + " | ".join(SCORES) + " |",
             "|---|" + "---|" * len(SCORES)]
    for label, vals in rows:
        lines.append(f"| {label} | " + " | ".join("-" if np.isnan(v) else f"{v:.2f}"
                                                  for v in vals) + " |")
    lines += ["", "Per factor, each value's mean rank over the scores that apply (1 = best):", ""]
    by = dict(rows)
    for name, values in FACTORS:
        labels = {v: label_of(name, v) for v in values}
        ranks = {v: [] for v in values}
        for k in range(len(SCORES)):
            col = {v: by[labels[v]][k] for v in values}
            if any(np.isnan(x) for x in col.values()):
                continue
            shown = {v: round(col[v], 2) for v in values}  # equal as printed: one (mean) rank
            for v in values:
                below = sum(shown[u] < shown[v] for u in values)
                ties = sum(shown[u] == shown[v] for u in values)
                ranks[v].append(below + (ties + 1) / 2)
        mean = {v: float(np.mean(r)) for v, r in ranks.items()}
        best = min(mean, key=mean.get)
        lines.append(f"- {name}: " + ", ".join(f"{v} {mean[v]:.2f}" for v in values)
                     + f" -> best {best}" + (" (the default)" if best == default_of(name)
                                             else f" (default {default_of(name)})"))
    if not with_opensense:
        lines.append("- (opensim not installed: the OpenSense column is empty)")
    lines += ["", "The support test of `--correction aor`: per knee, the angle (deg) between the "
              "AoR corrections (eq 9-12) of the two halves of the walk; applied only within "
              f"{MAX_SPREAD_DEG:g} deg ('-': a half moves too little):", "",
              "| input | right | left |", "|---|---|---|"]
    by_source: dict[str, dict[str, float | None]] = {}
    for source, side, apart in HALVES:
        by_source.setdefault(source, {})[side] = apart
    for source, sides in by_source.items():
        cells = ["-" if sides.get(k) is None else f"{sides[k]:.1f}" for k in ("right", "left")]
        lines.append(f"| {source} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if sys.argv[1:2] == ["--opensense"]:
        raise SystemExit(_opensense_child(Path(sys.argv[2])))
    main()
