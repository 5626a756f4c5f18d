"""One-sensor recordings on their own clocks -> one recording on one time base.

Each sensor's time stamps are its own (devices start a few ms apart; a file's time may start at 0
while its device clock did not: the reader then gives the clock's value at its first sample as
``header['clock_start_s']``, and ``header['clock_wrap_s']`` when the clock wraps, e.g. a 32-bit
microsecond counter every 71.6 min). :func:`align_clocks` puts them on the grid ``t0 + k / rate``
over the span any of them covers (its phase the last starting device's), with ``rate`` the
sensors' common rate (refused if they differ by more than 1 %); every signal is interpolated
onto it (linear; the quaternions by normalised linear interpolation between sign-aligned
neighbours). A sensor that starts late or ends early,
or whose own clock jumps (rows missing, longer than a short gap), is missing there (NaN, never
bridged: the run blanks what needs it, :mod:`pipeline.process.missing`). The notes say how far
the devices' clocks were apart and what each sensor leaves uncovered.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.checks import check_same_rate
from pipeline.io.gaps import DEFAULT_MAX_GAP_S
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
    """One-sensor recordings -> one recording on one grid (module docstring); each keeps its
    name (the mapping's key)."""
    if len(recs) == 1:
        (name, r), = recs.items()
        if _jumps(r.time, r.rate_hz) is None:
            return Recording(r.time - r.time[0], r.rate_hz, {name: r.sensor},
                             _header(r.rate_hz, recs.values()), r.notes, source,
                             _own_notes(recs))
    rate = check_same_rate({n: r.rate_hz for n, r in recs.items()}, file=source)
    first = next(iter(recs.values()))
    reference = float(device_time(first)[0])
    times = {n: device_time(r, reference) for n, r in recs.items()}
    starts = {n: float(t[0]) for n, t in times.items()}
    ends = {n: float(t[-1]) for n, t in times.items()}
    if max(starts.values()) - min(ends.values()) > -10.0 / rate:
        span = {n: f"{starts[n]:.3f}-{ends[n]:.3f} s" for n in recs}
        raise InputError(f"the sensors' time stamps do not overlap: {span}", file=source)
    # the grid's phase the last starter's, stepped back over the earlier ones' samples
    latest = max(starts.values())
    t0 = latest - np.floor((latest - min(starts.values())) * rate + 1e-9) / rate
    n = int(np.floor((max(ends.values()) - t0) * rate + 1e-9)) + 1
    t = t0 + np.arange(n) / rate
    t1 = t[-1]
    same = all(times[k].size == n and np.allclose(times[k], t, atol=1e-9, rtol=0) for k in recs)
    sensors: dict[str, SensorSignals] = {}
    notes: list[str] = [m for r in recs.values() for m in r.notes]
    for name, r in recs.items():
        sensors[name] = r.sensor if same else _on_grid(r.sensor, times[name], t, rate)
    if not same:
        spread = 1e3 * (max(starts.values()) - min(starts.values()))
        notes.append(f"clocks aligned by time stamp: devices started up to {spread:.1f} ms apart; "
                     f"resampled to {rate:.4g} Hz over {t1 - t0:.2f} s")
        notes += _uncovered(times, t0, t1, rate)
    return Recording(t - t0, float(rate), sensors, _header(rate, recs.values()), tuple(notes),
                     source, _own_notes(recs))


def _jumps(time: np.ndarray, rate_hz: float) -> list[int] | None:
    """The indices after which a sensor's own clock jumps by more than the samples that may be
    filled (:data:`~pipeline.io.gaps.DEFAULT_MAX_GAP_S`: rows missing, a radio dropout), or None."""
    jumps = np.flatnonzero(np.diff(time) > DEFAULT_MAX_GAP_S + 1.5 / rate_hz)
    return [int(k) for k in jumps] or None


def _late(by_s: float, rate_hz: float) -> bool:
    """Whether a sensor starting (ending) ``by_s`` after (before) the others misses more than a
    short gap (:data:`~pipeline.io.gaps.DEFAULT_MAX_GAP_S`) there."""
    return by_s > DEFAULT_MAX_GAP_S + 0.5 / rate_hz


def _on_grid(s: SensorSignals, tr: np.ndarray, t: np.ndarray, rate: float) -> SensorSignals:
    """A sensor's signals interpolated onto the grid ``t`` from its own time stamps ``tr``;
    missing (NaN) before its first sample and after its last where that is more than a short
    gap (a shorter one held, as a reader holds it), and where its clock jumps by more than a
    short gap (rows missing: never bridged)."""
    late, early = _late(tr[0] - t[0], rate), _late(t[-1] - tr[-1], rate)
    missing = (t < tr[0] - 0.5 / rate) & late | (t > tr[-1] + 0.5 / rate) & early
    for k in _jumps(tr, rate) or ():
        missing |= (t > tr[k] + 0.25 / rate) & (t < tr[k + 1] - 0.25 / rate)
    fields = {}
    for key in ("gyr", "acc", "mag"):
        v = getattr(s, key)
        fields[key] = None if v is None else np.stack(
            [np.interp(t, tr, v[:, k]) for k in range(3)], axis=1)
    fields["quat"] = None if s.quat is None else _nlerp(tr, s.quat, t)
    for v in fields.values():
        if v is not None:
            v[missing] = np.nan
    return SensorSignals(**fields)


def _uncovered(times: Mapping[str, np.ndarray], t0: float, t1: float, rate: float) -> list[str]:
    """What each sensor leaves uncovered of the recording's span: a late start, an early end,
    rows missing (its clock's jumps)."""
    out = []
    for name, tr in times.items():
        said = []
        if _late(tr[0] - t0, rate):
            said.append(f"starts {tr[0] - t0:.2f} s late")
        if _late(t1 - tr[-1], rate):
            said.append(f"ends {t1 - tr[-1]:.2f} s early")
        for k in _jumps(tr, rate) or ():
            said.append(f"has no samples between t = {tr[k] - t0:.2f} and {tr[k + 1] - t0:.2f} s")
        if said:
            out.append(f"{name} {', '.join(said)}: missing there, not bridged")
    return out


def _own_notes(recs: Mapping[str, Recording]) -> dict[str, tuple[str, ...]]:
    """Sensor -> what its own file's reader repaired or noticed (``Recording.sensor_notes``)."""
    return {name: tuple(r.notes) for name, r in recs.items() if r.notes}


def _header(rate: float, recs) -> dict[str, str]:
    """The merged recording's header: its rate, and the devices' world where they share one."""
    world = world_of(recs)
    return {"DataRate": f"{rate:.6f}", **({WORLD: world} if world else {})}
