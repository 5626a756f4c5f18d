"""The validation statistics of Wang 2023 (§II.D): RMS of the 3-D error, Pearson r and
ICC(A,1) (two-way, absolute agreement, single measures; McGraw & Wong 1996, checked on Shrout &
Fleiss' example in the tests)."""

from __future__ import annotations

import numpy as np

from pipeline.errors import InputError

__all__ = ["finite_rows", "icc_a1", "icc_a1_axes", "pearson_r", "pearson_r_axes", "rms_error",
"two_way_mean_squares"]


def finite_rows(x: np.ndarray) -> np.ndarray:
    """The rows of ``x`` (N, k) without a non-finite value."""
    return x[np.all(np.isfinite(x), axis=1)]


# --------------------------------------------------------------------------- statistics


def rms_error(e: np.ndarray) -> float:
    """RMS over time of the error norm, ``sqrt(mean_k |e^k|^2)``, over finite rows of e (N, d)."""
    e = np.asarray(e, dtype=float)
    ok = finite_rows(e[:, None] if e.ndim == 1 else e)
    if len(ok) == 0:
        return float("nan")
    return float(np.sqrt(np.mean(np.sum(ok**2, axis=1))))


def pearson_r(a: np.ndarray, b: np.ndarray) -> float:
    """Pearson correlation of two series (N,) over the samples finite in both (NaN if undefined)."""
    a = np.asarray(a, dtype=float).ravel()
    b = np.asarray(b, dtype=float).ravel()
    ok = np.isfinite(a) & np.isfinite(b)
    if ok.sum() < 2:
        return float("nan")
    a, b = a[ok] - a[ok].mean(), b[ok] - b[ok].mean()
    den = np.sqrt((a * a).sum() * (b * b).sum())
    return float((a * b).sum() / den) if den > 0 else float("nan")


def pearson_r_axes(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-axis Pearson r of two trajectories (N, d) -> (d,)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.array([pearson_r(a[:, j], b[:, j]) for j in range(a.shape[1])])


def two_way_mean_squares(y: np.ndarray) -> tuple[float, float, float]:
    """Two-way ANOVA mean squares of ``y`` (n targets x k raters), rows with NaN dropped.

    Returns ``(MSR, MSC, MSE)``: between targets ``k sum_i (ybar_i. - ybar)^2 / (n-1)``, between
    raters ``n sum_j (ybar_.j - ybar)^2 / (k-1)``, residual ``SSE / ((n-1)(k-1))`` with
    ``SSE = SST - SSR - SSC`` (Shrout & Fleiss 1979 BMS, JMS, EMS).
    """
    y = np.asarray(y, dtype=float)
    if y.ndim != 2 or y.shape[1] < 2:
        raise InputError(f"expected an (n targets, k >= 2 raters) table, got shape {y.shape}")
    y = finite_rows(y)
    n, k = y.shape
    if n < 2:
        raise InputError(f"need at least 2 complete targets for an ICC, got {n}")
    gm = y.mean()
    ssr = k * np.sum((y.mean(axis=1) - gm) ** 2)
    ssc = n * np.sum((y.mean(axis=0) - gm) ** 2)
    sse = np.sum((y - gm) ** 2) - ssr - ssc
    return float(ssr / (n - 1)), float(ssc / (k - 1)), float(sse / ((n - 1) * (k - 1)))


def icc_a1(y: np.ndarray) -> float:
    """ICC(A,1): two-way, absolute agreement, single measures (McGraw & Wong 1996).

    ``ICC = (MSR - MSE) / (MSR + (k-1) MSE + k (MSC - MSE) / n)`` on an (n targets x k raters)
    table; identical to Shrout & Fleiss (1979) ICC(2,1). A constant offset between raters raises
    MSC and lowers the ICC although the Pearson r is unchanged. NaN if the denominator is 0.
    """
    y = np.asarray(y, dtype=float)
    msr, msc, mse = two_way_mean_squares(y)
    n, k = finite_rows(y).shape
    den = msr + (k - 1) * mse + k * (msc - mse) / n
    return float((msr - mse) / den) if den > 0 else float("nan")


def icc_a1_axes(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-axis ICC(A,1) between two trajectories (N, d): targets = time frames, raters = 2."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    return np.array([icc_a1(np.column_stack([a[:, j], b[:, j]])) for j in range(a.shape[1])])
