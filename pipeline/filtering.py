"""Zero-phase low-pass filtering of sampled signals, in NumPy (importing ``scipy.signal`` costs a
command 0.7-1.1 s).

:func:`lowpass` convolves each column with a Gaussian kernel: its response
``|H(f)| = exp(-2 pi^2 sigma^2 f^2)`` is -3 dB at ``f_c = sqrt(ln 2) / (2 pi sigma)
= 0.1325 / sigma`` (``sigma`` in s), has no overshoot and no phase lag; the ends are padded by
reflection so that a signal's level is kept there. The joint constraints of real gait use it to
keep the motion (below ~4 Hz) and leave out what a rigid-body model does not hold: soft tissue
wobbling on the segment, heel-strike impacts, sensor noise.
"""

from __future__ import annotations

import numpy as np

from pipeline.errors import InputError

__all__ = ["lowpass"]

_SIGMA_PER_CUTOFF = np.sqrt(np.log(2)) / (2 * np.pi)  # sigma * f_c: |H(f_c)| = 1 / sqrt(2)


def lowpass(x: np.ndarray, rate_hz: float, cutoff_hz: float) -> np.ndarray:
    """``x`` (N,) or (N, k) low-passed along axis 0 (module docstring): -3 dB at ``cutoff_hz``."""
    x = np.asarray(x, dtype=float)
    if not (np.isfinite(rate_hz) and rate_hz > 0 and np.isfinite(cutoff_hz) and cutoff_hz > 0):
        raise InputError(f"expected a positive rate and cut-off, got {rate_hz}, {cutoff_hz}",
                         field="cutoff_hz")
    sigma = _SIGMA_PER_CUTOFF / cutoff_hz * rate_hz  # samples
    half = int(np.ceil(4 * sigma))
    if half < 1 or x.shape[0] < 2:
        return x.copy()
    k = np.exp(-0.5 * (np.arange(-half, half + 1) / sigma) ** 2)
    k /= k.sum()
    flat = x.reshape(x.shape[0], -1)
    pad = min(half, flat.shape[0] - 1)
    padded = np.pad(flat, ((pad, pad), (0, 0)), mode="reflect")
    if pad < half:  # a signal shorter than the kernel: pad the rest with its end values
        padded = np.pad(padded, ((half - pad, half - pad), (0, 0)), mode="edge")
    out = np.stack([np.convolve(padded[:, j], k, mode="valid") for j in range(flat.shape[1])],
                   axis=1)
    return out.reshape(x.shape)
