"""Where live samples come from: a recording replayed as if live, or Lab Streaming Layer streams.

Both give :class:`Chunk` s (a stream's samples since the last read, with its own time stamps)
through one method, ``read()``: a list of chunks (empty: nothing yet), None when the source has
ended. :class:`ReplaySource` plays any recording the project reads in real time (``speed`` 1,
or faster, or ``inf``: as fast as it is processed); :class:`LslSource` opens every LSL stream of
type ``IMU`` (one sensor each, named as a recording's sensors are, ``--sensor-map`` applying; its
channels as :mod:`pipeline.live.channels`), its time stamps LSL's, corrected to this machine's
clock. :func:`serve_outlets` is the other end, for a lab's test and ``pipeline live
--serve-example``: a recording's sensors as LSL outlets, in real time.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SENSOR_NAMES, our_name
from pipeline.live.channels import GROUPS, Layout, layout_of, split

__all__ = ["CHUNK_S", "Chunk", "LslSource", "ReplaySource", "serve_outlets", "stream_name_map"]

#: A replay gives its samples this often (s of recording; at ``speed`` inf, this much a read).
CHUNK_S = 0.01
#: How long (s) :class:`LslSource` looks for streams, and then for the rest of a setup's.
RESOLVE_S = 5.0
SETTLE_S = 1.0


@dataclass(frozen=True)
class Chunk:
    """One stream's samples: ``time`` (n,) s on its own clock, signal -> (n, d)."""

    sensor: str
    time: np.ndarray
    signals: dict[str, np.ndarray]


class ReplaySource:
    """``rec`` (our sensor names) played as live streams (module docstring); a sample a sensor
    misses (NaN) is not sent, as a stream would not send it."""

    def __init__(self, rec: Recording, speed: float = 1.0, *, chunk_s: float = CHUNK_S,
                 clock: Callable[[], float] = time.monotonic,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        if not speed > 0:
            raise InputError(f"expected a positive speed, got {speed}", field="speed")
        self.names, self.rate_hz = list(rec.sensor_names), float(rec.rate_hz)
        self._rec, self._speed, self._chunk = rec, float(speed), float(chunk_s)
        self._clock, self._sleep = clock, sleep
        self._k, self._start = 0, None

    def read(self) -> list[Chunk] | None:
        rec, k = self._rec, self._k
        if k >= rec.n_samples:
            return None
        if np.isinf(self._speed):
            stop = min(rec.n_samples, k + max(1, int(round(self._chunk * self.rate_hz))))
        else:
            now = self._clock()
            self._start = now if self._start is None else self._start
            due = (now - self._start) * self._speed + rec.time[0]
            stop = int(np.searchsorted(rec.time, due, side="right"))
            if stop <= k:
                self._sleep(min(self._chunk, (rec.time[k] - due) / self._speed))
                return []
        self._k = stop
        return [c for name in self.names if (c := self._chunk_of(name, k, stop)) is not None]

    def _chunk_of(self, name: str, a: int, b: int) -> Chunk | None:
        s = self._rec.sensors[name]
        signals = {g: getattr(s, g)[a:b] for g in GROUPS if getattr(s, g) is not None}
        sent = np.all([np.all(np.isfinite(v), axis=1) for v in signals.values()], axis=0)
        if not sent.any():
            return None
        return Chunk(name, self._rec.time[a:b][sent], {g: v[sent] for g, v in signals.items()})

    def close(self) -> None:
        pass


def stream_name_map(names: list[str], sensor_map: Mapping[str, str] | None,
                    where: str = "LSL") -> dict[str, str]:
    """Stream name -> our sensor name: by ``sensor_map`` (our name -> the stream's name or a
    unique part of it), else the name itself when it is one we know (an alias, a label)."""
    out: dict[str, str] = {}
    for ours, theirs in (sensor_map or {}).items():
        if ours not in SENSOR_NAMES:
            raise InputError(f"expected a sensor name among {list(SENSOR_NAMES)}, got {ours!r}",
                             field=f"sensors.{ours}")
        hits = [n for n in names if n == theirs] or [n for n in names if theirs in n]
        if len(hits) != 1:
            raise InputError(f"{'no' if not hits else 'several'} {where} streams match "
                             f"{theirs!r}: {names}", field=f"sensors.{ours}")
        out[hits[0]] = ours
    for n in names:
        if n not in out and (ours := our_name(n)) is not None:
            out[n] = ours
    return out


class LslSource:
    """Every LSL stream of type ``IMU`` found within ``resolve_s`` (module docstring); with
    ``prefix``, those whose names start with it, named without it (several setups on one
    network)."""

    def __init__(self, sensor_map: Mapping[str, str] | None = None, *,
                 resolve_s: float = RESOLVE_S, prefix: str = "") -> None:
        from pipeline.optional import need

        lsl = need("pylsl", "pipeline live --lsl")
        infos = _resolve(lsl, prefix, resolve_s)
        if not infos:
            raise InputError(f"no LSL stream of type IMU found within {resolve_s:g} s",
                             field="lsl")
        names = {i.name()[len(prefix):]: i for i in infos}
        mapped = stream_name_map(list(names), sensor_map)
        unnamed = sorted(set(names) - set(mapped))
        if unnamed:
            raise InputError(f"no sensor name for the LSL streams {unnamed}: name the streams "
                             "after our sensors or give --sensor-map NAME=<stream name>",
                             field="sensor_map")
        self._lsl, self._inlets, self.layouts = lsl, {}, {}
        flags = lsl.proc_clocksync | lsl.proc_monotonize
        rates = {}
        for name, info in names.items():
            inlet = lsl.StreamInlet(info, max_buflen=60, processing_flags=flags)
            full = inlet.info(timeout=resolve_s)
            self.layouts[mapped[name]] = _layout(full, name)
            rates[mapped[name]] = full.nominal_srate()
            inlet.open_stream(timeout=resolve_s)
            self._inlets[mapped[name]] = inlet
        from pipeline.io.checks import check_same_rate

        _sync_clocks(lsl, self._inlets, resolve_s)
        self.names = list(self._inlets)
        self.rate_hz = float(check_same_rate(rates, file=None))

    def read(self) -> list[Chunk]:
        chunks = []
        for name, inlet in self._inlets.items():
            try:
                values, stamps = inlet.pull_chunk(timeout=0.0)
            except (self._lsl.util.TimeoutError, self._lsl.util.LostError):  # gone: it stalls
                continue
            if stamps:
                chunks.append(Chunk(name, np.asarray(stamps, float),
                                    split(np.asarray(values), self.layouts[name])))
        if not chunks:
            time.sleep(0.001)
        return chunks

    def close(self) -> None:
        for inlet in self._inlets.values():
            inlet.close_stream()


def _sync_clocks(lsl, inlets: dict, timeout_s: float) -> None:
    """Each inlet's first clock offset, all at once (LSL's first takes ~0.6 s a stream; left to
    the first reads, one after the other, they held a capture's start by 4.5 s)."""
    from concurrent.futures import ThreadPoolExecutor

    def offset(item):
        name, inlet = item
        try:
            return inlet.time_correction(timeout=timeout_s)
        except lsl.util.TimeoutError:
            raise InputError(f"the LSL stream for {name} gave no clock reply within "
                             f"{timeout_s:g} s", field="lsl") from None

    with ThreadPoolExecutor(max_workers=len(inlets) or 1) as pool:
        list(pool.map(offset, inlets.items()))


def _resolve(lsl, prefix: str, resolve_s: float) -> list:
    """The IMU streams named ``prefix...``: the first within ``resolve_s``, then every one that
    shows up within :data:`SETTLE_S` more (the streams of a setup start together)."""
    def found(minimum: int, timeout: float) -> list:
        infos = lsl.resolve_byprop("type", "IMU", minimum=minimum, timeout=timeout)
        return [i for i in infos if i.name().startswith(prefix)]

    if not found(1, resolve_s):
        return []
    return found(10_000, SETTLE_S)  # waits SETTLE_S: all there are


def _layout(info, name: str) -> Layout:
    """A stream's channel layout from its ``desc/channels`` labels."""
    labels, ch = [], info.desc().child("channels").child("channel")
    while not ch.empty():
        labels.append(ch.child_value("label"))
        ch = ch.next_sibling()
    return layout_of(labels, name, info.channel_count())


def serve_outlets(rec: Recording, speed: float = 1.0, *, stop: Callable[[], bool] = lambda: False,
                  prefix: str = "") -> int:
    """``rec``'s sensors as LSL outlets of type ``IMU`` (named ``prefix + sensor``), its samples
    pushed in real time (``speed``) with LSL time stamps once every outlet has a reader (none
    is lost to a reader still connecting); returns the samples pushed when the recording ends
    or ``stop()`` says so."""
    from pipeline.optional import need

    lsl = need("pylsl", "pipeline live --serve-example")
    outlets = {}
    for name in rec.sensor_names:
        s = rec.sensors[name]
        groups = [g for g in GROUPS if getattr(s, g) is not None]
        info = lsl.StreamInfo(prefix + name, "IMU", sum(len(GROUPS[g]) for g in groups),
                              rec.rate_hz, "float32", f"pipeline-{prefix}{name}")
        channels = info.desc().append_child("channels")
        for g in groups:
            for label in GROUPS[g]:
                channels.append_child("channel").append_child_value("label", label)
        outlets[name] = (lsl.StreamOutlet(info), groups)
    while not stop() and not all(o.have_consumers() for o, _ in outlets.values()):
        time.sleep(0.01)
    source, base, pushed = ReplaySource(rec, speed), lsl.local_clock(), 0
    while not stop() and (chunks := source.read()) is not None:
        for c in chunks:
            outlet, groups = outlets[c.sensor]
            block = np.hstack([c.signals[g] for g in groups]).astype(np.float32)
            outlet.push_chunk(block.tolist(), (base + c.time).tolist())
            pushed += len(c.time)
    return pushed

