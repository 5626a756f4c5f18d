"""Medians and quantiles of 1-D samples, as NumPy computes them (``method="linear"``), by
``np.partition``.

NumPy's ``median``, ``quantile`` and ``percentile`` import ``numpy.ma`` on their first call
(~9 ms), which a short command pays on its critical path; these give the same values (tested)
without it. For finite 1-D data; NaN-aware variants skip non-finite samples.
"""

from __future__ import annotations

import numpy as np

__all__ = ["median", "nanmedian", "quantile"]


def quantile(x: np.ndarray, q: float) -> float:
    """The ``q``-quantile (0 <= q <= 1) of finite samples ``x`` (at least one), linear
    interpolation between the order statistics around ``q (n - 1)`` (NumPy's default, with its
    ``_lerp``: ``a + (b - a) t``, or ``b - (b - a) (1 - t)`` for ``t >= 0.5``)."""
    x = np.asarray(x, dtype=float).ravel()
    if not x.size:
        raise ValueError("quantile of no samples")
    if not 0.0 <= q <= 1.0:
        raise ValueError(f"q must be in [0, 1], got {q}")
    pos = q * (x.size - 1)
    lo = int(np.floor(pos))
    hi = min(lo + 1, x.size - 1)
    part = np.partition(x, [lo, hi] if hi != lo else lo)
    a, b, t = float(part[lo]), float(part[hi]), pos - lo
    return b - (b - a) * (1.0 - t) if t >= 0.5 else a + (b - a) * t


def median(x: np.ndarray) -> float:
    """The median of finite samples ``x`` (``np.median``: the mean of the two middle ones for an
    even count)."""
    x = np.asarray(x, dtype=float).ravel()
    n = x.size
    if not n:
        raise ValueError("median of no samples")
    k = n // 2
    if n % 2:
        return float(np.partition(x, k)[k])
    part = np.partition(x, [k - 1, k])
    return float((part[k - 1] + part[k]) / 2)


def nanmedian(x: np.ndarray) -> float:
    """The median of the finite samples of ``x`` (NaN if there are none)."""
    x = np.asarray(x, dtype=float).ravel()
    x = x[np.isfinite(x)]
    return median(x) if x.size else float("nan")
