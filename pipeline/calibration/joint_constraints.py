"""Joint constraints between two IMUs (Hu et al. 2021 §2, after Seel et al. 2012).

Sign convention for positions. ``o_S`` is the joint centre in the frame of sensor ``S`` (the
vector sensor -> joint). Hu's ``V_{J,S}`` points from the joint to the sensor, ``V = -o``; since
``Gamma`` is linear in its argument, eq 1-3 read with ``o``:

* eq 2: ``Gamma_S(o) = w_S x (w_S x o) + dw_S x o``  (``a_S + Gamma_S(o_S)`` is the specific
  force at the joint centre, the same physical vector seen from both sensors);
* eq 1/3: ``e(t) = |a_1 + Gamma_1(o_1)| - |a_2 + Gamma_2(o_2)|``;
* eq 9: ``de/do_S = +- (a_S + Gamma_S)^T / |a_S + Gamma_S| ([w]x[w]x + [dw]x)`` (+ for sensor 1).

Hinge (eq 4-6): ``e(t) = |w_1 x j_1| - |w_2 x j_2|`` with ``j_S`` the unit axis in sensor ``S``;
eq 14 (its denominator is misprinted as squared): ``d|w x j|/dj = ((w x j) x w)^T / |w x j|``.
Eq 5 (its third component is misprinted as ``sin(theta)``): ``j = [cos p cos t, cos p sin t,
sin p]`` with pitch ``p`` and yaw ``t``. Eq 16 moves the hinge positions along the axis so that
``j_1.o_1 + j_2.o_2 = 0`` (the position along a hinge axis is undetermined).

The angular acceleration ``dw`` comes from the gyro by a Savitzky-Golay derivative (local cubic
fit, 0.11 s window at 100 Hz), which low-passes before differencing: raw 5-point differences
amplify gyro noise and floor the joint positions at 1-3 mm (DESIGN.md §8).
Observability (:func:`observability`) inspects the singular values of the Jacobian in tangent
coordinates at the solution and names the parameter blocks that the data do not determine.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import cross, matrix_from_quat, normalize, skew

__all__ = [
    "JointData",
    "angular_acceleration",
    "axis_from_spherical",
    "consistent_axis_signs",
    "joint_force",
    "gamma",
    "hinge_jacobian",
    "hinge_jacobian_spherical",
    "hinge_residual",
    "joint_data",
    "project_hinge_positions",
    "spherical_from_axis",
    "spherical_jacobian",
    "spherical_residual",
]


@dataclass(frozen=True)
class JointData:
    """Gyro ``gyr_*``, accelerometer ``acc_*`` and angular acceleration ``gyr_dot_*`` (N,3) of two
    sensors in their own frames, on one time base."""

    gyr_1: np.ndarray
    gyr_2: np.ndarray
    acc_1: np.ndarray
    acc_2: np.ndarray
    gyr_dot_1: np.ndarray
    gyr_dot_2: np.ndarray


def angular_acceleration(
    time: np.ndarray, gyr: np.ndarray, *, window_s: float = 0.11, polyorder: int = 3
) -> np.ndarray:
    """``dw/dt`` by a Savitzky-Golay derivative over ``window_s`` seconds (odd sample count)."""
    t = np.asarray(time, dtype=float)
    dt = np.diff(t)
    if t.size < 7 or np.any(dt <= 0) or np.ptp(dt) > 1e-3 * dt.mean():
        raise InputError("expected >= 7 uniformly sampled, increasing times", field="time")
    h = float(dt.mean())
    win = max(polyorder + 2, int(round(window_s / h)) | 1)
    if win > t.size:
        raise InputError(f"expected at least {win} samples ({window_s:g} s) for the angular "
                         f"acceleration, got {t.size}", field="time")
    return savgol_derivative(np.asarray(gyr, float), win, polyorder, h)


def savgol_derivative(y: np.ndarray, window: int, polyorder: int, delta: float) -> np.ndarray:
    """First derivative along axis 0 by Savitzky-Golay local least-squares polynomials.

    What ``scipy.signal.savgol_filter(y, window, polyorder, deriv=1, delta=delta, axis=0)``
    returns (its default ``mode='interp'``; the tests compare them): inside, the derivative at
    the centre of the polynomial of degree ``polyorder`` fitted to the ``window`` (odd) samples
    around each one, ``sum_i w_i y_{n+i} / delta`` with ``w`` the row of ``pinv(V)`` (``V`` the
    window's Vandermonde matrix) that gives the linear coefficient; within half a window of either
    end, the derivative of the polynomial fitted to the first (last) window, at each sample.
    Written here because importing ``scipy.signal`` costs a command 0.7-1.1 s.
    """
    y = np.asarray(y, dtype=float)
    n, m = y.shape[0], window // 2
    if window % 2 != 1 or window > n or polyorder >= window:
        raise InputError(f"expected an odd window <= {n} samples above the degree {polyorder}, "
                         f"got {window}", field="window")
    x = np.arange(-m, m + 1, dtype=float)
    P = np.linalg.pinv(np.vander(x, polyorder + 1, increasing=True))  # samples -> coefficients
    k = np.arange(polyorder + 1, dtype=float)

    def slopes(at: np.ndarray) -> np.ndarray:  # (len(at), window): d/dx of the fit at ``at``
        powers = np.where(k > 0, at[:, None] ** np.maximum(k - 1, 0), 0.0)
        return (k * powers) @ P / delta

    out = np.empty_like(y)
    windows = np.lib.stride_tricks.sliding_window_view(y, window, axis=0)  # (n-w+1, ..., w)
    out[m : n - m] = windows @ slopes(np.zeros(1))[0]
    out[:m] = np.tensordot(slopes(x[:m]), y[:window], axes=1)
    out[n - m :] = np.tensordot(slopes(x[m + 1 :]), y[n - window :], axes=1)
    return out


def joint_data(time, gyr_1, acc_1, gyr_2, acc_2, *, window_s: float = 0.11) -> JointData:
    """Two sensors' signals with filtered angular accelerations (:func:`angular_acceleration`)."""
    arrs = [np.asarray(a, dtype=float) for a in (gyr_1, acc_1, gyr_2, acc_2)]
    n = np.asarray(time).size
    for name, a in zip(("gyr_1", "acc_1", "gyr_2", "acc_2"), arrs, strict=True):
        if a.shape != (n, 3):
            raise InputError(f"expected shape ({n}, 3), got {a.shape}", field=name)
    return JointData(
        gyr_1=arrs[0],
        gyr_2=arrs[2],
        acc_1=arrs[1],
        acc_2=arrs[3],
        gyr_dot_1=angular_acceleration(time, arrs[0], window_s=window_s),
        gyr_dot_2=angular_acceleration(time, arrs[2], window_s=window_s),
    )


def gamma(w: np.ndarray, dw: np.ndarray, o: np.ndarray) -> np.ndarray:
    """Eq 2: ``Gamma(o) = w x (w x o) + dw x o`` for (N,3) ``w``, ``dw`` and a (3,) ``o``."""
    return cross(w, cross(w, o)) + cross(dw, o)


def joint_force(d: JointData, o1: np.ndarray, o2: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq 2: the specific force at the joint centre in each sensor's frame, ``a_i + Gamma_i(o_i)``
    (N, 3) m/s^2, for sensor -> joint positions ``o1``, ``o2``."""
    f1 = d.acc_1 + gamma(d.gyr_1, d.gyr_dot_1, o1)
    f2 = d.acc_2 + gamma(d.gyr_2, d.gyr_dot_2, o2)
    return f1, f2


def spherical_residual(o1: np.ndarray, o2: np.ndarray, data: JointData) -> np.ndarray:
    """Eq 3: ``e(t) = |a_1 + Gamma_1(o_1)| - |a_2 + Gamma_2(o_2)|`` (N,) in m/s^2."""
    f1, f2 = joint_force(data, o1, o2)
    return np.linalg.norm(f1, axis=1) - np.linalg.norm(f2, axis=1)


def gamma_matrix(w: np.ndarray, dw: np.ndarray) -> np.ndarray:
    """``K`` with ``Gamma(o) = K o``: ``[w]x [w]x + [dw]x`` (eq 10), (N,3,3)."""
    W = skew(w)
    return W @ W + skew(dw)


def spherical_jacobian(o1: np.ndarray, o2: np.ndarray, data: JointData) -> np.ndarray:
    """Eq 8-9: ``de/d[o_1, o_2]`` (N,6)."""
    f1, f2 = joint_force(data, o1, o2)
    u1 = f1 / np.linalg.norm(f1, axis=1, keepdims=True)
    u2 = f2 / np.linalg.norm(f2, axis=1, keepdims=True)
    J1 = np.einsum("ni,nij->nj", u1, gamma_matrix(data.gyr_1, data.gyr_dot_1))
    J2 = np.einsum("ni,nij->nj", u2, gamma_matrix(data.gyr_2, data.gyr_dot_2))
    return np.hstack([J1, -J2])


def hinge_residual(
    j1: np.ndarray, j2: np.ndarray, gyr_1: np.ndarray, gyr_2: np.ndarray
) -> np.ndarray:
    """Eq 6: ``e(t) = |w_1 x j_1| - |w_2 x j_2|`` (N,) in rad/s."""
    return np.linalg.norm(cross(gyr_1, j1), axis=1) - np.linalg.norm(cross(gyr_2, j2), axis=1)


def _norm_cross_grad(w: np.ndarray, j: np.ndarray) -> np.ndarray:
    c = cross(w, j)
    n = np.maximum(np.linalg.norm(c, axis=1, keepdims=True), 1e-12)
    return cross(c, w) / n


def hinge_jacobian(j1: np.ndarray, j2: np.ndarray, gyr_1, gyr_2) -> np.ndarray:
    """Eq 13-14: ``de/d[j_1, j_2]`` (N,6) for Cartesian axes."""
    return np.hstack([_norm_cross_grad(gyr_1, j1), -_norm_cross_grad(gyr_2, j2)])


def axis_from_spherical(pitch: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """Eq 5 (corrected): ``[cos p cos y, cos p sin y, sin p]``."""
    p, y = np.asarray(pitch, float), np.asarray(yaw, float)
    return np.stack([np.cos(p) * np.cos(y), np.cos(p) * np.sin(y), np.sin(p)], axis=-1)


def spherical_from_axis(j: np.ndarray) -> tuple[float, float]:
    """Inverse of :func:`axis_from_spherical`: ``(pitch, yaw)``."""
    j = normalize(np.asarray(j, float))
    return float(np.arcsin(np.clip(j[2], -1, 1))), float(np.arctan2(j[1], j[0]))


def _daxis(p: float, y: float) -> np.ndarray:
    """``[dj/dp, dj/dy]`` (3,2)."""
    return np.array(
        [
            [-np.sin(p) * np.cos(y), -np.cos(p) * np.sin(y)],
            [-np.sin(p) * np.sin(y), np.cos(p) * np.cos(y)],
            [np.cos(p), 0.0],
        ]
    )


def hinge_jacobian_spherical(x: np.ndarray, gyr_1, gyr_2) -> np.ndarray:
    """``de/d[p_1, y_1, p_2, y_2]`` (N,4): eq 13-14 chained with eq 5 (eq 12's parameters)."""
    j1, j2 = axis_from_spherical(x[0], x[1]), axis_from_spherical(x[2], x[3])
    J = hinge_jacobian(j1, j2, gyr_1, gyr_2)
    return np.hstack([J[:, :3] @ _daxis(x[0], x[1]), J[:, 3:] @ _daxis(x[2], x[3])])


def project_hinge_positions(o1, o2, j1, j2) -> tuple[np.ndarray, np.ndarray]:
    """Eq 16: shift both positions along the (sign-consistent) axis by ``s = (j1.o1 + j2.o2)/2``
    so that ``j1.o1 + j2.o2 = 0``: the point of the axis midway between the two sensors."""
    s = 0.5 * (np.dot(j1, o1) + np.dot(j2, o2))
    return np.asarray(o1) - s * np.asarray(j1), np.asarray(o2) - s * np.asarray(j2)


def consistent_axis_signs(
    j1: np.ndarray,
    j2: np.ndarray,
    *,
    quat_1: np.ndarray | None = None,
    quat_2: np.ndarray | None = None,
    data: JointData | None = None,
    o1: np.ndarray | None = None,
    o2: np.ndarray | None = None,
    reference_1: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Flip ``j2`` so that both axes are the same physical direction, and both so that ``j1``
    points along ``reference_1`` (e.g. the subject's right in sensor 1, if known).

    Eq 4 is blind to both signs. With sensor orientations (wxyz, sensor -> world) the test is
    ``mean((R_1 j_1).(R_2 j_2)) > 0``. Otherwise, the specific force at the joint centre ``f``
    (eq 2, needs ``data`` and positions) is one physical vector, so ``j_1.f_1 = j_2.f_2`` for
    consistent signs: the sign of ``sum (j_1.f_1)(j_2.f_2)`` decides.
    Without a reference, ``j1``'s largest-magnitude component is made positive.
    """
    j1, j2 = np.asarray(j1, float), np.asarray(j2, float)
    if quat_1 is not None and quat_2 is not None:
        s = np.mean(
            np.einsum("nij,j,nik,k->n", matrix_from_quat(quat_1), j1, matrix_from_quat(quat_2), j2)
        )
    elif data is not None:
        z = np.zeros(3)
        f1, f2 = joint_force(data, z if o1 is None else o1, z if o2 is None else o2)
        s = np.sum((f1 @ j1) * (f2 @ j2))
    else:
        raise InputError("need sensor orientations or signals to fix the axis signs")
    if s < 0:
        j2 = -j2
    ref = np.eye(3)[np.argmax(np.abs(j1))] if reference_1 is None else reference_1
    if np.dot(j1, ref) < 0:
        j1, j2 = -j1, -j2
    return j1, j2
