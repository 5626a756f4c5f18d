"""The real walk S02 as users bring it, against Vicon: as recorded, cut to start as the walk starts
(sample 1120) or mid-walk (1300, 1500), and with its other shank sensors (``imu_other_shanks/``:
a second sensor strapped elsewhere on each shank), on every input path of
``scripts/bench_real_gait.py``, with the default options. A section of that benchmark's report
(:func:`section`); the recordings here are what its tests cut too.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import numpy as np

from pipeline.io.formats import read_recording
from pipeline.io.recording import Recording
from pipeline.process import mot_columns, process_recording

__all__ = ["CUTS", "OTHER_SHANKS", "other_shanks", "section"]

#: Where each cut starts (samples): the recording as recorded, as the walk starts, mid-walk.
CUTS = (0, 1120, 1300, 1500)
#: The other shank sensors' ids (the dataset's README).
OTHER_SHANKS = {"tibia_l_imu": "00B40BA5", "tibia_r_imu": "00B40C35"}
#: The walk scored (samples), as bench_real_gait.WALK.
WALK = (1120, 2075)


def other_shanks(data: Path, sensor_map: dict[str, str]) -> Recording:
    """S02 with ``imu_other_shanks/`` in place of the two shank files (a folder of links, read
    as users would put the files together)."""
    folder = Path(tempfile.mkdtemp(prefix="s02_other_shanks_"))
    replaced = {sensor_map[n] for n in OTHER_SHANKS}
    for f in (data / "imu").iterdir():
        if not any(i in f.name for i in replaced):
            os.symlink(f, folder / f.name)
    for f in (data / "imu_other_shanks").iterdir():
        os.symlink(f, folder / f.name)
    return read_recording(folder, {**sensor_map, **OTHER_SHANKS})


def _as_input(rec: Recording, path: str) -> tuple[Recording, dict]:
    """The recording as one input path reads it (bench_real_gait.recording's paths)."""
    if path == "vendor":
        return rec, {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)}
    keep_mag = path == "vqf9"
    sensors = {n: s.replace(quat=None, mag=s.mag if keep_mag else None)
               for n, s in rec.sensors.items()}
    return rec.with_sensors(sensors), {"filter": "pi" if path == "pi6" else "vqf"}


def _error(ours: np.ndarray, truth: np.ndarray, start: int) -> np.ndarray:
    """Ours less the truth (deg) over the walk's samples the cut keeps."""
    a = max(WALK[0], start)
    return np.degrees(ours[a - start:WALK[1] - start] - truth[a:WALK[1]])


def _rmse(ours: np.ndarray, truth: np.ndarray, start: int, centred: bool = False) -> float:
    """The RMSE (deg) over the walk; ``centred``: with the walk's mean error removed."""
    e = _error(ours, truth, start)
    return float(np.sqrt(np.mean((e - e.mean() if centred else e) ** 2)))


def _calibration(how: str) -> str:
    """The summary's calibration line, shortened for a table cell."""
    if how.startswith("from the walk"):
        return "the walk (" + how.split("(", 1)[1].split(")")[0].split(":")[0] + ")"
    return how.split(" (")[0].replace("standing pose, read in the ", "")


def section(data: Path, sensor_map: dict[str, str], subject, inputs, sagittal, refs) -> str:
    """The report's section: per input path and recording, the calibration used, the six
    sagittal RMSEs against Vicon, their median, it with the walk's mean error removed, the median
    against the markers, and the flags; then each joint's mean error against both references
    (what a calibration without a pose changes: the zeros)."""
    full = read_recording(data / "imu", sensor_map)
    recordings = {f"from {s}" if s else "as recorded": (full.cropped(s), s) for s in CUTS}
    recordings["other shanks"] = (other_shanks(data, sensor_map), 0)
    names = " | ".join(c.replace("_angle", "").replace("_flexion", "") for c in sagittal)
    lines = ["", "## The recordings users bring (defaults)", "",
             "S02 as recorded, cut to start as the walk starts (sample 1120) or mid-walk (1300, "
             "1500; scored over the walk's samples the cut keeps), and with the other shank "
             "sensors: the calibration each run chose, the sagittal RMSE against Vicon (deg), "
             "their median, the median with each joint's mean error over the walk removed "
             "(what no choice of the angles' zeros changes), the median against the markers, "
             "and the run's flags.", "",
             f"| input | recording | calibration | {names} | median | mean removed | markers "
             "| flags |", "|---|---|---|" + "---|" * (len(sagittal) + 4)]
    offsets = []
    for path in inputs:
        for label, (rec, start) in recordings.items():
            recording, options = _as_input(rec, path)
            run = process_recording(recording, subject, **options)
            cols = mot_columns(run)
            rmse = {ref: [_rmse(cols[c], table.columns[c], start) for c in sagittal]
                    for ref, table in refs.items()}
            centred = [_rmse(cols[c], refs["vicon"].columns[c], start, True) for c in sagittal]
            lines.append(f"| {path} | {label} | {_calibration(run.calibration)} | "
                         + " | ".join(f"{v:.1f}" for v in rmse["vicon"])
                         + f" | **{np.median(rmse['vicon']):.1f}** | {np.median(centred):.1f} | "
                         f"{np.median(rmse['markers']):.1f} | {len(run.flags)} |")
            offsets.append(f"| {path} | {label} | " + " | ".join(
                " / ".join(f"{_error(cols[c], refs[r].columns[c], start).mean():+.1f}"
                           for r in ("vicon", "markers")) for c in sagittal) + " |")
            print(f"{path:7s} {label:12s} median {np.median(rmse['vicon']):.1f}", flush=True)
    lines += ["", "Each sagittal angle's mean error over the walk (deg, ours less the reference) "
              "against Vicon / the markers, per run above:", "",
              f"| input | recording | {names} |", "|---|---|" + "---|" * len(sagittal), *offsets]
    return "\n".join(lines) + "\n"
