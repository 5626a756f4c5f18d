"""The pelvis carried by the stance foot during a live capture.

At each look for strides (:mod:`pipeline.live.gait`) the offline step that carries the body
(:func:`pipeline.process.gait.with_pelvis_path`: each foot sensor's path by strapdown integration
with zero-velocity updates, its orientation from the IK, the stance foot carrying the pelvis)
runs on the same window, with the live configurations of its frames. Its settled part (up to
:data:`~pipeline.live.gait.SETTLE_S` before the window's end) continues the path known so far:
shifted so that it starts where that path ends (each window's integration starts at its own
origin). Between two looks the pelvis goes on at the last settled stride's mean velocity
(:meth:`LivePath.at`), so that the body walks on as it is shown and is put back on the path when
the next look settles it. Without a foot sensor on each foot walking there is no path: the body
stays at the pelvis, as offline.
"""

from __future__ import annotations

import numpy as np

from pipeline.io.recording import Recording
from pipeline.live.gait import SETTLE_S
from pipeline.process.gait import Gait, with_pelvis_path

__all__ = ["VELOCITY_S", "LivePath"]

#: The pelvis's velocity between looks: its mean over this last stretch of the settled path (s).
VELOCITY_S = 1.0


class LivePath:
    """The settled path so far (module docstring): :attr:`time` (n,) s and :attr:`position`
    (n, 3) m in the model's world, replaced together (a look may run beside the frames)."""

    def __init__(self) -> None:
        self._known: tuple[np.ndarray, np.ndarray] = (np.zeros(0), np.zeros((0, 3)))

    @property
    def time(self) -> np.ndarray:
        return self._known[0]

    @property
    def position(self) -> np.ndarray:
        return self._known[1]

    def update(self, gait: Gait, window: Recording, skeleton, Q: np.ndarray) -> bool:
        """Continue the path with ``window``'s settled part (module docstring); ``gait`` the
        window's gait, ``Q`` its frames' configurations of ``skeleton``. Whether it grew."""
        if window.n_samples == 0 or len(Q) != window.n_samples or not np.all(np.isfinite(Q)):
            return False
        found = with_pelvis_path(gait, window, skeleton, Q, []).pelvis_path
        if found is None:
            return False
        known_t, known_p = self._known
        t = window.time
        settled = (t <= t[-1] - SETTLE_S) & np.all(np.isfinite(found), axis=1)
        if len(known_t):
            settled &= t > known_t[-1]
        if not settled.any():
            return False
        new_p = found[settled]
        if len(known_t):  # continue where the path ends (the window's own origin differs)
            last = known_t[-1]
            here = np.array([np.interp(last, t, found[:, j]) for j in range(3)]) \
                if last >= t[0] else new_p[0]
            new_p = new_p + (known_p[-1] - here)
        self._known = (np.concatenate([known_t, t[settled]]),
                       np.concatenate([known_p, new_p]))
        return True

    def at(self, t: float) -> np.ndarray | None:
        """The pelvis at capture time ``t``: on the settled path, or on from its end at its last
        mean velocity; None without a path."""
        time, position = self._known
        if not len(time):
            return None
        if t <= time[-1]:
            return np.array([np.interp(t, time, position[:, j]) for j in range(3)])
        recent = time >= time[-1] - VELOCITY_S
        span = time[-1] - time[recent][0]
        v = (position[-1] - position[recent][0]) / span if span > 0 else np.zeros(3)
        v[1] = 0.0  # on at its height: the vertical is the strides' to settle
        return position[-1] + v * (t - time[-1])
