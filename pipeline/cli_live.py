"""``pipeline live``'s flags and its command (:mod:`pipeline.commands.live`): its own options
(:class:`~pipeline.live.options.LiveOptions`) and ``pipeline ik``'s, each from its one
definition; importable at no cost (``--help`` loads no NumPy)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pipeline.option import add_flags

__all__ = ["EXAMPLE_RECORDING", "add_live_options", "run_live_command"]

#: What ``--serve-example`` streams without a recording named.
EXAMPLE_RECORDING = "example:ximu3_lower_body"


def add_live_options(p: argparse.ArgumentParser) -> None:
    """The flags of ``pipeline live``."""
    from pipeline.live.options import live_specs

    p.add_argument("--config", type=Path, help="subject.toml: subject, sensor names and any of "
                   "pipeline ik's options (flags override it) (default: none)")
    p.add_argument("--serve-example", nargs="?", const=EXAMPLE_RECORDING, default=None,
                   metavar="RECORDING", help="instead of a capture: stream a recording's sensors "
                   f"as LSL outlets in real time, for --lsl to read (default: {EXAMPLE_RECORDING})")
    add_flags(p, live_specs())


def run_live_command(args) -> int:
    """``pipeline live`` with parsed ``args``: a capture, or ``--serve-example``."""
    from pipeline.live.options import LiveOptions
    from pipeline.option import from_flag, specs

    if args.serve_example is not None:
        return _serve(args.serve_example, from_flag_map(args))
    from pipeline.commands.live import run_live
    from pipeline.process.options import all_specs, resolve_settings

    own = {s.name: from_flag(s, getattr(args, s.name)) for s in specs(LiveOptions)}
    live = LiveOptions(**{k: v for k, v in own.items() if v is not None})
    values = {s.name: from_flag(s, getattr(args, s.name)) for s in all_specs()
              if s.name not in ("orientations", "static_trial")}
    values["orientations"] = live.replay or "lsl"
    settings = resolve_settings(args.config, values)
    result = run_live(settings, live)
    print(f"live: {result.recording.n_samples} frames captured; written to "
          f"{settings.outputs.out}")
    return 0


def from_flag_map(args) -> dict[str, str] | None:
    """The ``--sensor-map`` pairs given, for ``--serve-example`` (the streams' names)."""
    from pipeline.option import parse_pairs

    words = getattr(args, "sensor_map", None)
    return parse_pairs(words, "sensor_map") if words else None


def _serve(recording: str, sensor_map) -> int:
    from pipeline.commands.ik import load_orientations
    from pipeline.live.sources import serve_outlets

    rec = load_orientations(recording, sensor_map)
    print(f"serving {len(rec.sensor_names)} LSL streams of type IMU ({', '.join(rec.sensor_names)})"
          f" at {rec.rate_hz:.4g} Hz for {rec.time[-1]:.1f} s once a pipeline live --lsl reads "
          "them all; Ctrl-C stops", file=sys.stderr)
    pushed = serve_outlets(rec)
    print(f"served {pushed} samples", file=sys.stderr)
    return 0
