"""Live streams on their own clocks put on one time base, frame by frame.

Each stream's samples arrive with its own time stamps (LSL's, a replayed file's), in chunks, a
stream sometimes late, stalled or dropping samples. :class:`Aligner` puts them on the grid
``t0 + k / rate`` as :func:`pipeline.io.clocks.align_clocks` does offline: its phase the last
starting stream's first sample (once every stream has started, or :data:`STALL_S` after the first
one did, without those that did not); each signal interpolated linearly (quaternions by
normalised linear interpolation between sign-aligned neighbours), missing (NaN) where the
stream's own samples around a grid time are more than a short gap apart
(:data:`~pipeline.io.gaps.DEFAULT_MAX_GAP_S`: dropped samples, never bridged). A grid time is
given out once every stream that is not stalled has a sample at or after it; a stream whose
newest sample is :data:`STALL_S` behind the newest of all, and from which nothing arrived for
:data:`STALL_S` (by the clock), is stalled: its frames are given out missing meanwhile, not
held, and it is back with its next sample. A stream that delivers a backlog (its samples late
but arriving: a reader catching up, a network burst) is waited for, not cut.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pipeline.io.checks import make_quaternions_continuous
from pipeline.io.gaps import DEFAULT_MAX_GAP_S
from pipeline.io.recording import SensorSignals

__all__ = ["STALL_S", "Aligner", "Block"]

#: A stream this far (s) behind the newest sample of all is stalled (its frames missing).
STALL_S = 0.25


@dataclass(frozen=True)
class Block:
    """Consecutive frames: ``time`` (m,) s from ``t0``, each stream's signals on them."""

    time: np.ndarray
    sensors: dict[str, SensorSignals]


class Aligner:
    """Streams ``names`` (each pushed with its own time stamps) onto one grid at ``rate_hz``
    (module docstring)."""

    def __init__(self, names, rate_hz: float, stall_s: float = STALL_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.names, self.rate, self.stall = list(names), float(rate_hz), float(stall_s)
        self.clock, self._heard = clock, {}  # when each stream's last samples arrived
        self._t: dict[str, np.ndarray] = {n: np.zeros(0) for n in self.names}
        self._x: dict[str, dict[str, np.ndarray]] = {n: {} for n in self.names}
        self.t0: float | None = None
        self._next = 0  # the next grid index to give out
        self._first = np.inf  # the first time stamp of any stream

    def push(self, name: str, t: np.ndarray, signals: dict[str, np.ndarray]) -> None:
        """Append a stream's chunk (time stamps (n,) s, signal -> (n, d)); samples not later
        than its last are dropped (a repeated or reordered time stamp)."""
        t = np.asarray(t, dtype=float)
        last = self._t[name][-1] if self._t[name].size else -np.inf
        keep = t > last
        keep &= np.concatenate([[True], np.diff(t) > 0]) if t.size else keep
        if not keep.any():
            return
        self._heard[name] = self.clock()
        self._first = min(self._first, float(t[keep][0]))
        self._t[name] = np.concatenate([self._t[name], t[keep]])
        for signal, v in signals.items():
            v = np.asarray(v, dtype=float)[keep]
            if signal == "quat":
                v = _continuous(v, self._x[name].get("quat"))
            old = self._x[name].get(signal)
            self._x[name][signal] = v if old is None else np.concatenate([old, v])

    def pull(self) -> Block | None:
        """The frames every stream that is not stalled has reached since the last pull, or
        None."""
        last = {n: t[-1] for n, t in self._t.items() if t.size}
        if not last:
            return None
        newest = max(last.values())
        if self.t0 is None and not self._start(last, newest):
            return None
        now = self.clock()
        live = [n for n in last if last[n] >= newest - self.stall
                or now - self._heard[n] < self.stall]
        stop = int(np.floor((min(last[n] for n in live) - self.t0) * self.rate + 1e-9)) + 1
        if stop <= self._next:
            return None
        tau = self.t0 + np.arange(self._next, stop) / self.rate
        self._next = stop
        sensors = {n: self._on(n, tau) for n in self.names}
        for n in self.names:
            self._trim(n, tau[-1])
        return Block(tau - self.t0, sensors)

    def _start(self, last: dict[str, float], newest: float) -> bool:
        """Set ``t0`` once every stream has started, or once the first started :data:`STALL_S`
        ago, by its time stamps and by the clock (a reader's first bursts come in any order)."""
        waited = self.clock() - min(self._heard.values())
        if len(last) < len(self.names) and (newest < self._first + self.stall
                                            or waited < self.stall):
            return False
        latest = max(self._t[n][0] for n in last)
        self.t0 = latest - np.floor((latest - self._first) * self.rate + 1e-9) / self.rate
        return True

    def _on(self, name: str, tau: np.ndarray) -> SensorSignals:
        """The stream's signals at ``tau``, NaN where its samples around are a gap apart."""
        t, x = self._t[name], self._x[name]
        if not x:
            return SensorSignals()
        k = np.searchsorted(t, tau, side="right")  # t[k-1] <= tau < t[k]
        lo, hi = np.clip(k - 1, 0, max(t.size - 1, 0)), np.clip(k, 0, max(t.size - 1, 0))
        eps = 1e-6 / self.rate  # the grid's and the stamps' rounding
        at_lo, at_hi = np.abs(t[lo] - tau) <= eps, np.abs(t[hi] - tau) <= eps
        inside = (k >= 1) & (k < t.size)
        span = np.where(inside, t[hi] - t[lo], np.inf)
        ok = at_lo | at_hi | (inside & (span <= DEFAULT_MAX_GAP_S + 1.5 / self.rate))
        w = np.where(inside & (span > 0), (tau - t[lo]) / np.where(span > 0, span, 1.0), 0.0)
        w = np.where(at_lo, 0.0, np.where(at_hi, 1.0, w))
        out = {}
        for signal, v in x.items():
            y = (1 - w)[:, None] * v[lo] + w[:, None] * v[hi]
            if signal == "quat":
                y /= np.linalg.norm(y, axis=1, keepdims=True)
            y[~ok] = np.nan
            out[signal] = y
        return SensorSignals(**out)

    def _trim(self, name: str, done: float) -> None:
        """Drop the samples no later grid time needs (keep the last one at or before ``done``)."""
        t = self._t[name]
        k = max(int(np.searchsorted(t, done, side="right")) - 1, 0)
        if k:
            self._t[name] = t[k:]
            self._x[name] = {s: v[k:] for s, v in self._x[name].items()}


def _continuous(q: np.ndarray, before: np.ndarray | None) -> np.ndarray:
    """Quaternions sign-aligned with each other and with the last one ``before``."""
    if len(q) == 1 and before is not None and len(before):  # a live stream's usual chunk
        return -q if float(q[0] @ before[-1]) < 0 else q
    if before is not None and len(before):
        return make_quaternions_continuous(np.vstack([before[-1:], q]))[0][1:]
    return make_quaternions_continuous(q)[0]
