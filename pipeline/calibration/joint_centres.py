"""A joint's centre in both sensors' frames from their signals and orientations in one world.

Hu 2021 eq 2: the specific force at a joint's centre, ``a_S + Gamma_S(o_S)`` with
``Gamma_S(o) = w_S x (w_S x o) + dw_S x o`` (:mod:`pipeline.calibration.joint_constraints`), is
one physical vector seen by the two sensors. Eq 1-3 compare its norms (orientations unknown);
with both sensors' orientations in one world the whole vector must agree,

    R_1 (a_1 + Gamma_1 o_1) = R_2 (a_2 + Gamma_2 o_2),                            (1)

three equations per sample, linear in ``(o_1, o_2)``:

    [R_1 G_1, -R_2 G_2] [o_1; o_2] = R_2 a_2 - R_1 a_1,  G = [w]x^2 + [dw]x,      (2)

solved by least squares over the samples (Seel et al. 2012 use the norm form; the vector form is
Crabolu et al. 2017's, J Biomech 57:1-8). On real gait the signals are low-passed first
(:func:`pipeline.filtering.lowpass`, :data:`CUTOFF_HZ`): a rigid-body model does not hold what
soft tissue and heel strikes add above it. On the real walk ``gaittoolbox_s02`` (vendor
orientations, headings aligned) the residual of (2) at the knees and ankles is 1.8-2.9 m/s^2
unfiltered, 0.5-1.8 at 8 Hz, 0.3-1.0 at 4 Hz, and the distance between the knee's and the
ankle's centre in the shank sensor (the tibia's length) 0.34-0.39 m, 0.38-0.41 m and
0.415-0.434 m (the optical system's tibia: 0.432 m). The orientations' headings must agree (a
6-D filter's must be aligned first, :mod:`pipeline.process.heading_alignment`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.calibration.joint_constraints import angular_acceleration
from pipeline.errors import InputError
from pipeline.filtering import lowpass
from pipeline.rotations import skew

__all__ = ["CUTOFF_HZ", "JointCentre", "joint_centre"]

#: Low-pass cut-off of the gyroscope and accelerometer signals (Hz).
CUTOFF_HZ = 4.0


@dataclass(frozen=True)
class JointCentre:
    """``o_1``, ``o_2``: the centre in each sensor's frame (m, sensor -> centre); ``residual``:
    RMS of (2) (m/s^2); ``conditioning``: the ratio of the smallest to the largest singular value
    of (2)'s matrix (small: some direction is not determined by the motion); ``weakest``: that
    direction, ``(d_1, d_2)`` (3,) each, the move of ``o_1`` and ``o_2`` it stands for (for a
    hinge: both centres along its axis)."""

    o_1: np.ndarray
    o_2: np.ndarray
    residual: float
    conditioning: float
    weakest: tuple[np.ndarray, np.ndarray]


def _gamma_matrices(time: np.ndarray, gyr: np.ndarray) -> np.ndarray:
    w, dw = gyr, angular_acceleration(time, gyr)
    W = skew(w)
    return W @ W + skew(dw)


def joint_centre(
    time: np.ndarray,
    gyr_1: np.ndarray,
    acc_1: np.ndarray,
    R_1: np.ndarray,
    gyr_2: np.ndarray,
    acc_2: np.ndarray,
    R_2: np.ndarray,
    *,
    rows: np.ndarray | slice = slice(None),
    cutoff_hz: float = CUTOFF_HZ,
    shared_axis: int | None = None,
) -> JointCentre:
    """Eq (2) of the module docstring on the samples ``rows`` (the signals are filtered over the
    whole trial first): gyroscopes (rad/s) and accelerometers (m/s^2) in the sensor frames,
    orientations ``R_i`` (N, 3, 3) sensor -> world (one world). ``shared_axis``: the index of
    the one world axis the two orientations share (the vertical of two attitude filters whose
    headings differ): only (2)'s component along it is used, one equation per sample, which
    any turn of either world about that axis leaves exact (the residual is then that
    component's RMS)."""
    t = np.asarray(time, dtype=float)
    rate = 1.0 / float(np.median(np.diff(t)))
    g1, a1 = lowpass(gyr_1, rate, cutoff_hz), lowpass(acc_1, rate, cutoff_hz)
    g2, a2 = lowpass(gyr_2, rate, cutoff_hz), lowpass(acc_2, rate, cutoff_hz)
    G1, G2 = _gamma_matrices(t, g1)[rows], _gamma_matrices(t, g2)[rows]
    R1, R2 = np.asarray(R_1, float)[rows], np.asarray(R_2, float)[rows]
    A = np.concatenate([R1 @ G1, -(R2 @ G2)], axis=2)
    y = np.einsum("nij,nj->ni", R2, a2[rows]) - np.einsum("nij,nj->ni", R1, a1[rows])
    if shared_axis is not None:
        A, y = A[:, shared_axis : shared_axis + 1], y[:, shared_axis]
    A, y = A.reshape(-1, 6), y.ravel()
    ok = np.isfinite(y) & np.all(np.isfinite(A), axis=1)
    if ok.sum() < 30:
        raise InputError("too few samples to locate the joint's centre", field="time")
    x, *_ = np.linalg.lstsq(A[ok], y[ok], rcond=None)
    _, s, Vt = np.linalg.svd(A[ok], full_matrices=False)
    res = A[ok] @ x - y[ok]
    per_sample = 3 if shared_axis is None else 1  # components of (2) per sample
    return JointCentre(x[:3], x[3:], float(np.sqrt(np.mean(res**2) * per_sample)),
                       float(s[-1] / s[0]),
                       (Vt[-1, :3], Vt[-1, 3:]))
