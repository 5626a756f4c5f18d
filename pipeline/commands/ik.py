"""``pipeline ik``: a recording of IMU orientations in, joint angles and landmarks out.

Reads an OpenSim ``.sto`` (or a folder of Xsens MT ``.txt`` exports), runs
:func:`pipeline.process.process_recording` and writes, all or nothing: ``<name>_ik.mot``
(OpenSim coordinate names, degrees), ``<name>_landmarks.csv`` (m), ``<name>.urdf`` (with the
calibrated IMU frames), ``<name>.rrd`` (rerun) and ``<name>_summary.md``.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from pipeline.errors import InputError, QualityError
from pipeline.io.atomic import output_dir, output_set
from pipeline.io.mot import write_mot
from pipeline.io.opensim import read_orientations_sto
from pipeline.io.recording import Recording
from pipeline.io.tables import csv_text
from pipeline.io.xsens import read_xsens_trial
from pipeline.model.anthropometry import Measures
from pipeline.model.conventions import DEFAULT_KNEE
from pipeline.process import IKRun, mot_columns, process_recording

__all__ = ["load_orientations", "run_ik"]


def load_orientations(
    path: str | Path, xsens_map: dict[str, str] | None = None
) -> Recording:
    """An OpenSim ``.sto`` file, or a folder of Xsens MT ``.txt`` exports (one per sensor).

    For a folder, ``xsens_map`` maps OpenSense sensor names to Xsens sensor ids (like OpenSense's
    ``myIMUMappings.xml``), e.g. ``{"pelvis_imu": "00B421AF", ...}``; files are found as
    ``<prefix><id>.txt`` with the common prefix of the export (``MT_012005D6_009-001_``).
    """
    path = Path(path)
    if not path.is_dir():
        return read_orientations_sto(path)
    if not xsens_map:
        raise InputError(
            "a folder of Xsens .txt files needs --xsens-map NAME=ID ... (e.g. "
            "pelvis_imu=00B421AF femur_r_imu=00B4227B)",
            file=path,
        )
    first_id = next(iter(xsens_map.values()))
    matches = sorted(path.glob(f"*{first_id}.txt"))
    if not matches:
        raise InputError(f"no file ending in {first_id}.txt", file=path, field="xsens_map")
    prefix = matches[0].name[: -len(f"{first_id}.txt")]
    return read_xsens_trial(path, {sid: name for name, sid in xsens_map.items()}, prefix=prefix)


def run_ik(
    sto: str | Path,
    measures: Measures,
    out_dir: str | Path,
    *,
    knee: str = DEFAULT_KNEE,
    sensor_to_model: tuple[float, float, float] | None = None,
    heading: str = "anatomical",
    rerun: bool = True,
    xsens_map: dict[str, str] | None = None,
    strict: bool = False,
) -> str:
    """``pipeline ik``: read, calibrate, IK, write `.mot`, landmarks `.csv`, URDF, `.rrd`.

    Implausible results (:mod:`pipeline.analysis.quality`) open the summary and go to stderr;
    with ``strict`` they raise :class:`~pipeline.errors.QualityError` and nothing is written.
    """
    sto, out_dir = Path(sto), Path(out_dir)
    trial = load_orientations(sto, xsens_map)
    name = sto.stem if sto.suffix else sto.name
    output_dir(out_dir)
    with output_set() as out:
        run = process_recording(trial, measures, knee=knee, sensor_to_model=sensor_to_model,
                                heading=heading)
        if run.flags and strict:
            raise QualityError(run.flags, file=sto)
        for flag in run.flags:
            print(f"warning: {flag}", file=sys.stderr)
        run.skeleton.write_urdf(out.path(out_dir / f"{name}.urdf"))
        write_mot(out.path(out_dir / f"{name}_ik.mot"), run.time, mot_columns(run))
        rows = []
        for k, t in enumerate(run.time):
            row = {"time": float(t)}
            for lm, xyz in run.landmarks.items():
                row.update({f"{lm}_{a}": float(xyz[k, i]) for i, a in enumerate("xyz")})
            rows.append(row)
        columns = ["time"] + [f"{lm}_{a}" for lm in run.landmarks for a in "xyz"]
        with out.open(out_dir / f"{name}_landmarks.csv") as fh:
            fh.write(csv_text(rows, columns))
        if rerun:
            _log(run, out.path(out_dir / f"{name}.rrd"), name)
        summary = _summary(sto, run, measures)
        with out.open(out_dir / f"{name}_summary.md") as fh:
            fh.write(summary)
    return summary


def _log(run: IKRun, path: Path, name: str) -> None:
    from pipeline.viz.model import log_motion  # rerun only when a recording is asked for

    log_motion(path, run.time - run.time[0], run.skeleton, run.q, recording_name=name)


def _summary(sto: Path, run: IKRun, measures: Measures) -> str:
    name = sto.stem if sto.suffix else sto.name
    fps = len(run.time) / max(run.seconds_ik, 1e-9)
    lines = [
        f"# IK of {sto.name}",
        "",
        *(f"**WARNING: {flag}**\n" for flag in run.flags),
        f"- subject: sex {measures.sex}, height {measures.height_m:.2f} m; model: {name}.urdf",
        f"- {len(run.time)} frames, {run.time[-1] - run.time[0]:.2f} s; IK {run.seconds_ik:.2f} s "
        f"({fps:.0f} frames/s)",
        f"- heading: {run.heading_method}; subject's right at t0 (world): "
        + "("
        + ", ".join(f"{v:.3f}" for v in run.heading_right)
        + ")",
        f"- orientation residual RMS: median {np.degrees(np.nanmedian(run.residual_rms)):.2f} deg, "
        f"95th percentile {np.degrees(np.nanpercentile(run.residual_rms, 95)):.2f} deg",
        "",
        "| angle | min (deg) | max (deg) |",
        "|---|---|---|",
    ]
    for k, v in run.joint_angles.items():
        lines.append(f"| {k} | {np.degrees(np.nanmin(v)):.1f} | {np.degrees(np.nanmax(v)):.1f} |")
    if run.notes:
        lines += ["", "Notes:", ""] + [f"- {n}" for n in run.notes]
    return "\n".join(lines) + "\n"
