"""The faults of time and of the file system (issue 41), as users' files carry them: one sensor's
rows missing from its file or its cells left empty for 0.1, 1 and 5 s mid-walk, a sensor that
starts 5 s late or ends 10 s early, one sensor's quaternions written x, y, z, w, and two runs
started into one output folder. Injected into S02's Xsens files (a copy; the right shank's, the
right thigh's for the quaternions), each recording read back by ``pipeline``'s reader and run on
the vendor's orientations and on the raw signals through VQF. A section of
``scripts/bench_faults.py``'s report (:func:`section`).

For each fault: whether the run named it (the sensor's finding: ``read``, ``dropout``,
``orientations``; or a refusal naming the first run), the samples its joints are blank, and the
RMS change (deg) of the joints against the faultless run outside the fault's span: the joints the
sensor's leg does not have ("untouched", target 0.5) and its leg's.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from pipeline.io.formats import read_recording
from pipeline.model.measures import Measures
from pipeline.process import process_recording

__all__ = ["FAULTS", "section"]

#: S02's sensors (bench_gait.S02_MAP).
S02_MAP = {"pelvis_imu": "00B40B91", "femur_l_imu": "00B40C45", "femur_r_imu": "00B40C3C",
           "tibia_l_imu": "00B40C44", "tibia_r_imu": "00B40C47", "calcn_l_imu": "00B40C55",
           "calcn_r_imu": "00B40C48"}
SHANK, THIGH = "tibia_r_imu", "femur_r_imu"
#: The joints of each faulty sensor's leg: its own, and those its leg's calibration measures with
#: it (the standing lean from the knee's and ankle's centres, the knee's heading); the others (the
#: other leg's, the pelvis's) are "untouched".
JOINTS = {SHANK: ("right_",), THIGH: ("right_",)}
#: Where a mid-walk fault starts (sample, 100 Hz: 14 s, S02 walks from 11 to 21 s).
AT = 1400
SUBJECT = Measures("m", 1.72)

Edit = Callable[[list[str]], list[str]]


def _rows_missing(n: int) -> Edit:
    return lambda rows: rows[:AT] + rows[AT + n:]


def _cells_empty(n: int) -> Edit:
    def edit(rows):
        blank = [r.split(",", 1)[0] + "," * r.count(",") for r in rows[AT:AT + n]]
        return rows[:AT] + blank + rows[AT + n:]

    return edit


def _xyzw(rows: list[str]) -> list[str]:
    out = []
    for r in rows:
        c = r.split(",")
        c[-4:] = c[-3:] + c[-4:-3]  # q0 (w) written last
        out.append(",".join(c))
    return out


#: Fault -> (the sensor, how its file's data rows are edited, the span (samples) it covers in the
#: faultless recording: start, stop; None: the end).
FAULTS: dict[str, tuple[str, Edit, tuple[int, int | None]]] = {
    **{f"{s:g} s of rows missing": (SHANK, _rows_missing(int(100 * s)), (AT, AT + int(100 * s)))
       for s in (0.1, 1.0, 5.0)},
    **{f"{s:g} s of empty cells": (SHANK, _cells_empty(int(100 * s)), (AT, AT + int(100 * s)))
       for s in (0.1, 1.0, 5.0)},
    "starting 5 s late": (SHANK, lambda rows: rows[500:], (0, 500)),
    "ending 10 s early": (SHANK, lambda rows: rows[:-1000], (-1000, None)),
    "quaternions written x, y, z, w": (THIGH, _xyzw, (0, 0)),
}


def _faulty_copy(src: Path, sensor: str, edit: Edit) -> Path:
    """A folder of ``src``'s files (links) but the sensor's, written edited."""
    out = Path(tempfile.mkdtemp(prefix="time_fault_"))
    for f in src.iterdir():
        if S02_MAP[sensor] in f.name:
            lines = f.read_text().splitlines()
            head = next(i for i, line in enumerate(lines) if line.startswith("PacketCounter")) + 1
            (out / f.name).write_text("\n".join(lines[:head] + edit(lines[head:])) + "\n")
        else:
            os.symlink(f.resolve(), out / f.name)
    return out


def _paths(rec):
    """Input path -> (recording, options): the vendor's orientations, the raw signals (VQF)."""
    raw = rec.with_sensors({n: s.replace(quat=None) for n, s in rec.sensors.items()})
    return {"vendor": (rec, {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)}),
            "VQF": (raw, {"filter": "vqf"})}


def _named(run, sensor: str) -> str:
    """The sensor's findings of time and of its orientations, each cut to its first clause."""
    return "; ".join(f"{f.check} ({f.action}): {f.evidence.split(';')[0][:110]}"
                     for f in run.sensor_findings if f.sensor == sensor
                     and f.check in ("read", "dropout", "orientations"))


def _scores(run, base, sensor: str, span: tuple[int, int | None]) -> tuple[int, float, float]:
    """(samples blank, RMS change of the untouched joints, of the sensor's) outside ``span``."""
    n = len(base.time)
    outside = np.ones(n, dtype=bool)
    outside[slice(*span)] = False
    blank = max((int(np.isnan(v).sum()) for v in run.joint_angles.values()), default=0)
    untouched, touched = [0.0], [0.0]
    for key, y in base.joint_angles.items():
        d = np.angle(np.exp(1j * (run.joint_angles[key][outside] - y[outside])))
        rms = float(np.degrees(np.sqrt(np.nanmean(d**2))))
        (touched if key.startswith(JOINTS[sensor]) else untouched).append(rms)
    return blank, max(untouched), max(touched)


def _two_runs(src: Path) -> str:
    """Two ``pipeline ik`` started into one folder, the second once the first holds it: the
    second's exit code and first line."""
    out = Path(tempfile.mkdtemp(prefix="two_runs_")) / "out"
    sensors = ["--sensor-map", *(f"{k}={v}" for k, v in S02_MAP.items())]
    args = [sys.executable, "-m", "pipeline", "ik", "--orientations", str(src), *sensors,
            "--sex", "m", "--height-m", "1.72", "--sensor-to-model", "-1.5708", "0", "0",
            "--no-rerun", "--out", str(out)]
    first = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    for _ in range(600):
        if (out / ".pipeline.lock").exists() or first.poll() is not None:
            break
        time.sleep(0.05)
    second = subprocess.run(args, capture_output=True, text=True)
    first.wait()
    said = (second.stderr.strip().splitlines() or [""])[0]
    said = re.sub(r"\(pid \d+ on [^,]*, started [^:]*:[^:]*:[^)]*\)",
                  "(pid, host, start, recording)", said.replace(str(out), "OUT"))
    return f"exit {second.returncode} (the first: {first.returncode}): {said}"


def section(data: Path) -> list[str]:
    """The report's section on S02 (its files under ``data``)."""
    src = data / "gaittoolbox_s02" / "imu"
    lines = ["## The faults of time (S02's files, one sensor's; scripts/time_faults.py)", "",
             "| fault | input | detected | what the run said | blank (samples) | untouched "
             "joints (deg RMS) | its leg's joints (deg RMS) |", "|---|---|---|---|---|---|---|"]
    bases = {k: process_recording(r, SUBJECT, **o)
             for k, (r, o) in _paths(read_recording(src, S02_MAP)).items()}
    for name, (sensor, edit, span) in FAULTS.items():
        folder = _faulty_copy(src, sensor, edit)
        for path, (rec, opts) in _paths(read_recording(folder, S02_MAP)).items():
            if "quaternions" in name and path == "VQF":
                continue  # the raw signals carry no quaternions
            run = process_recording(rec, SUBJECT, **opts)
            said = _named(run, sensor)
            blank, untouched, touched = _scores(run, bases[path], sensor, span)
            lines.append(f"| {name} | {path} | {'yes' if said else '**no**'} | "
                         f"{said.replace('|', '/') or 'nothing'} | {blank} | {untouched:.2f} | "
                         f"{touched:.2f} |")
    rows = [r.split(" | ") for r in lines[4:]]
    missed = [f"{r[0][2:]} ({r[1]})" for r in rows if r[2] == "**no**"]
    gaps = max(float(r[5]) for r in rows if "quaternions" not in r[0])
    order = max(float(r[5]) for r in rows if "quaternions" in r[0])
    two = _two_runs(src)
    refused = "yes" if "another run" in two else "**no**"
    lines.append(f"| two runs into one folder | vendor | {refused} | {two.replace('|', '/')} | - "
                 "| - | - |")
    lines += ["", f"Detected and named: {len(rows) - len(missed)} of {len(rows)} runs"
              + (f"; not: {', '.join(missed)}" if missed else "") + "; the second run into one "
              f"folder {'refused, naming the first' if refused == 'yes' else 'not refused'}. "
              f"Untouched joints moved by up to {gaps:.2f} deg RMS outside a gap in time (target "
              f"0.5), by {order:.2f} with the thigh's quaternions x, y, z, w (its orientation then "
              "from its raw signals, 6-D, aligned by the joints). A gap is blank in its sensor's "
              "joints; its leg's other joints move by what its lean and headings, measured on "
              "fewer samples, move."]
    return lines + [""]
