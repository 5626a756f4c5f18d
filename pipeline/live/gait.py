"""Gait events and strides during a live capture, each stride said as it completes.

Every :data:`GAIT_S` of capture once it is calibrated, the offline gait step
(:func:`pipeline.process.gait.gait_of`: each leg's events from its foot sensor, else its shank's,
and the strides between them) runs on the capture's last :data:`WINDOW_S` of raw signals. A
stride is new when it ends :data:`SAME_S` or more after the last one its side reported (a contact
placed again on more samples moves by a sample or two), and complete when it ends at least
:data:`SETTLE_S` before the window does (its contacts then no longer move as samples arrive: the
events need the swing after the stride to place its final contact, and a rest's stillest instant
the stance around it). The window is long enough for a stride of
:data:`~pipeline.analysis.strides.MAX_STRIDE_S` and the swings that date it; the capture's
written strides are the offline run's, on the whole capture.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pipeline.analysis.strides import MAX_STRIDE_S, Stride
from pipeline.io.recording import Recording
from pipeline.process.gait import Gait, gait_of

__all__ = ["GAIT_S", "SAME_S", "SETTLE_S", "WINDOW_S", "LiveGait"]

#: How often (s of capture) the strides are looked for (a look takes ~11 ms on S02's seven
#: sensors: beside the frames, it delays at most one frame in this many seconds' worth).
GAIT_S = 2.0
#: The window (s) they are looked for in.
WINDOW_S = 12.0
#: A stride ending this close (s) to the window's end is not yet complete.
SETTLE_S = MAX_STRIDE_S / 2
#: Two strides of a side ending closer than this (s) are one, found again.
SAME_S = 0.25


@dataclass
class LiveGait:
    """The strides a capture has completed so far (module docstring), in the order they were
    found; ``due``: the capture time (s) of the next look; ``last``: the last look's gait (its
    window's events, paths and strides)."""

    strides: list[Stride] = field(default_factory=list)
    due: float = GAIT_S
    last: Gait | None = None
    _until: dict[str, float] = field(default_factory=lambda: {"right": -np.inf,
                                                               "left": -np.inf})

    def window_frames(self, rate_hz: float) -> int:
        return int(round(WINDOW_S * rate_hz))

    def update(self, window: Recording) -> list[Stride]:
        """The strides of the capture's last frames ``window`` that completed since the last
        look (module docstring); the next look is due :data:`GAIT_S` later."""
        if window.n_samples == 0:
            return []
        end = float(window.time[-1])
        self.due = end + GAIT_S
        self.last = gait_of(window, [])
        found = self.last.strides
        new = [s for s in found if s.end_s > self._until[s.side] + SAME_S
               and s.end_s <= end - SETTLE_S and s.start_s >= float(window.time[0])]
        for s in new:
            self._until[s.side] = max(self._until[s.side], s.end_s)
        self.strides += new
        return new
