"""One-sensor recordings on their own clocks -> one recording on one time base.

Each sensor's time stamps are its own (devices start a few ms apart; a file's time may start at 0
while its device clock did not: the reader then gives the clock's value at its first sample as
``header['clock_start_s']``, and ``header['clock_wrap_s']`` when the clock wraps, e.g. a 32-bit
microsecond counter every 71.6 min). :func:`align_clocks` keeps the span all sensors cover, on the
grid ``t0 + k / rate`` with ``rate`` the sensors' common rate (refused if they differ by more than
1 %); every signal is interpolated onto it (linear; the quaternions by normalised linear
interpolation between sign-aligned neighbours). The notes say how far the devices' clocks were
apart and what was cropped.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.checks import check_same_rate
from pipeline.io.recording import WORLD, Recording, SensorSignals, world_of

__all__ = ["align_clocks", "device_time"]


def device_time(rec: Recording, reference: float | None = None) -> np.ndarray:
    """The recording's time stamps on its device clock (``clock_start_s`` added); a wrapping
    clock is unwrapped to the turn nearest ``reference`` (s)."""
    start = float(rec.header.get("clock_start_s", 0.0))
    t = rec.time - rec.time[0] + start if "clock_start_s" in rec.header else rec.time
    wrap = rec.header.get("clock_wrap_s")
    if wrap is not None and reference is not None:
        period = float(wrap)
        t = t + period * np.round((reference - t[0]) / period)
    return t


def _nlerp(t_src: np.ndarray, q: np.ndarray, t: np.ndarray) -> np.ndarray:
    i = np.clip(np.searchsorted(t_src, t, side="right") - 1, 0, len(t_src) - 2)
    a = ((t - t_src[i]) / (t_src[i + 1] - t_src[i]))[:, None]
    q0, q1 = q[i], q[i + 1]
    q1 = np.where(np.sum(q0 * q1, axis=1, keepdims=True) < 0, -q1, q1)
    out = (1 - a) * q0 + a * q1
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def align_clocks(recs: Mapping[str, Recording], *, source: Path | None = None) -> Recording:
    """One-sensor recordings -> one recording on the common span and rate (module docstring);
    each keeps its name (the mapping's key)."""
    if len(recs) == 1:
        (name, r), = recs.items()
        return Recording(r.time - r.time[0], r.rate_hz, {name: r.sensor},
                         _header(r.rate_hz, recs.values()), r.notes, source,
                         _own_notes(recs))  # fmt: skip
    rate = check_same_rate({n: r.rate_hz for n, r in recs.items()}, file=source)
    first = next(iter(recs.values()))
    reference = float(device_time(first)[0])
    times = {n: device_time(r, reference) for n, r in recs.items()}
    starts = {n: float(t[0]) for n, t in times.items()}
    ends = {n: float(t[-1]) for n, t in times.items()}
    t0, t1 = max(starts.values()), min(ends.values())
    if t1 - t0 < 10.0 / rate:
        span = {n: f"{starts[n]:.3f}-{ends[n]:.3f} s" for n in recs}
        raise InputError(f"the sensors' time stamps do not overlap: {span}", file=source)
    n = int(np.floor((t1 - t0) * rate + 1e-9)) + 1
    t = t0 + np.arange(n) / rate
    same = all(times[k].size == n and np.allclose(times[k], t, atol=1e-9, rtol=0) for k in recs)
    sensors: dict[str, SensorSignals] = {}
    notes: list[str] = [m for r in recs.values() for m in r.notes]
    for name, r in recs.items():
        s = r.sensor
        if same:
            sensors[name] = s
            continue
        tr = times[name]
        fields = {}
        for key in ("gyr", "acc", "mag"):
            v = getattr(s, key)
            fields[key] = None if v is None else np.stack(
                [np.interp(t, tr, v[:, k]) for k in range(3)], axis=1)  # fmt: skip
        fields["quat"] = None if s.quat is None else _nlerp(tr, s.quat, t)
        sensors[name] = SensorSignals(**fields)
    if not same:
        spread = 1e3 * (max(starts.values()) - min(starts.values()))
        notes.append(f"clocks aligned by time stamp: devices started up to {spread:.1f} ms apart; "
                     f"kept the {t1 - t0:.2f} s all cover, resampled to {rate:.4g} Hz")  # fmt: skip
    return Recording(t - t0, float(rate), sensors, _header(rate, recs.values()), tuple(notes),
                     source, _own_notes(recs))  # fmt: skip


def _own_notes(recs: Mapping[str, Recording]) -> dict[str, tuple[str, ...]]:
    """Sensor -> what its own file's reader repaired or noticed (``Recording.sensor_notes``)."""
    return {name: tuple(r.notes) for name, r in recs.items() if r.notes}


def _header(rate: float, recs) -> dict[str, str]:
    """The merged recording's header: its rate, and the devices' world where they share one."""
    world = world_of(recs)
    return {"DataRate": f"{rate:.6f}", **({WORLD: world} if world else {})}
