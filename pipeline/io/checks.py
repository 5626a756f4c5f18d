"""Validation shared by every reader: time stamps, rates, gaps, quaternions, units.

One place for the checks a recording must pass before it enters the pipeline. Every refusal is an
:class:`~pipeline.errors.InputError` naming the file, the field, what was expected and what was
found (with the row). Every repair (gap interpolation, quaternion normalisation, sign flips) is
written to a :class:`Notes` list that the reader returns, so that nothing is changed silently; the
CLI prints the notes.

Conventions: rows are counted from 0 over the data rows; readers that know where the data start in
the file pass ``first_line`` so messages also give the 1-based file line. Reading and parsing text
tables (:func:`parse_table`, :func:`read_text_lines`) live in :mod:`pipeline.io.text`,
:class:`Notes` in :mod:`pipeline.io.notes` and the gap filling :func:`fill_gaps` in
:mod:`pipeline.io.gaps`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.io.notes import Notes
from pipeline.io.text import FileLike, where
from pipeline.quantiles import median

__all__ = [
    "PLAUSIBLE_RATE_HZ",
    "RateInfo",
    "check_acc_units",
    "check_gyro_units",
    "check_position_units",
    "check_rate",
    "check_quaternions",
    "check_same_length",
    "check_same_rate",
    "check_time",
    "estimate_rate",
    "make_quaternions_continuous",
]

# --------------------------------------------------------------------------------------------
# time and rate


@dataclass(frozen=True)
class RateInfo:
    """Sampling rate estimated from time stamps.

    ``rate_hz = 1 / median(dt)``; ``jitter_s`` = standard deviation of ``dt``; ``max_dt_s`` the
    longest interval (a dropped-sample gap shows up there).
    """

    rate_hz: float
    dt_s: float
    jitter_s: float
    max_dt_s: float
    n_samples: int


def check_time(
    time: np.ndarray,
    *,
    file: FileLike = None,
    field: str = "time",
    first_line: int | None = None,
    min_samples: int = 2,
) -> np.ndarray:
    """Return ``time`` as a float array after checking it is finite and strictly increasing.

    Refuses: fewer than ``min_samples`` samples; non-finite values; a repeated time stamp
    (``t[r] == t[r-1]``) and an unsorted one (``t[r] < t[r-1]``), each with the first offending
    row.
    """
    t = np.asarray(time, dtype=float)
    if t.ndim != 1:
        raise InputError(f"expected a 1-D time column, got shape {t.shape}", file=file, field=field)
    if t.size < min_samples:
        raise InputError(
            f"expected at least {min_samples} samples, found {t.size}", file=file, field=field
        )
    bad = np.flatnonzero(~np.isfinite(t))
    if bad.size:
        r = int(bad[0])
        raise InputError(
            f"time stamp is not a finite number at {where(r, first_line)}", file=file, field=field
        )
    dt = np.diff(t)
    rep = np.flatnonzero(dt == 0)
    back = np.flatnonzero(dt < 0)
    if rep.size and (not back.size or rep[0] < back[0]):
        r = int(rep[0]) + 1
        raise InputError(
            f"repeated time stamp {t[r]:.6g} s at {where(r, first_line)} (same as the row before);"
            " expected strictly increasing time",
            file=file,
            field=field,
        )
    if back.size:
        r = int(back[0]) + 1
        raise InputError(
            f"time stamps not sorted: {t[r]:.6g} s at {where(r, first_line)} comes after "
            f"{t[r - 1]:.6g} s; expected strictly increasing time",
            file=file,
            field=field,
        )
    return t


def estimate_rate(time: np.ndarray) -> RateInfo:
    """Sampling rate from (already checked) time stamps: ``1 / median(diff(t))``."""
    t = np.asarray(time, dtype=float)
    dt = np.diff(t)
    med = median(dt)
    return RateInfo(
        rate_hz=1.0 / med,
        dt_s=med,
        jitter_s=float(np.std(dt)),
        max_dt_s=float(np.max(dt)),
        n_samples=int(t.size),
    )


#: Sampling rates (Hz) accepted as those of human motion capture.
PLAUSIBLE_RATE_HZ = (1.0, 10_000.0)


def check_rate(
    time: np.ndarray,
    declared_hz: float | None = None,
    *,
    rtol: float = 0.01,
    jitter_tol: float = 0.05,
    notes: Notes | None = None,
    file: FileLike = None,
    field: str = "time",
) -> RateInfo:
    """Estimate the rate from ``time`` and compare it with a declared one (e.g. .sto ``DataRate``).

    Refuses ``|rate - declared| > rtol * declared``, and a rate outside :data:`PLAUSIBLE_RATE_HZ`
    (human motion capture samples at 1 Hz to 10 kHz): time stamps in milliseconds (or
    microseconds) read as seconds give 0.01-1 Hz, and the message says so. Notes (does not
    refuse) irregular sampling: jitter (std of dt) above ``jitter_tol * dt``, or intervals longer
    than 1.5 dt (dropped samples).
    """
    info = estimate_rate(time)
    lo, hi = PLAUSIBLE_RATE_HZ
    if not lo <= info.rate_hz <= hi:
        hint = ""
        for unit, factor in (("milliseconds", 1e-3), ("microseconds", 1e-6)):
            if lo <= info.rate_hz / factor <= hi:
                hint = (f"; the time looks like {unit} (that would be "
                        f"{info.rate_hz / factor:.4g} Hz): expected seconds")
                break
        raise InputError(
            f"the time stamps give {info.rate_hz:.4g} Hz (median interval {info.dt_s:.6g}), "
            f"outside the plausible {lo:g}-{hi:g} Hz{hint}",
            file=file,
            field=field,
        )
    if declared_hz is not None:
        if not np.isfinite(declared_hz) or declared_hz <= 0:
            raise InputError(
                f"declared sampling rate must be a positive number, found {declared_hz!r}",
                file=file,
                field=field,
            )
        if abs(info.rate_hz - declared_hz) > rtol * declared_hz:
            raise InputError(
                f"declared rate {declared_hz:g} Hz but the time stamps give {info.rate_hz:.4g} Hz "
                f"(median interval {info.dt_s:.6g} s); fix the header or the time column",
                file=file,
                field=field,
            )
    if notes is not None:
        if info.jitter_s > jitter_tol * info.dt_s:
            notes.add(
                f"irregular sampling: interval {info.dt_s * 1e3:.4g} ms +- "
                f"{info.jitter_s * 1e3:.3g} ms (jitter)",
                file=file,
                field=field,
            )
        n_long = int(np.sum(np.diff(np.asarray(time, float)) > 1.5 * info.dt_s))
        if n_long:
            notes.add(
                f"{n_long} interval(s) longer than 1.5 sampling periods (dropped samples?), "
                f"longest {info.max_dt_s:.4g} s",
                file=file,
                field=field,
            )
    return info


def check_same_length(lengths: dict[str, int], *, file: FileLike = None) -> int:
    """All streams must have the same number of samples; returns it or refuses listing them."""
    values = set(lengths.values())
    if len(values) > 1:
        detail = ", ".join(f"{k}: {v}" for k, v in lengths.items())
        raise InputError(f"streams have different numbers of samples ({detail})", file=file)
    return values.pop() if values else 0


def check_same_rate(rates: dict[str, float], *, rtol: float = 0.01, file: FileLike = None) -> float:
    """All streams must share one sampling rate (within ``rtol``); returns the first one."""
    vals = list(rates.values())
    if not vals:
        raise InputError("no streams to compare", file=file)
    ref = vals[0]
    if any(abs(v - ref) > rtol * ref for v in vals):
        detail = ", ".join(f"{k}: {v:g} Hz" for k, v in rates.items())
        raise InputError(f"streams have different sampling rates ({detail})", file=file)
    return ref


# --------------------------------------------------------------------------------------------
# quaternions


def make_quaternions_continuous(q: np.ndarray) -> tuple[np.ndarray, int]:
    """Flip signs so that consecutive quaternions share a hemisphere (``q_k . q_{k-1} >= 0``).

    ``q`` and ``-q`` are the same rotation; continuity matters for interpolation and filtering.
    Returns the new array and the number of samples whose sign changed.
    """
    q = np.array(q, dtype=float, copy=True)
    if len(q) < 2:
        return q, 0
    dots = np.sum(q[1:] * q[:-1], axis=1)
    flips = np.concatenate([[1.0], np.cumprod(np.where(dots < 0, -1.0, 1.0))])
    q *= flips[:, None]
    return q, int(np.sum(flips < 0))


def check_quaternions(
    q: np.ndarray,
    *,
    norm_range: tuple[float, float] = (0.9, 1.1),
    notes: Notes | None = None,
    file: FileLike = None,
    field: str | None = None,
    first_line: int | None = None,
    note_above: float = 1e-3,
    allow_missing: bool = False,
) -> np.ndarray:
    """Check and clean scalar-first quaternions ``(N, 4)``; returns unit, sign-continuous ones.

    Refuses non-finite (unless ``allow_missing``: such rows are missing samples, kept NaN) and
    zero quaternions, and norms outside ``norm_range`` ("not unit quaternions (norm x at row
    r)"). Norms inside the range are normalised; a deviation larger than ``note_above`` is noted.
    Hemisphere flips (q -> -q) are removed and noted.
    """
    q = np.asarray(q, dtype=float)
    if q.ndim != 2 or q.shape[1] != 4:
        raise InputError(
            f"expected quaternions as an (N, 4) array, got shape {q.shape}", file=file, field=field
        )
    bad = np.flatnonzero(~np.all(np.isfinite(q), axis=1))
    if bad.size and allow_missing and bad.size < len(q):
        ok = np.all(np.isfinite(q), axis=1)
        out = np.full_like(q, np.nan)
        out[ok] = check_quaternions(q[ok], norm_range=norm_range, notes=notes, file=file,
                                    field=field, note_above=note_above)
        return out
    if bad.size:
        raise InputError(
            f"non-finite quaternion at {where(int(bad[0]), first_line)}", file=file, field=field
        )
    n = np.linalg.norm(q, axis=1)
    zero = np.flatnonzero(n < 1e-9)
    if zero.size:
        raise InputError(
            f"zero quaternion at {where(int(zero[0]), first_line)} (no rotation defined)",
            file=file,
            field=field,
        )
    lo, hi = norm_range
    out = np.flatnonzero((n < lo) | (n > hi))
    if out.size:
        r = int(out[0])
        raise InputError(
            f"not unit quaternions (norm {n[r]:.4g} at {where(r, first_line)}; "
            f"expected within [{lo:g}, {hi:g}])",
            file=file,
            field=field,
        )
    dev = np.abs(n - 1.0)
    if notes is not None and dev.max() > note_above:
        notes.add(
            f"normalised {int(np.sum(dev > note_above))} quaternion(s) with |norm - 1| up to "
            f"{dev.max():.3g}",
            file=file,
            field=field,
        )
    # q and -q are the same rotation: making the signs continuous changes no orientation, so it
    # is not reported (real files flip hemispheres hundreds of times).
    q, _ = make_quaternions_continuous(q / n[:, None])
    return q


# --------------------------------------------------------------------------------------------
# units


def check_position_units(
    points_m: np.ndarray,
    *,
    max_extent_m: float = 20.0,
    file: FileLike = None,
    field: str | None = None,
) -> None:
    """Refuse positions (metres) whose extent is implausible for human motion capture.

    Extent = largest distance of a finite point from the median point. Above ``max_extent_m``
    the values are most likely millimetres (x1000) or centimetres (x100) labelled as metres.
    """
    p = np.asarray(points_m, dtype=float).reshape(-1, 3)
    p = p[np.all(np.isfinite(p), axis=1)]
    if p.size == 0:
        return
    extent = float(np.max(np.linalg.norm(p - np.median(p, axis=0), axis=1)))
    if extent > max_extent_m:
        raise InputError(
            f"positions span {extent:.4g} m, implausible for a motion-capture volume "
            f"(expected < {max_extent_m:g} m); they look like millimetres given as metres "
            "(check the unit: divide by 1000)",
            file=file,
            field=field,
        )


def check_gyro_units(
    gyr: np.ndarray, *, limit: float = 20.0, file: FileLike = None, field: str | None = "gyr"
) -> None:
    """Refuse angular velocities that look like deg/s given as rad/s.

    Human segments rarely exceed 20 rad/s (1150 deg/s); if the 90th percentile of ``|w|`` is
    above ``limit`` the column is routinely that fast, which means degrees per second.
    """
    w = np.linalg.norm(np.asarray(gyr, dtype=float), axis=1)
    w = w[np.isfinite(w)]
    if w.size and float(np.percentile(w, 90)) > limit:
        raise InputError(
            f"angular velocity |w| is routinely above {limit:g} rad/s (90th percentile "
            f"{np.percentile(w, 90):.4g}); it looks like deg/s: expected rad/s "
            "(multiply deg/s by pi/180)",
            file=file,
            field=field,
        )


def check_acc_units(acc: np.ndarray, *, file: FileLike = None, field: str | None = "acc") -> None:
    """Refuse accelerations that look like g, or like raw counts / mm/s^2, instead of m/s^2.

    On a human-worn IMU the median of ``|a|`` is close to gravity, 9.81 m/s^2. A median within
    [0.5, 2] means the unit is g; above 100 it is not m/s^2 either.
    """
    a = np.linalg.norm(np.asarray(acc, dtype=float), axis=1)
    a = a[np.isfinite(a)]
    if not a.size:
        return
    med = float(np.median(a))
    if 0.5 <= med <= 2.0:
        raise InputError(
            f"median |a| is {med:.3g}, close to 1: the acceleration looks like it is in g; "
            "expected m/s^2 (multiply by 9.80665)",
            file=file,
            field=field,
        )
    if med > 100.0:
        raise InputError(
            f"median |a| is {med:.4g}, implausible in m/s^2 (gravity is 9.81); "
            "raw counts or mm/s^2?",
            file=file,
            field=field,
        )
