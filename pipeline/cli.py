"""Command-line interface: ``pipeline <command> ...`` (also ``python -m pipeline``).

Errors in user input are printed as one line naming the file and the field, with exit code 2 and no
traceback (``--debug`` shows it). Heavy imports happen inside the commands so ``--help`` is instant.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pipeline.calibration.conventions import (
    DEFAULT_FILTER,
    DEFAULT_METHOD,
    FILTERS,
    JOINTS,
    METHODS,
)
from pipeline.cli_examples import EXAMPLE_NEEDS, EXAMPLES
from pipeline.cli_live import add_live_options, run_live_command
from pipeline.cli_options import PORT, add_ik_options, int_from
from pipeline.cli_startup import recording_writer, single_threaded_blas
from pipeline.errors import InputError, QualityError, RecordingError, Terminated
from pipeline.model.conventions import DEFAULT_KNEE, KNEE_MODES
from pipeline.simulate.conventions import MOTIONS, STANDING_S

DEBUG_HELP = "show tracebacks on errors (default: one line; before or after the command)"


def _version() -> str:
    from pipeline import __version__

    return __version__


def _sub(sub, name: str, help_: str) -> argparse.ArgumentParser:
    needs = f" (reads {EXAMPLE_NEEDS[name]})" if name in EXAMPLE_NEEDS else ""
    p = sub.add_parser(
        name,
        help=help_,
        description=help_,
        epilog=f"example{needs}:\n  {EXAMPLES[name]}",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    # after the command too (``pipeline ik ... --debug``); unset there, the program's stands
    p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP)
    return p


def _add_anthropometrics(p: argparse.ArgumentParser) -> None:
    """The subject's measures (:class:`~pipeline.model.measures.Measures`), sex and height
    required."""
    from pipeline.model.measures import Measures
    from pipeline.option import add_flags, specs

    add_flags(p, specs(Measures))
    for action in p._actions:
        if action.dest in ("sex", "height_m"):
            action.required = True


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="pipeline",
        description="Lower-limb IMU-to-skeleton pipeline on Pinocchio (Wang 2023, Hu 2021).",
        epilog="examples:\n  " + "\n  ".join(EXAMPLES.values()),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="command")

    p = _sub(sub, "scale", "build a subject-scaled URDF from the regression equations")
    _add_anthropometrics(p)
    p.add_argument("--knee", choices=KNEE_MODES, default=DEFAULT_KNEE,
                   help=f"knee model (default {DEFAULT_KNEE})")
    for seg in ("femur", "tibia"):
        p.add_argument(
            f"--knee-axis-{seg}",
            type=float,
            nargs=3,
            metavar=("X", "Y", "Z"),
            help=f"knee AoR in the {seg} frame (unit vector, pointing right) for the hinge; "
            "default: the population mean of the subject's sex (Wang 2023 dataset)",
        )
    p.add_argument("--out", type=Path, required=True, help="output .urdf file")
    p.set_defaults(func=_cmd_scale)

    p = _sub(sub, "ik", "joint angles and landmarks from a recording (IMU orientations or raw "
             "signals)")
    add_ik_options(p)
    p.add_argument("--verbose", action="store_true",
                   help="also print the run's summary (<name>_summary.md; by default: the files "
                   "written and the headline figures)")
    p.set_defaults(func=_cmd_ik)

    p = _sub(sub, "calibrate", "joint-constraint calibration of IMU placement (Hu 2021)")
    p.add_argument("joint", choices=JOINTS, help="joint model")
    p.add_argument("--imu1", type=Path, required=True, help="proximal IMU CSV")
    p.add_argument("--imu2", type=Path, required=True, help="distal IMU CSV")
    p.add_argument("--method", choices=METHODS, default=DEFAULT_METHOD,
                   help=f"optimiser (default {DEFAULT_METHOD}): ipopt is the most accurate and "
                   "fastest, with robust losses and priors; gn (Gauss-Newton, Hu eq 7-15) is "
                   "as accurate on well-excited trials; dwpso and gwo are the paper's swarms, "
                   "kept for comparison (slower; check that they report 'determined')")
    p.add_argument("--iterations", type=int_from(1),
                   help="iteration limit (default: gn 50, ipopt 100, swarms 150 per stage)")
    p.add_argument("--population", type=int_from(2),
                   help="particles (dwpso) or wolves (gwo) (default 40)")
    p.add_argument("--seed", type=int_from(0), default=0,
                   help="seed of the random starts and swarms (default 0)")
    p.add_argument("--json", action="store_true",
                   help="print the result as JSON (default: a text table)")
    p.set_defaults(func=_cmd_calibrate)

    p = _sub(sub, "simulate", "simulate IMU trials with known truth")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--motion", choices=MOTIONS, default="gait",
                   help="simulated motion (default gait)")
    p.add_argument("--duration-s", type=float, default=15.0,
                   help="duration in seconds (default 15; at most 600)")
    p.add_argument("--standing-s", type=float,
                   help="seconds standing still in the neutral pose first (a calibration pose "
                   f"for pipeline ik), then a 1.5 s transition into the motion (default "
                   f"{STANDING_S:g} for gait and static, whose rest pose is standing; 0 for the "
                   "others)")
    p.add_argument("--seed", type=int_from(0), default=0,
                   help="seed of the motion, placements and noise (default 0)")
    p.set_defaults(func=_cmd_simulate)

    p = _sub(sub, "orientations", "raw IMU signals to an OpenSense-compatible orientation .sto")
    p.add_argument("--imu", type=Path, required=True, help="a folder of raw IMU recordings "
                   "(<sensor>.csv, Movella DOT .csv, x-IMU3 device folders) or one file (required)")
    p.add_argument("--filter", choices=FILTERS, default=DEFAULT_FILTER,
                   help=f"attitude filter (default {DEFAULT_FILTER}; pi: Hu 2021's PI filter)")
    p.add_argument("--sensor-map", action="extend", nargs="+", metavar="NAME=ID",
                   help="our sensor name = a unique part of a file name (default: the names)")
    p.add_argument("--ignore", action="extend", nargs="+", metavar="PATTERN", default=[],
                   help="entries of the folder to leave out (file name patterns) (default: none)")
    p.add_argument("--out", type=Path, required=True, help="output .sto file")
    p.set_defaults(func=_cmd_orientations)

    p = _sub(sub, "batch", "run pipeline ik on every trial of a manifest, locally or on Dask")
    p.add_argument("manifest", type=Path, help="CSV: subject,sex,height_m,orientations and any "
                   "pipeline ik option as a column (e.g. sensor_to_model, knee, correction)")
    p.add_argument("--out", type=Path, required=True, help="output directory (required)")
    p.add_argument("--workers", type=int_from(1),
                   help="local worker processes (default: one per core; 1 runs in this process)")
    p.add_argument("--scheduler", help="a Dask scheduler, tcp://HOST:PORT, to run on instead "
                   "(default: local workers)")
    p.add_argument("--force", action="store_true",
                   help="redo trials whose outputs are complete (default: skip them)")
    p.set_defaults(func=_cmd_batch)

    p = _sub(sub, "reproduce", "reproduce a paper's results on its published data")
    p.add_argument("paper", choices=["wang2023"])
    p.add_argument("--data", type=Path, required=True, help="dataset directory")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.add_argument("--rerun", type=Path,
                   help="also write one .rrd per IMC subject into this folder (default: none)")
    p.set_defaults(func=_cmd_reproduce)

    p = _sub(sub, "demo", "end-to-end run on a simulated subject (no external data)")
    p.add_argument("--out", type=Path, default=Path("out/demo"),
                   help="output directory (default out/demo)")
    p.add_argument("--standing-s", type=float, default=STANDING_S,
                   help="seconds standing still in the neutral pose first (the calibration "
                   f"pose; 0.5-10), then a 1.5 s transition into gait (default {STANDING_S:g})")
    p.add_argument("--seed", type=int_from(0), default=0,
                   help="seed of the simulation (default 0)")
    p.add_argument("--overwrite", action="store_true",
                   help="replace a previous demo's outputs in --out (default: refused)")
    p.set_defaults(func=_cmd_demo)

    p = _sub(sub, "view", "open a recording in the rerun viewer")
    p.add_argument("rrd", type=Path, help=".rrd file")
    p.add_argument("--web", action="store_true",
                   help="serve the web viewer on 127.0.0.1 (default: the native viewer)")
    p.add_argument("--port", type=PORT, default=9090,
                   help="port of the web viewer with --web (default 9090)")
    p.add_argument("--grpc-port", type=PORT, default=9876,
                   help="port serving the recording's data with --web (default 9876)")
    p.set_defaults(func=_cmd_view)

    p = _sub(sub, "live", "joint angles and the skeleton while the subject moves: Lab Streaming "
             "Layer streams, or a recording replayed as if live")
    add_live_options(p)
    p.set_defaults(func=run_live_command)
    for sp in sub.choices.values():  # every option's help says whether it has a default
        for action in sp._actions:
            if action.required and action.option_strings and "required" not in action.help:
                action.help += " (required)"
    return parser


def _measures(args):
    from pipeline.model.measures import Measures
    from pipeline.option import specs

    return Measures(**{f.name: getattr(args, f.name) for f in specs(Measures)})


def _pairs(items: list[str] | None, option: str) -> dict[str, str] | None:
    from pipeline.option import parse_pairs

    return parse_pairs(items, option) if items else None


def _say(text: str) -> None:
    """A command's report on standard output, after its outputs are written: a closed pipe
    (``| head -1``) is said nothing of, as a Unix tool does, a full device (``> /dev/full``) on
    stderr; neither is an error (the outputs are complete). Standard output then goes nowhere,
    so that its flush at exit fails no more."""
    import os

    try:
        print(text, flush=True)
    except OSError as exc:
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        if not isinstance(exc, BrokenPipeError):
            print(f"warning: could not print to standard output ({exc.strerror or exc}); the "
                  "outputs are written", file=sys.stderr)


def _cmd_scale(args) -> int:
    from pipeline.commands.scale import run_scale

    line = run_scale(_measures(args), args.out, knee=args.knee,
                     knee_axis_femur=args.knee_axis_femur, knee_axis_tibia=args.knee_axis_tibia)
    _say(line)
    return 0


def _cmd_ik(args) -> int:
    from pipeline.commands.ik import run_settings, summary_text, written_text
    from pipeline.option import from_flag
    from pipeline.process.options import all_specs, resolve_settings
    from pipeline.progress import shown

    values = {s.name: from_flag(s, getattr(args, s.name)) for s in all_specs()}
    settings = resolve_settings(args.config, values)
    with shown("pipeline ik"):
        run = run_settings(settings, recorder=args.recorder)
    _say(summary_text(run) if args.verbose else written_text(run, settings))
    return 0


def _cmd_calibrate(args) -> int:
    from pipeline.commands.calibrate import run_calibration

    # its report is its output (no file): printing it failing is an error
    print(run_calibration(args.joint, args.imu1, args.imu2, args.method, args.seed, args.json,
                          iterations=args.iterations, population=args.population), flush=True)
    return 0


def _cmd_simulate(args) -> int:
    from pipeline.commands.simulate import run_simulation
    from pipeline.simulate.model import STANDING_MOTIONS

    standing = args.standing_s
    if standing is None:  # a calibration pose where the motion's rest pose is standing
        standing = (STANDING_S if args.motion in STANDING_MOTIONS and args.duration_s > STANDING_S
                    else 0.0)
    from pipeline.progress import shown

    with shown(f"pipeline simulate --motion {args.motion}"):
        text = run_simulation(args.out, args.motion, args.duration_s, args.seed, standing)
    _say(text)
    return 0


def _cmd_orientations(args) -> int:
    from pipeline.commands.orientations import run_orientations

    _say(run_orientations(args.imu, args.out, filter=args.filter,
                           sensor_map=_pairs(args.sensor_map, "--sensor-map"),
                           ignore=tuple(args.ignore)))
    return 0


def _cmd_batch(args) -> int:
    """Exit 0 when every row is ok or skipped, 1 when any failed (the summary says which)."""
    from pipeline.commands.batch import run_batch

    text, failed = run_batch(args.manifest, args.out, workers=args.workers,
                             scheduler=args.scheduler, force=args.force)
    _say(text)
    return 1 if failed else 0


def _cmd_reproduce(args) -> int:
    from pipeline.commands.reproduce import run_reproduce

    _say(run_reproduce(args.paper, args.data, args.out, rerun_dir=args.rerun))
    return 0


def _cmd_demo(args) -> int:
    from pipeline.commands.demo import run_demo

    _say(run_demo(args.out, seed=args.seed, standing_s=args.standing_s,
                  overwrite=args.overwrite))
    return 0


def _cmd_view(args) -> int:
    from pipeline.commands.view import run_view

    return run_view(args.rrd, web=args.web, port=args.port, grpc_port=args.grpc_port)


def _terminate(signum, frame) -> None:
    raise Terminated


#: commands that write a rerun recording and use no pandas (``reproduce`` reads MATLAB files
#: through pandas)
_RECORDING_COMMANDS = {_cmd_ik, _cmd_demo}


def main(argv: list[str] | None = None) -> int:
    """The ``pipeline`` program (``argv=None``: ``sys.argv``, run as a program)."""
    if argv is None:
        single_threaded_blas()
    recorder = recording_writer(argv)
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        args.recorder = recorder
        import signal

        if argv is None and args.func in _RECORDING_COMMANDS:
            from pipeline.viz.arrow import avoid_pandas_when_recording

            avoid_pandas_when_recording()  # saves each recording ~0.5 s (see its docstring)

        previous = signal.signal(signal.SIGTERM, _terminate)
        try:
            return _run(args)
        finally:
            signal.signal(signal.SIGTERM, previous)
    finally:
        if recorder is not None:
            recorder.close()


def _run(args) -> int:
    try:
        return int(args.func(args) or 0)
    except QualityError as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return 3
    except (InputError, FileNotFoundError, RecordingError) as exc:
        if args.debug:
            raise
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:  # a fault around the outputs (disk full, permissions, ...)
        if args.debug:
            raise
        where = f"{exc.filename}: " if exc.filename else "cannot write the outputs: "
        print(f"error: {where}{exc.strerror or exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"interrupted: {_left(args)}", file=sys.stderr)
        return 130
    except Terminated:
        print(f"terminated: {_left(args)}", file=sys.stderr)
        return 143


def _left(args) -> str:
    """What an interrupted command leaves."""
    if args.func is _cmd_batch:
        return "the trials that finished are complete, batch_summary.csv lists them"
    from pipeline.io.atomic import committed_outputs

    if done := committed_outputs():  # the signal came after the commit, while the command ended
        return f"the outputs were complete before it ({len(done)} files in {done[0].parent})"
    return "no output was written"


if __name__ == "__main__":
    raise SystemExit(main())
