"""``pipeline ik``: a recording in, joint angles and landmarks out.

Reads any recording :func:`pipeline.io.formats.read_recording` reads (an OpenSim ``.sto``, a
folder of Xsens MT ``.txt`` exports, raw IMU files), runs
:func:`pipeline.process.process_recording` and writes, all or nothing: ``<name>_ik.mot``
(OpenSim coordinate names, degrees), ``<name>_landmarks.csv`` (m), ``<name>.urdf`` (with the
calibrated IMU frames), ``<name>.rrd`` (rerun), ``<name>_summary.md``, ``<name>_config.toml``
(the resolved configuration: ``pipeline ik --config`` with it reproduces the ``.mot``),
``<name>_figures.json`` (the run's figures, :func:`figures_json`), ``<name>_strides.csv`` when the
recording has strides (:mod:`pipeline.analysis.strides`) and, with ``osim``, ``<name>.osim``
(:mod:`pipeline.model.osim`). A previous run's outputs of the same name are refused unless
``overwrite`` (:data:`OUTPUT_SUFFIXES`).
"""

from __future__ import annotations

import dataclasses
import os
import sys
from pathlib import Path

import numpy as np

from pipeline.analysis.cycles import Cycles, cycle_angles, cycles_csv, cycles_figures
from pipeline.analysis.strides import left_out, strides_csv
from pipeline.commands.ik_summary import summary_text
from pipeline.errors import InputError, QualityError
from pipeline.io.atomic import output_dir, output_set
from pipeline.io.formats import read_recording, recording_name
from pipeline.io.lock import output_lock
from pipeline.io.mot import write_mot
from pipeline.io.recording import Recording
from pipeline.io.tables import write_array_csv
from pipeline.model.measures import Measures
from pipeline.option import specs
from pipeline.process.options import (
    IKOptions,
    IKSettings,
    InputOptions,
    OutputOptions,
    settings_text,
)
from pipeline.process.run import IKRun, mot_columns, process_recording
from pipeline.progress import step

__all__ = ["figures_json", "load_orientations", "output_name", "recording_name", "run_ik",
           "run_settings", "written_text",
           "summary_text", "write_landmarks_csv", "write_outputs"]


def load_orientations(path: str | Path, sensor_map: dict[str, str] | None = None,
                      ignore: tuple[str, ...] = ()) -> Recording:
    """The recording at ``path`` with our sensor names (:func:`pipeline.io.formats.read_recording`:
    every format, the sensor map applied)."""
    return read_recording(path, sensor_map, ignore=ignore)


def run_ik(
    orientations: str | Path,
    measures: Measures,
    out_dir: str | Path,
    options: IKOptions | None = None,
    *,
    recorder=None,
    **changes: object,
) -> IKRun:
    """``pipeline ik`` from Python: read ``orientations``, process, write the files of the module
    docstring into ``out_dir``; return the :class:`~pipeline.process.IKRun`.

    ``options`` (default :class:`IKOptions`) with any option of ``pipeline ik`` changed by
    keyword (:mod:`pipeline.process.options`: e.g. ``correction="none"``, ``sensor_map={...}``,
    ``rerun=False``, ``strict=True``).
    """
    groups: dict[type, dict[str, object]] = {InputOptions: {"orientations": str(orientations)},
                                             OutputOptions: {"out": str(out_dir)}}
    ik_changes = {}
    for key, value in changes.items():
        cls = next((c for c in (InputOptions, OutputOptions) if key in _names(c)), None)
        if cls is None:
            ik_changes[key] = value
        else:
            groups[cls][key] = value
    opts = (options or IKOptions()).replace(**ik_changes)
    settings = IKSettings(measures, InputOptions(**groups[InputOptions]), opts,
                          OutputOptions(**groups[OutputOptions]))
    return run_settings(settings, recorder=recorder)


def _names(cls) -> set[str]:
    return {s.name for s in specs(cls)}


def run_settings(settings: IKSettings, *, recorder=None) -> IKRun:
    """``pipeline ik`` on resolved settings (:func:`~pipeline.process.options.resolve_settings`):
    read, calibrate, correct, IK; write the files of the module docstring; return the run.

    ``recorder``: a :class:`~pipeline.viz.background.BackgroundRecording` the caller started
    early (the command-line program, before its imports; this closes it), else one is started
    here for a short recording where forking is safe. One run writes into a folder at a time
    (:mod:`pipeline.io.lock`); the recording's own folder is refused. Implausible results
    (:mod:`pipeline.analysis.quality`) open the summary and go to stderr; with ``strict`` they
    raise :class:`~pipeline.errors.QualityError` and nothing is written.
    """
    inputs, outputs = settings.inputs, settings.outputs
    orientations, out_dir = Path(inputs.orientations), Path(outputs.out)
    _not_into(orientations, out_dir)
    trial = load_orientations(orientations, inputs.sensor_map, inputs.ignore)
    static = None
    if inputs.static_trial is not None:
        static = load_orientations(inputs.static_trial, inputs.sensor_map, inputs.ignore)
    name = output_name(outputs.name, orientations)
    output_dir(out_dir, create=False)
    taken: list[str] = []
    with output_lock(out_dir, f"pipeline ik of {orientations}", taken):
        for note in taken:
            print(f"note: {note}", file=sys.stderr)
        return _write_run(trial, static, name, settings, recorder)


def output_name(given: str | None, recording: str | Path) -> str:
    """The outputs' name: ``given`` (``--name``: one path component), else the recording's
    (:func:`~pipeline.io.formats.recording_name`)."""
    if given is None:
        return recording_name(recording)
    if not given or given in (".", "..") or "/" in given or os.sep in given:
        raise InputError(f"expected a name, not a path: {given!r}", field="name")
    return given


def _not_into(recording: Path, out_dir: Path) -> None:
    """Refuse outputs into a recording folder or below it (they would mix with its files, and
    be read as part of it next time); beside a one-file recording they are welcome."""
    if not recording.is_dir():
        return
    folder, out = recording.resolve(), out_dir.resolve()
    if out == folder or folder in out.parents:
        raise InputError("--out is in the recording's own folder: its outputs would mix with the "
                         "recording's files; give another --out", file=out_dir, field="out")


def _write_run(trial, static, name: str, settings: IKSettings, recorder) -> IKRun:
    """:func:`run_settings`'s writing, its output folder locked (:mod:`pipeline.io.lock`)."""
    outputs, out_dir = settings.outputs, Path(settings.outputs.out)
    previous = previous_outputs(out_dir, name)
    if previous and not outputs.overwrite:
        names = ", ".join(p.name for p in previous)
        raise InputError(f"a previous run's outputs are there ({names}): give another --out, "
                         "or --overwrite to replace them", file=out_dir, field="out")
    background = (outputs.rerun or outputs.report) and trial.n_samples <= BACKGROUND_FRAMES
    if recorder is not None and not background:
        recorder.close()  # a long recording logs here (one process bounds the memory)
        recorder = None
    worker = recorder
    if worker is None and background:
        from pipeline.viz.background import BackgroundRecording
        worker = BackgroundRecording.start(warm=_warm_outputs)
    try:
        with output_set() as out:
            try:
                run = _outputs(out, out_dir, name, trial, static, settings, worker)
            except BaseException:
                if worker is not None:
                    worker.close()  # the child is gone before its temporary file is removed
                raise
    finally:
        if worker is not None:
            worker.close()
    for stale in set(previous) - set(out.destinations):  # the previous run's, not rewritten
        stale.unlink(missing_ok=True)
    return run


#: Every file ``pipeline ik`` may write for a recording ``<name>``.
OUTPUT_SUFFIXES = (".rrd", ".urdf", "_ik.mot", "_landmarks.csv", ".osim", "_summary.md",
                   "_config.toml", "_figures.json", "_strides.csv", "_cycles.csv",
                   "_report.html")


def written_text(run: IKRun, settings: IKSettings) -> str:
    """What ``pipeline ik`` prints: the headline (frames, strides, warnings) and the files it
    wrote (the summary stays in ``<name>_summary.md``; ``--verbose`` prints it)."""
    out_dir = Path(settings.outputs.out)
    name = output_name(settings.outputs.name, settings.inputs.orientations)
    files = [p.name for p in previous_outputs(out_dir, name)]
    n = len(run.gait.strides)
    head = (f"{name}: {len(run.time)} frames, {run.time[-1] - run.time[0]:.1f} s; joints "
            f"{', '.join(run.sensors.joints)}; {n} stride{'s' * (n != 1)}; "
            f"{len(run.flags)} warning{'s' * (len(run.flags) != 1)}")
    return "\n".join([head, f"wrote {len(files)} files to {out_dir}:",
                      *(f"  {f}" for f in files),
                      f"the summary: {out_dir / f'{name}_summary.md'} (--verbose prints it)"])


def previous_outputs(out_dir: Path, name: str) -> list[Path]:
    """The files (or links) of :data:`OUTPUT_SUFFIXES` for ``name`` already in ``out_dir``."""
    found = [out_dir / f"{name}{s}" for s in OUTPUT_SUFFIXES]
    return [Path(os.path.abspath(p)) for p in found if p.is_symlink() or p.exists()]


#: Recordings up to this many frames are logged by a forked child
#: (:mod:`pipeline.viz.background`), whose imports and logging then overlap the calibration
#: and the IK; longer ones log in the process, where that import is a small part of the time and
#: one process bounds the memory (``results/bench_long.txt``).
BACKGROUND_FRAMES = 20_000


def write_outputs(out, out_dir: Path, name: str, trial: Recording, settings: IKSettings) -> IKRun:
    """Every file of ``pipeline ik`` for ``trial`` (our sensor names) into the output set
    ``out`` (:func:`~pipeline.io.atomic.output_set`), the recording's ``.rrd`` logged here."""
    return _outputs(out, out_dir, name, trial, None, settings, None)


def _outputs(out, out_dir, name, trial, static, settings: IKSettings, worker) -> IKRun:
    outputs = settings.outputs
    run = process_recording(trial, settings.subject, settings.options, static=static)
    run = dataclasses.replace(run, inputs=settings.inputs)
    if run.flags and outputs.strict:
        raise QualityError(run.flags, file=settings.inputs.orientations)
    for flag in run.flags:
        print(f"warning: {flag}", file=sys.stderr)
    if outputs.landmarks == "world" and run.gait.pelvis_path is None:
        run.notes.append("--landmarks world: no pelvis path (a foot sensor on each foot walking "
                         "is needed): the landmarks are relative to the pelvis")
    step("writing the outputs")
    # first: the child writes the recording and the report while the other files are written
    report = _report_job(out, out_dir, name, run) if outputs.report else None
    rrd = out.path(out_dir / f"{name}.rrd") if outputs.rerun else None
    _record_and_report(run, rrd, name, report, worker)
    run.skeleton.write_urdf(out.path(out_dir / f"{name}.urdf"))
    write_mot(out.path(out_dir / f"{name}_ik.mot"), run.time, mot_columns(run))
    with out.open(out_dir / f"{name}_landmarks.csv") as fh:
        write_landmarks_csv(fh, run, world=outputs.landmarks == "world")
    if outputs.osim:
        from pipeline.model.osim import osim_text

        with out.open(out_dir / f"{name}.osim") as fh:
            fh.write(osim_text(run.skeleton, run.sensors.joints, pelvis=run.sensors.pelvis,
                               name=name))
    if run.gait.strides:
        with out.open(out_dir / f"{name}_strides.csv") as fh:
            fh.write(strides_csv(run.gait.strides))
        with out.open(out_dir / f"{name}_cycles.csv") as fh:
            fh.write(cycles_csv(run_cycles(run)))
    with out.open(out_dir / f"{name}_summary.md") as fh:
        fh.write(summary_text(run, name))
    with out.open(out_dir / f"{name}_config.toml") as fh:
        fh.write(_config(settings, name))
    with out.open(out_dir / f"{name}_figures.json") as fh:
        fh.write(figures_json(run))
    if worker is not None:
        worker.wait()
    return run


def _warm_outputs() -> None:
    """The child's imports (:mod:`pipeline.viz.background`): the recording's and the report's."""
    from pipeline.report.plots import warm_plots
    from pipeline.viz.scene import warm_recording

    warm_recording()
    warm_plots()


def _report_job(out, out_dir: Path, name: str, run: IKRun):
    """``(temporary path, ReportParts)`` of ``<name>_report.html`` (:mod:`pipeline.report`);
    None without matplotlib, a warning naming the extra."""
    import importlib.util

    if importlib.util.find_spec("matplotlib") is None:
        print(f"warning: no {name}_report.html: the report needs matplotlib, which the 'report' "
              "extra installs: pip install 'imu-skeleton-pipeline[report]'", file=sys.stderr)
        return None
    from pipeline.report.page import report_parts

    return str(out.path(out_dir / f"{name}_report.html")), report_parts(run, name)


def _config(settings: IKSettings, name: str) -> str:
    from pipeline import __version__

    header = (f"pipeline ik configuration of {name} (pipeline {__version__}); to reproduce:\n"
              f"pipeline ik --config {name}_config.toml --out DIR")
    return settings_text(settings, header)


def run_cycles(run: IKRun) -> Cycles:
    """The run's strides' joint angles over their cycles (:mod:`pipeline.analysis.cycles`)."""
    return cycle_angles(run.time, run.joint_angles, run.gait.strides)


def figures_json(run: IKRun) -> str:
    """The run's figures as JSON (what ``pipeline batch`` lists per trial): frames, duration,
    median and 95th-percentile residual (deg), the quality flags, the strides' means over the
    straight, steady strides (SI units; ``stance_share`` a fraction) and why the others were left
    out, and each joint's mean ± SD curve over the cycle per side (``cycles``, deg, 101 points:
    :func:`pipeline.analysis.cycles.cycles_figures`)."""
    import json

    res = np.degrees(run.residual_rms)
    fig = {"frames": int(len(run.time)), "duration_s": float(run.time[-1] - run.time[0]),
           "residual_median_deg": float(np.nanmedian(res)),
           "residual_p95_deg": float(np.nanpercentile(res, 95)),
           "flags": list(run.flags), "joints": list(run.sensors.joints),
           "strides": len(run.gait.strides), **_stride_means(run),
           "strides_left_out": left_out(run.gait.strides) if run.gait.strides else {},
           "cycles": cycles_figures(run_cycles(run))}
    return json.dumps(fig, indent=1) + "\n"


#: The strides' means (both sides) that ``_figures.json`` and ``batch_summary.csv`` list.
STRIDE_FIGURES = ("stride_time_s", "stride_length_m", "speed_m_s", "cadence_steps_min",
                  "stance_share")


def _stride_means(run: IKRun) -> dict[str, float | None]:
    from pipeline.analysis.strides import stride_summary

    both = stride_summary(run.gait.strides)["both"]
    return {c: (float(both[c][0]) if both[c][2] else None) for c in STRIDE_FIGURES}


def write_landmarks_csv(fh, run: IKRun, chunk: int = 10_000, world: bool = False) -> None:
    """``time`` and ``<landmark>_x,y,z`` (m, 6 significant digits) to the open file ``fh``, in
    chunks of rows (memory stays bounded on long recordings); ``world``: in the room (the
    pelvis's path added), where the run has that path."""
    columns = ["time"] + [f"{lm}_{a}" for lm in run.landmarks for a in "xyz"]
    shift = run.gait.pelvis_path if world and run.gait.pelvis_path is not None else 0.0
    shift = np.broadcast_to(shift, (len(run.time), 3))
    for start in range(0, max(len(run.time), 1), chunk):
        rows = slice(start, start + chunk)
        data = np.column_stack([run.time[rows], *(xyz[rows] + shift[rows]
                                                  for xyz in run.landmarks.values())])
        write_array_csv(fh, columns, data, digits=6, header=start == 0)


def _recording_args(run: IKRun, name: str) -> tuple:
    """``(time, skeleton, Q, SceneOptions)`` of the run's recording."""
    from pipeline.viz.model import SceneOptions  # rerun only when a recording is asked for

    angles = [k for k in run.joint_angles if not k.startswith("pelvis_")]
    path, prints = run.gait.pelvis_path, {}
    if path is not None:  # walking through the room, each foot's last rest marked
        prints = {f"{side}_footprint": _footprints(run, side) for side in run.gait.paths}
    return run.time - run.time[0], run.skeleton, run.q, SceneOptions(
        recording_name=name, landmarks=list(run.landmarks) or False, joint_angles=angles,
        root_path=path, reference_landmarks=prints or None)


def _footprints(run: IKRun, side: str) -> np.ndarray:
    """Where the ``side`` foot's sensor last rested (in the room), at every sample."""
    from pipeline.analysis.landmarks import frame_trajectories

    _, p = frame_trajectories(run.skeleton, run.q, [f"{side}_foot_imu"])[f"{side}_foot_imu"]
    world = p + run.gait.pelvis_path
    out = np.full_like(world, np.nan)
    for a, b in run.gait.events[side].rests:
        out[a:] = np.nanmean(world[a:b], axis=0)
    return out


def _record_and_report(run: IKRun, rrd: Path | None, name: str, report, worker) -> None:
    """The run's ``.rrd`` (:func:`pipeline.viz.model.log_motion`) at ``rrd`` (None: none) and its
    report (``(path, parts)`` or None); with a ``worker``, the scene computed here
    (:func:`pipeline.viz.model.motion_scene`) and both written by the child
    (:func:`outputs_in_child`, no Pinocchio there): the same files."""
    if worker is None:
        if rrd is not None:
            from pipeline.viz.model import log_motion  # rerun only when a recording is asked for

            log_motion(rrd, *_recording_args(run, name))
        if report is not None:
            from pipeline.report.page import write_report

            write_report(*report)
        return
    scene = None
    if rrd is not None:
        from pipeline.viz.model import motion_scene

        scene = motion_scene(*_recording_args(run, name))
    worker.submit(outputs_in_child, None if rrd is None else str(rrd), scene, report)


def outputs_in_child(rrd: str | None, scene, report) -> None:
    """The forked child's job (:mod:`pipeline.viz.background`): the recording from its scene
    (:func:`pipeline.viz.scene.log_scene`) and the report (``(path, parts)``:
    :func:`pipeline.report.page.write_report`), each where given."""
    if rrd is not None:
        from pipeline.viz.scene import log_scene

        log_scene(rrd, scene)
    if report is not None:
        from pipeline.report.page import write_report

        write_report(*report)
