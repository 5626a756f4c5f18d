"""A live capture: samples in, joint angles out, frame by frame, calibrated as it goes.

:class:`LiveCapture` reads a source (:mod:`pipeline.live.sources`) until it ends, the duration
is reached or it is stopped, and for each block of frames the streams give
(:mod:`pipeline.live.aligner`): keeps the samples (the capture, written at the end as ``pipeline
ik`` writes a recording), turns them into orientations (:mod:`pipeline.live.orientation`) and,
once calibrated, into configurations and joint angles (:mod:`pipeline.live.tracker`), handed to
the viewer as they come (:mod:`pipeline.live.viewer`). Its states, said on the terminal and in the
viewer: ``stand still`` until the capture has a still window of :data:`STILL_S` (every sensor at
rest, :mod:`pipeline.process.still`); then it is calibrated on what it has
(:mod:`pipeline.live.calibration`) and, until that calibration is final (``walk``: the walk
checks the pose and gives the heading), again every :data:`RECALIBRATE_S` of capture; then
``calibrated``. A calibration runs beside the frames (a thread) when the source is live, and in
line when it is replayed as fast as it is processed (the frames then wait: the same result
whatever the machine's speed).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.live.aligner import Aligner, Block
from pipeline.live.calibration import LiveCalibration, calibrate_capture
from pipeline.live.gait import LiveGait
from pipeline.live.orientation import LiveOrientations
from pipeline.live.path import LivePath
from pipeline.live.store import CaptureStore, ColumnSpool, Spool
from pipeline.live.tracker import Tracker
from pipeline.model.measures import Measures
from pipeline.process.options import IKOptions
from pipeline.process.still import still_windows

__all__ = ["ANGLE_COLUMNS", "RECALIBRATE_S", "STILL_S", "CalibrationUsed", "CaptureResult",
           "LiveCapture"]

#: The live angles kept (every joint angle the model gives and the pelvis's).
ANGLE_COLUMNS = [f"{side}_{joint}_{angle}" for side in ("right", "left")
                 for joint, angles in (("hip", ("flexion", "adduction", "rotation")),
                                       ("knee", ("flexion", "adduction", "rotation")),
                                       ("ankle", ("flexion", "inversion")))
                 for angle in angles] + ["pelvis_tilt", "pelvis_list", "pelvis_rotation"]

#: The still window (s) the first calibration waits for.
STILL_S = 1.0
#: Until its calibration is final, the capture is calibrated again after this much more (s).
RECALIBRATE_S = 2.0
#: How often (s of capture) the capture looks for its still window.
LOOK_S = 0.5
#: Nothing from any stream for this long (s, by the clock) is said (once, and again when back).
QUIET_S = 3.0


class CalibrationUsed(NamedTuple):
    """A calibration of the capture: made on its first ``at_s`` seconds, ``how``, ``final``,
    and in use from ``from_s`` (later than ``at_s`` when it ran beside the frames)."""

    at_s: float
    how: str
    final: bool
    from_s: float


@dataclass
class CaptureResult:
    """What a capture gave: the ``recording`` captured (our sensor names, on its grid), the live
    ``angles`` (name -> (N,), rad; NaN before the first calibration), each frame's processing
    time (``frame_s``, s: from its block's arrival to its angles, a calibration or a look for
    strides made in line not counted: live, they run beside the frames), the calibrations
    (``calibrations``: :class:`CalibrationUsed`), what it said (``notes``) and
    the strides it found as each completed (``strides``, :mod:`pipeline.live.gait`)."""

    recording: Recording
    angles: dict[str, np.ndarray]
    frame_s: np.ndarray
    calibrations: list[CalibrationUsed] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)
    strides: list = field(default_factory=list)


class LiveCapture:
    """A capture from ``source`` of ``measures`` with ``opts`` (module docstring); ``viewer``:
    what logs each block (or None), ``say``: where the states are said (the terminal)."""

    def __init__(self, source, measures: Measures, opts: IKOptions, *, viewer=None,
                 duration_s: float | None = None, in_line: bool = False,
                 say: Callable[[str], None] = print) -> None:
        self.source, self.measures, self.opts = source, measures, opts
        self.viewer, self.duration_s, self.in_line, self.say = viewer, duration_s, in_line, say
        self.header = dict(getattr(source, "header", {}) or {})
        self.store = CaptureStore(source.names)
        self.orient: LiveOrientations | None = None
        self.tracker: Tracker | None = None
        self.cal: LiveCalibration | None = None
        self.state = ""
        self._pending: threading.Thread | None = None
        self._fresh: LiveCalibration | None = None
        self.gait, self.path = LiveGait(), LivePath()
        self._gait_pending: threading.Thread | None = None
        self._q: Spool | None = None  # each frame's configuration, for the pelvis's path
        self._next_look = STILL_S
        self._refused = ""  # why the last calibration was refused, said once
        self._angles = ColumnSpool(ANGLE_COLUMNS)
        self._frame_s = ColumnSpool(["s"])
        self.result = CaptureResult(Recording(np.zeros(0), 1.0, {}), {}, np.zeros(0))

    def run(self, stop: Callable[[], bool] = lambda: False) -> CaptureResult:
        """Read the source until it ends, ``duration_s`` is reached or ``stop()``; the result."""
        aligner = Aligner(self.source.names, self.source.rate_hz)
        self._set_state("stand still")
        quiet = Quiet(QUIET_S)
        try:
            while not stop():
                chunks = self.source.read()
                if chunks is None:
                    break
                if (words := quiet.heard(bool(chunks), time.monotonic())) is not None:
                    self.say(words)
                arrived = time.perf_counter()
                for c in chunks:
                    aligner.push(c.sensor, c.time, c.signals)
                block = aligner.pull()
                if block is not None and self._frames(block, arrived):
                    break
        finally:
            self.source.close()
            for pending in (self._pending, self._gait_pending):
                if pending is not None:
                    pending.join()
        return self._result()

    def _frames(self, block: Block, arrived: float) -> bool:
        """One block (module docstring); True once ``duration_s`` is reached."""
        if self.duration_s is not None:
            keep = block.time < self.duration_s
            if not keep.all():
                block = _first(block, int(keep.sum()))
        m = len(block.time)
        if m == 0:
            return True
        if self.orient is None:
            own = self.opts.filter is None and all(s.quat is not None
                                                   for s in block.sensors.values())
            self.orient = LiveOrientations(self.source.names, self.source.rate_hz, own,
                                           self._world(own, block), self.opts.filter or "vqf")
        kinds = self.orient.update(block.sensors)
        rotations = self.orient.chosen(kinds)
        self.store.add(block, kinds)
        began = time.perf_counter()
        self._calibrate_if_due(float(block.time[-1]))
        calibrating = time.perf_counter() - began  # in line: not the frames' own time
        angles, Q = {}, None
        if self.tracker is not None:
            Q, angles, poses = self.tracker.solve(rotations)
            if self.viewer is not None:
                self.viewer.log(block.time, poses, angles, self.tracker.cal, Q[-1],
                                self.path.at(float(block.time[-1])))
        self._keep_configurations(Q, m)
        self._angles.append(angles, m)
        self._frame_s.append({"s": np.full(m, (time.perf_counter() - arrived - calibrating) / m)},
                             m)
        self._strides_if_due(float(block.time[-1]))  # in line: after the frames' own time
        return self.duration_s is not None and block.time[-1] >= self.duration_s - 1e-9

    def _keep_configurations(self, Q: np.ndarray | None, m: int) -> None:
        """The block's configurations (NaN before the first calibration) on disk."""
        if self._q is None:
            if Q is None:
                return
            self._q = Spool(Q.shape[1])
            self._q.append(np.full((self.store.n - m, Q.shape[1]), np.nan))
        self._q.append(np.full((m, self._q.width), np.nan) if Q is None else Q)

    def _world(self, own: bool, block: Block) -> np.ndarray | None:
        """The model's world for the streams' own orientations (offline's rule)."""
        if not own:
            return None
        from pipeline.process.prepare import model_world

        rec = Recording(block.time, self.source.rate_hz, block.sensors, self.header)
        return model_world(rec, self.opts, False)[0]

    def _calibrate_if_due(self, now_s: float) -> None:
        if self._fresh is not None:  # a calibration finished beside the frames
            self._use(self._fresh, now_s)
            self._fresh = None
        if self._pending is not None or (self.cal is not None and self.cal.final):
            return
        if self.cal is None:
            if now_s < self._next_look:
                return
            self._next_look = now_s + LOOK_S
            rec = self.store.recording(self.source.rate_hz, self.header)
            if not any(w.t1 - w.t0 >= STILL_S for w in still_windows(rec)):
                return
        elif now_s < max(self.cal.at_s + RECALIBRATE_S, self._next_look):
            return
        self._next_look = now_s + RECALIBRATE_S  # a refused calibration is tried again then
        self._start_calibration(now_s)

    def _strides_if_due(self, now_s: float) -> None:
        """The strides completed since the last look (:mod:`pipeline.live.gait`), every
        :data:`~pipeline.live.gait.GAIT_S`: beside the frames, or in line as a calibration."""
        if self._gait_pending is not None or self.cal is None or now_s < self.gait.due:
            return
        rows = self.gait.window_frames(self.source.rate_hz)
        window = self.store.recording(self.source.rate_hz, self.header, last=rows)
        Q = self._q.read(rows) if self._q is not None else None
        skeleton = self.tracker.cal.skeleton if self.tracker is not None else None

        def work() -> None:
            try:
                new = self.gait.update(window)
                self.result.strides += new
                grew = Q is not None and self.path.update(self.gait.last, window, skeleton, Q)
                if self.viewer is not None and (new or grew):
                    self.viewer.strides(new, self.path.position if grew else None)
            finally:
                self._gait_pending = None

        if self.in_line:
            work()
            return
        self.gait.due = now_s + 1e9  # until the look ends
        self._gait_pending = threading.Thread(target=work, name="live-gait", daemon=True)
        self._gait_pending.start()

    def _start_calibration(self, now_s: float) -> None:
        rec = self.store.recording(self.source.rate_hz, self.header)
        live = self.store.live_rotations()
        if self.in_line:
            if (cal := self._calibration_of(rec, live)) is not None:
                self._use(cal, now_s)
            return

        def work() -> None:
            try:
                self._fresh = self._calibration_of(rec, live)
            finally:
                self._pending = None

        self._pending = threading.Thread(target=work, name="live-calibration", daemon=True)
        self._pending.start()

    def _calibration_of(self, rec: Recording, live) -> LiveCalibration | None:
        """The capture's calibration, or None (said once per reason) where the capture so far
        cannot give one: tried again at the next look."""
        try:
            return calibrate_capture(rec, self.measures, self.opts, live)
        except InputError as e:
            if str(e) != self._refused:
                self._refused = str(e)
                self.say(f"live: not calibrated yet: {e}")
            return None

    def _use(self, cal: LiveCalibration, now_s: float) -> None:
        if self.orient is not None:
            self.orient.nine_d = cal.nine_d
        if cal.final:
            self.store.forget_orientations()
        self.cal, self.tracker = cal, Tracker(cal, self.opts.joint_limits)
        self.result.calibrations.append(CalibrationUsed(cal.at_s, cal.how, cal.final, now_s))
        self._set_state("calibrated" if cal.final else "calibrated: walk a few steps to finish")

    def _set_state(self, state: str) -> None:
        if state != self.state:
            self.state = state
            self.say(f"live: {state}")
            if self.viewer is not None:
                self.viewer.state(state)

    def _result(self) -> CaptureResult:
        self.result.recording = self.store.recording(self.source.rate_hz, self.header)
        self.result.angles = {k: v for k, v in self._angles.read().items() if np.isfinite(v).any()}
        self.result.frame_s = self._frame_s.read()["s"]
        for spool in (self.store, self._angles, self._frame_s, self._q):
            if spool is not None:
                spool.close()
        return self.result


class Quiet:
    """Whether the streams have fallen silent: nothing from any of them for ``limit_s`` (an
    LSL outlet closed, a network down, the sensors off) is said once, and their return."""

    def __init__(self, limit_s: float) -> None:
        self.limit, self.last, self.said = limit_s, None, False

    def heard(self, got: bool, now: float) -> str | None:
        """What to say after a read that ``got`` samples or none at ``now`` (s), if anything."""
        if self.last is None or got:
            self.last = now
            if got and self.said:
                self.said = False
                return "live: the streams are back"
            return None
        if not self.said and now - self.last >= self.limit:
            self.said = True
            return (f"live: nothing from any stream for {self.limit:g} s (Ctrl-C stops and writes "
                    "the capture)")
        return None


def _first(block: Block, m: int) -> Block:
    """The first ``m`` frames of a block."""
    return Block(block.time[:m], {n: s.replace(**{g: getattr(s, g)[:m] for g in
                                                  ("quat", "gyr", "acc", "mag")
                                                  if getattr(s, g) is not None})
                                  for n, s in block.sensors.items()})
