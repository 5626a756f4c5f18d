"""``pipeline live``: joint angles and the walking skeleton while the subject moves.

A source (:mod:`pipeline.live.sources`: ``--replay RECORDING``, any recording the project reads,
played as if live; or ``--lsl``, Lab Streaming Layer streams) through the live capture
(:mod:`pipeline.live.capture`), shown in rerun as it comes (:mod:`pipeline.live.viewer`). It
stops at the replay's end, after ``--duration-s``, or on Ctrl-C or SIGTERM; then it writes into
``--out``, all or nothing (:mod:`pipeline.io.atomic`; the folder held for the whole capture,
:mod:`pipeline.io.lock`): the capture (``<name>_capture/<sensor>.csv``, our IMU CSV, or
``<name>_capture.sto`` when the streams carry orientations only: ``pipeline ik`` reads it back),
every output ``pipeline ik`` writes for it (the same options, the whole capture processed as a
recording), and the angles as they were shown (``<name>_live.mot``, NaN before the first
calibration).
"""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Callable
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.atomic import output_dir, output_set
from pipeline.io.imu_csv import write_imu_csv
from pipeline.io.lock import output_lock
from pipeline.io.mot import write_mot
from pipeline.io.opensim import write_orientations_sto
from pipeline.io.recording import Recording
from pipeline.live.capture import CaptureResult, LiveCapture
from pipeline.live.options import LiveOptions
from pipeline.process.options import IKSettings
from pipeline.process.run import MOT_NAMES
from pipeline.process.solve import PELVIS_ANGLES

__all__ = ["live_mot_columns", "run_live"]


def run_live(settings: IKSettings, live: LiveOptions, *, source=None,
             stop: Callable[[], bool] | None = None) -> CaptureResult:
    """The capture of the module docstring; ``source``: one given (tests), else ``live``'s;
    ``stop``: the capture ends when it says so (else Ctrl-C or SIGTERM)."""
    from pipeline.commands.ik import recording_name

    out_dir = Path(settings.outputs.out)
    name = settings.outputs.name or (recording_name(Path(live.replay)) if live.replay
                                     else "live")
    output_dir(out_dir, create=False)
    with output_lock(out_dir, f"pipeline live ({name})", []):
        source = source if source is not None else _source(live, settings)
        viewer = _viewer(live, name)
        capture = LiveCapture(source, settings.subject, settings.options, viewer=viewer,
                              duration_s=live.duration_s,
                              in_line=bool(live.replay) and live.speed == "max",
                              say=lambda line: print(line, file=sys.stderr))
        stopped = threading.Event()
        try:
            with _stopping_on_signals(stopped):
                result = capture.run(lambda: stopped.is_set() or (stop is not None and stop()))
        finally:
            if viewer is not None:
                viewer.close()
        if stopped.is_set():
            print("live: stopped; writing the capture", file=sys.stderr)
        _write(result, name, settings)
    return result


def _source(live: LiveOptions, settings: IKSettings):
    """The source ``live`` asks for (module docstring)."""
    from pipeline.live.sources import LslSource, ReplaySource

    if live.lsl:
        return LslSource(settings.inputs.sensor_map)
    from pipeline.commands.ik import load_orientations

    rec = load_orientations(live.replay, settings.inputs.sensor_map, settings.inputs.ignore)
    source = ReplaySource(rec, live.speed_factor)
    source.header = dict(rec.header)
    return source


def _viewer(live: LiveOptions, name: str):
    """The viewer ``live.viewer`` asks for, or None (``auto`` without a display: said)."""
    mode = live.viewer
    if mode == "auto":
        from pipeline.viz.viewer import has_display

        mode = "spawn" if has_display() else "none"
        if mode == "none":
            print("live: no display for a viewer here (--viewer web serves one)", file=sys.stderr)
    if mode == "none":
        return None
    from pipeline.live.viewer import LiveViewer

    return LiveViewer(name, mode)


class _stopping_on_signals:
    """Ctrl-C and SIGTERM end the capture (``event`` set) instead of the program: the capture is
    then written; a second one stops the program (nothing half-written)."""

    def __init__(self, event: threading.Event) -> None:
        self.event, self.previous = event, {}

    def __enter__(self):
        if threading.current_thread() is not threading.main_thread():
            return self
        for sig in (signal.SIGINT, signal.SIGTERM):
            self.previous[sig] = signal.signal(sig, self._stop)
        return self

    def _stop(self, signum, frame) -> None:
        self.event.set()
        for sig, handler in self.previous.items():  # a second signal: the program's own
            signal.signal(sig, handler)

    def __exit__(self, *exc) -> None:
        for sig, handler in self.previous.items():
            signal.signal(sig, handler)


def _write(result: CaptureResult, name: str, settings: IKSettings) -> None:
    """The capture's files (module docstring), all or nothing."""
    from pipeline.commands.ik import write_outputs

    rec = result.recording
    if rec.n_samples < 2:
        raise InputError("nothing was captured (no frame of every stream)", field="replay")
    out_dir = Path(settings.outputs.out)
    raw = all(s.gyr is not None and s.acc is not None for s in rec.sensors.values())
    where = out_dir / (f"{name}_capture" if raw else f"{name}_capture.sto")
    with output_set() as out:
        if raw:  # our IMU CSV, one per sensor
            for sensor in rec.sensor_names:
                one = Recording.single(sensor, rec.time, rate_hz=rec.rate_hz,
                                       **_signals(rec, sensor))
                write_imu_csv(out.path(where / f"{sensor}.csv"), one)
        else:  # orientations only: OpenSense's .sto
            write_orientations_sto(out.path(where), rec)
        capture = settings.inputs.replace(orientations=str(where))
        write_outputs(out, out_dir, name, rec, IKSettings(settings.subject, capture,
                                                          settings.options, settings.outputs))
        write_mot(out.path(out_dir / f"{name}_live.mot"), rec.time,
                  live_mot_columns(result.angles))


def _signals(rec: Recording, sensor: str) -> dict[str, np.ndarray]:
    s = rec.sensors[sensor]
    return {k: getattr(s, k) for k in ("quat", "gyr", "acc", "mag") if getattr(s, k) is not None}


def live_mot_columns(angles: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The live angles as :func:`~pipeline.process.run.mot_columns` names them (radians)."""
    cols = {k: angles[k] for k in PELVIS_ANGLES if k in angles}
    for side, suffix in (("right", "r"), ("left", "l")):
        for ours, theirs in MOT_NAMES.items():
            if f"{side}_{ours}" in angles:
                cols[f"{theirs}_{suffix}"] = angles[f"{side}_{ours}"]
    return cols
