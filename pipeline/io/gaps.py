"""Missing samples: interpolate short runs of NaN; long ones stay missing or are refused.

Readers turn empty or ``NaN`` cells into NaN (:mod:`pipeline.io.text`); :func:`fill_gaps` decides
what to do with them. A short gap is filled (linear interpolation of vectors, slerp of
quaternions, holding the nearest sample at either end) and written to the reader's
:class:`~pipeline.io.notes.Notes`; a gap longer than ``max_gap_s`` stays missing in a
recording's signals (``keep_long``: never bridged, noted with its time range) and is refused
elsewhere (a table the run compares with) with an :class:`~pipeline.errors.InputError`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pipeline.errors import InputError
from pipeline.io.notes import Notes
from pipeline.io.text import FileLike
from pipeline.rotations import exp3, log3, matrix_from_quat, quat_from_matrix

__all__ = ["DEFAULT_MAX_GAP_S", "fill_gaps", "true_runs"]

DEFAULT_MAX_GAP_S = 0.1
"""Longest run of missing samples (seconds) that is interpolated; longer gaps are refused."""


@dataclass(frozen=True)
class Missing:
    """Sensor -> the ``[start, stop)`` sample ranges it misses (a channel of it not finite);
    ``restarted``: the sensors whose orientations were filtered here from their raw signals, the
    filter started again after each gap (a 6-D heading of its own from there on)."""

    spans: dict[str, tuple[tuple[int, int], ...]] = field(default_factory=dict)
    restarted: frozenset[str] = frozenset()

    def mask(self, sensor: str, n: int) -> np.ndarray:
        """(n,) bool: the samples ``sensor`` misses."""
        out = np.zeros(n, dtype=bool)
        for a, b in self.spans.get(sensor, ()):
            out[a:b] = True
        return out

    def of(self, sensors) -> Missing:
        """The spans of ``sensors`` alone."""
        return Missing({k: v for k, v in self.spans.items() if k in sensors},
                       self.restarted & frozenset(sensors))

    def cropped(self, start: int, n: int) -> Missing:
        """The spans of the ``n`` samples from ``start`` on, counted from there."""
        spans = {}
        for name, runs in self.spans.items():
            kept = tuple((max(a - start, 0), min(b - start, n)) for a, b in runs
                         if b > start and a < start + n)
            if kept:
                spans[name] = kept
        return Missing(spans, self.restarted)

    def breaks(self, sensors, n: int) -> np.ndarray:
        """(n,) bool: the samples missing of those ``sensors`` whose filter started again
        after them (a heading may jump across them)."""
        out = np.zeros(n, dtype=bool)
        for name in self.restarted & frozenset(sensors):
            out |= self.mask(name, n)
        return out

    def describe(self, sensor: str, time: np.ndarray) -> str:
        """The spans of ``sensor`` in seconds, for a finding."""
        return ", ".join(f"{time[a]:.2f}-{time[b - 1]:.2f} s" for a, b in self.spans[sensor])


def true_runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """Half-open index runs ``[a, b)`` where ``mask`` is True."""
    m = np.concatenate([[False], mask, [False]]).astype(np.int8)
    d = np.diff(m)
    return list(zip(np.flatnonzero(d == 1).tolist(), np.flatnonzero(d == -1).tolist(), strict=True))


def _slerp_fill(q: np.ndarray, t: np.ndarray, a: int, b: int) -> None:
    """Fill ``q[a:b]`` in place by slerp between ``q[a-1]`` and ``q[b]`` (geodesic on SO(3))."""
    R0 = matrix_from_quat(q[a - 1])
    R1 = matrix_from_quat(q[b])
    w = log3(R0.T @ R1)
    s = (t[a:b] - t[a - 1]) / (t[b] - t[a - 1])
    filled = quat_from_matrix(R0 @ exp3(s[:, None] * w))
    ref = q[a - 1] / np.linalg.norm(q[a - 1])
    filled[filled @ ref < 0] *= -1
    q[a:b] = filled


def fill_gaps(
    time: np.ndarray,
    values: np.ndarray,
    *,
    kind: str = "vector",
    max_gap_s: float = DEFAULT_MAX_GAP_S,
    notes: Notes | None = None,
    file: FileLike = None,
    field: str | None = None,
    keep_long: bool = False,
) -> np.ndarray:
    """Interpolate short runs of missing (non-finite) samples; refuse long ones, or with
    ``keep_long`` leave them missing (NaN: a recording's dropout is never bridged; the run
    blanks what needs the sensor there, :mod:`pipeline.process.missing`) and note them.

    A sample (row) is missing when any of its components is not finite. A run of ``n`` missing
    samples lasts ``n * dt`` (dt = median interval). Runs up to ``max_gap_s`` are filled, inside
    the recording by linear interpolation (``kind="vector"``) or slerp (``kind="quaternion"``,
    constant angular velocity between the neighbours), and at either end by holding the nearest
    valid sample. Each filled run is reported in ``notes`` with its time range. Longer runs are
    refused with their time range. Returns a new array (the input is not modified).
    """
    if kind not in ("vector", "quaternion"):
        raise ValueError(f"kind must be 'vector' or 'quaternion', got {kind!r}")
    t = np.asarray(time, dtype=float)
    v = np.array(values, dtype=float, copy=True)
    squeeze = v.ndim == 1
    if squeeze:
        v = v[:, None]
    if v.shape[0] != t.size:
        raise InputError(f"{v.shape[0]} samples but {t.size} time stamps", file=file, field=field)
    missing = ~np.all(np.isfinite(v), axis=1)
    if not missing.any():
        return v[:, 0] if squeeze else v
    if missing.all():
        raise InputError("no finite values at all (every sample missing)", file=file, field=field)
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    runs = true_runs(missing)
    long = [(a, b) for a, b in runs if (b - a) * dt > max_gap_s + 1e-9]
    if keep_long:
        for a, b in long:
            if notes is not None:
                notes.add(f"missing {b - a} sample(s) ({(b - a) * dt:.3g} s) from t={t[a]:.4g} s "
                          f"to t={t[b - 1]:.4g} s: longer than the {max_gap_s:g} s that may be "
                          "interpolated, not bridged", file=file, field=field)
        runs = [r for r in runs if r not in long]
    for a, b in runs:
        dur = (b - a) * dt
        if dur > max_gap_s + 1e-9:
            raise InputError(
                f"gap of {b - a} missing samples ({dur:.3g} s) from t={t[a]:.4g} s to "
                f"t={t[b - 1]:.4g} s (rows {a}-{b - 1}) is longer than the {max_gap_s:g} s that "
                "may be interpolated",
                file=file,
                field=field,
            )
    for a, b in runs:
        if a == 0 or b == t.size:
            v[a:b] = v[b] if a == 0 else v[a - 1]
            how = "held the nearest valid sample"
        elif kind == "quaternion":
            for r in (a - 1, b):
                if np.linalg.norm(v[r]) < 1e-9:
                    raise InputError(f"zero quaternion at row {r}", file=file, field=field)
            _slerp_fill(v, t, a, b)
            how = "slerp"
        else:
            s = ((t[a:b] - t[a - 1]) / (t[b] - t[a - 1]))[:, None]
            v[a:b] = (1 - s) * v[a - 1] + s * v[b]
            how = "linear interpolation"
        if notes is not None:
            notes.add(
                f"filled {b - a} missing sample(s) from t={t[a]:.4g} s to t={t[b - 1]:.4g} s "
                f"({how})",
                file=file,
                field=field,
            )
    return v[:, 0] if squeeze else v
