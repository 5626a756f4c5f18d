"""The one home of SO(3) helpers.

Conventions (DESIGN.md §2):

* A rotation matrix ``R`` of a segment has the segment axes as its columns, expressed in the
  world: ``p_world = R @ p_segment + t``.
* Quaternions are scalar-first ``[w, x, y, z]`` everywhere in this package. Pinocchio's
  configuration vectors (root joints) and rerun are scalar-last: :func:`quat_xyzw_from_matrix`,
  :func:`matrix_from_quat_xyzw` and :func:`quat_xyzw_integrate` are the only places the order
  changes.
* Plain NumPy, vectorised over stacks (no SciPy: ``scipy.spatial`` costs a command ~0.4 s of
  import, more than the IK of a whole trial). ``tests/test_rotations.py`` checks every map against
  SciPy's ``Rotation`` and Pinocchio's ``exp3``/``log3``.
* Every function accepts a single item (``(3,)``, ``(3, 3)``, ``(4,)``) or a stack
  (``(N, 3)``, ``(N, 3, 3)``, ``(N, 4)``) and returns the same leading shape.
* Angles are radians.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "angle_between",
    "axis_angle",
    "cross",
    "euler_xyz_fixed_from_matrix",
    "euler_zyx_from_matrix",
    "exp3",
    "log3",
    "matrix_from_euler_xyz_fixed",
    "matrix_from_euler_zyx",
    "matrix_from_quat",
    "matrix_from_quat_xyzw",
    "normalize",
    "project_to_so3",
    "quat_from_matrix",
    "quat_xyzw_from_matrix",
    "quat_xyzw_integrate",
    "rot_x",
    "rot_y",
    "rot_z",
    "rotation_aligning",
    "skew",
    "tangent_basis",
    "unwrap_angles",
]


def _stack(a: np.ndarray, item_ndim: int) -> tuple[np.ndarray, bool]:
    a = np.asarray(a, dtype=float)
    single = a.ndim == item_ndim
    return (a[None] if single else a), single


def normalize(v: np.ndarray, axis: int = -1) -> np.ndarray:
    """Unit vectors along ``axis``. Raises ``ValueError`` on a zero-length vector."""
    v = np.asarray(v, dtype=float)
    n = np.linalg.norm(v, axis=axis, keepdims=True)
    if np.any(n == 0):
        raise ValueError("cannot normalise a zero-length vector")
    return v / n


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a x b`` over the last axis (size 3) with broadcasting: ``np.cross`` by its components,
    without its axis juggling (~10x faster on the (N, 3) stacks the calibrations evaluate
    thousands of times)."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrix ``[v]x`` with ``[v]x @ u == np.cross(v, u)``."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def _elementary(axis: str, angle: np.ndarray | float) -> np.ndarray:
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros(angle.shape + (3, 3))
    i, j = {"x": (1, 2), "y": (2, 0), "z": (0, 1)}[axis]
    k = 3 - i - j
    out[..., k, k] = 1.0
    out[..., i, i], out[..., j, j] = c, c
    out[..., i, j], out[..., j, i] = -s, s
    return out


def unwrap_angles(angle: np.ndarray) -> np.ndarray:
    """A continuous copy of an angle series (N,) in radians: every jump larger than pi between
    consecutive finite samples is removed by a multiple of 2 pi (``numpy.unwrap`` over the finite
    samples; NaN stay NaN). The first finite sample keeps its value."""
    a = np.array(angle, dtype=float)
    ok = np.isfinite(a)
    if ok.sum() > 1:
        a[ok] = np.unwrap(a[ok])
    return a


def tangent_basis(v: np.ndarray) -> np.ndarray:
    """(3, 2) orthonormal basis ``[t1, t2]`` of the plane orthogonal to ``v`` (normalised here),
    with ``t1 = v x e`` (``e`` the world axis least aligned with ``v``) and ``t2 = v x t1``: the
    two-parameter tangent space of a unit axis around ``v``."""
    v = normalize(np.asarray(v, float))
    e = np.eye(3)[int(np.argmin(np.abs(v)))]
    t1 = normalize(np.cross(v, e))
    return np.stack([t1, np.cross(v, t1)], axis=1)


def rot_x(angle: np.ndarray | float) -> np.ndarray:
    """Rotation about x by ``angle`` (right-handed)."""
    return _elementary("x", angle)


def rot_y(angle: np.ndarray | float) -> np.ndarray:
    """Rotation about y by ``angle`` (right-handed)."""
    return _elementary("y", angle)


def rot_z(angle: np.ndarray | float) -> np.ndarray:
    """Rotation about z by ``angle`` (right-handed)."""
    return _elementary("z", angle)


def exp3(rotvec: np.ndarray) -> np.ndarray:
    """Exponential map so(3) -> SO(3) (Rodrigues), rotation vector = axis * angle.

    ``R = I + (sin t / t) K + ((1 - cos t) / t^2) K^2`` with ``K = [r]x``, ``t = |r|``; the two
    coefficients by their Taylor series below ``t = 1e-4`` (exact to double precision there).
    """
    r, single = _stack(rotvec, 1)
    t2 = np.einsum("ni,ni->n", r, r)
    t = np.sqrt(t2)
    small = t < 1e-4
    ts = np.where(small, 1.0, t)
    a = np.where(small, 1.0 - t2 / 6.0, np.sin(ts) / ts)
    b = np.where(small, 0.5 - t2 / 24.0, (1.0 - np.cos(ts)) / (ts * ts))
    K = skew(r)
    out = np.eye(3) + a[:, None, None] * K + b[:, None, None] * (K @ K)
    return out[0] if single else out


def log3(R: np.ndarray) -> np.ndarray:
    """Logarithm SO(3) -> rotation vector (axis * angle, angle in [0, pi]).

    Up to a quarter turn (``cos t = (tr R - 1) / 2 >= 0``) from the antisymmetric part
    ``v = vee(R - R^T) / 2 = sin t * axis``: ``r = atan2(|v|, cos t) v / |v|`` (``v / cos t`` as
    ``|v| -> 0``), accurate there; beyond, through the unit quaternion (:func:`quat_from_matrix`,
    accurate up to pi): ``r = 2 atan2(|u|, w) u / |u|``.
    """
    m, single = _stack(R, 2)
    v = 0.5 * np.stack([m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0],
                        m[:, 1, 0] - m[:, 0, 1]], axis=-1)
    c = 0.5 * (m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2] - 1.0)
    s = np.sqrt(np.einsum("ni,ni->n", v, v))
    tiny = s < 1e-12
    ss = np.where(tiny, 1.0, s)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = v * np.where(tiny, 1.0 / c, np.arctan2(ss, c) / ss)[:, None]
    wide = c < 0.0
    if wide.any():
        q = quat_from_matrix(m[wide])
        w, u = q[:, 0], q[:, 1:]
        s = np.sqrt(np.einsum("ni,ni->n", u, u))
        out[wide] = u * (2.0 * np.arctan2(s, w) / s)[:, None]  # |u| >= sin(pi/4) here
    return out[0] if single else out


def axis_angle(R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Axis (unit) and angle (>= 0) of rotation matrices; the axis of an identity is NaN."""
    rv = log3(R)
    angle = np.linalg.norm(rv, axis=-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        axis = rv / angle[..., None]
    return axis, angle


def matrix_from_quat(q: np.ndarray) -> np.ndarray:
    """Rotation matrices from scalar-first quaternions ``[w, x, y, z]``.

    Quaternions are normalised first; a zero or infinite quaternion raises ``ValueError``; NaN in,
    NaN out (a sensor's missing sample).
    """
    q, single = _stack(q, 1)
    n = np.linalg.norm(q, axis=-1)
    if np.any(np.isinf(q)) or np.any(n < 1e-12):
        raise ValueError("zero or infinite quaternion")
    w, x, y, z = (q / n[:, None]).T
    out = np.empty((q.shape[0], 3, 3))
    out[:, 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    out[:, 0, 1] = 2.0 * (x * y - w * z)
    out[:, 0, 2] = 2.0 * (x * z + w * y)
    out[:, 1, 0] = 2.0 * (x * y + w * z)
    out[:, 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    out[:, 1, 2] = 2.0 * (y * z - w * x)
    out[:, 2, 0] = 2.0 * (x * z - w * y)
    out[:, 2, 1] = 2.0 * (y * z + w * x)
    out[:, 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return out[0] if single else out


def matrix_from_quat_xyzw(q: np.ndarray) -> np.ndarray:
    """Rotation matrices from **scalar-last** quaternions ``[x, y, z, w]`` (Pinocchio's spherical
    and free-flyer configurations), normalised first."""
    q = np.asarray(q, dtype=float)
    return matrix_from_quat(q[..., [3, 0, 1, 2]])


def quat_xyzw_integrate(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``q (x) exp(v)``: scalar-last quaternions (N, 4) moved by body-frame rotation vectors
    (N, 3), then normalised: ``pin.integrate`` of a spherical joint (``R <- R exp3(v)``)."""
    q = np.asarray(q, dtype=float)
    v = np.asarray(v, dtype=float)
    half = 0.5 * np.sqrt(np.einsum("...i,...i->...", v, v))
    small = half < 1e-6
    hs = np.where(small, 1.0, half)
    k = np.where(small, 0.5 - half * half / 12.0, 0.5 * np.sin(hs) / hs)  # sin(|v|/2) / |v|
    pw, pv = np.cos(half), v * k[..., None]
    qw, qv = q[..., 3], q[..., :3]
    out = np.empty(np.broadcast_shapes(q.shape, v.shape[:-1] + (4,)))
    out[..., :3] = qw[..., None] * pv + pw[..., None] * qv + np.cross(qv, pv)
    out[..., 3] = qw * pw - np.einsum("...i,...i->...", qv, pv)
    return out / np.linalg.norm(out, axis=-1, keepdims=True)


def quat_from_matrix(R: np.ndarray) -> np.ndarray:
    """Scalar-first unit quaternions ``[w, x, y, z]`` with ``w >= 0``.

    Shepperd's method: of the four equivalent formulas, the one dividing by the largest of
    ``1 + tr R``, ``1 + 2 R_ii - tr R`` (numerically stable at every angle); NaN in, NaN out.
    """
    m, single = _stack(R, 2)
    r00, r01, r02 = m[:, 0, 0], m[:, 0, 1], m[:, 0, 2]
    r10, r11, r12 = m[:, 1, 0], m[:, 1, 1], m[:, 1, 2]
    r20, r21, r22 = m[:, 2, 0], m[:, 2, 1], m[:, 2, 2]
    tr = r00 + r11 + r22
    cand = np.stack(
        [
            np.stack([1.0 + tr, r21 - r12, r02 - r20, r10 - r01], axis=-1),
            np.stack([r21 - r12, 1.0 + r00 - r11 - r22, r01 + r10, r02 + r20], axis=-1),
            np.stack([r02 - r20, r01 + r10, 1.0 - r00 + r11 - r22, r12 + r21], axis=-1),
            np.stack([r10 - r01, r02 + r20, r12 + r21, 1.0 - r00 - r11 + r22], axis=-1),
        ],
        axis=1,
    )  # (N, 4 formulas, 4)
    pick = np.argmax(np.nan_to_num(np.stack([tr, r00, r11, r22], axis=-1), nan=0.0), axis=1)
    q = cand[np.arange(m.shape[0]), pick]
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q[q[:, 0] < 0] *= -1
    return q[0] if single else q


def quat_xyzw_from_matrix(R: np.ndarray) -> np.ndarray:
    """Unit quaternion(s) **scalar-last** ``[x, y, z, w]`` of rotation matrices, the order of
    Pinocchio's spherical/free-flyer configuration and of rerun (``w >= 0``, as
    :func:`quat_from_matrix`)."""
    return quat_from_matrix(R)[..., [1, 2, 3, 0]]


def matrix_from_euler_zyx(euler: np.ndarray) -> np.ndarray:
    """``R = Rz(e0) @ Ry(e1) @ Rx(e2)`` (MATLAB ``eul2rotm`` default order 'ZYX')."""
    e = np.asarray(euler, dtype=float)
    return rot_z(e[..., 0]) @ rot_y(e[..., 1]) @ rot_x(e[..., 2])


def euler_zyx_from_matrix(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`matrix_from_euler_zyx`: ``[z, y, x]`` angles, ``y`` in [-pi/2, pi/2].

    ``y = -asin(r20)``, ``z = atan2(r10, r00)``, ``x = atan2(r21, r22)``; at gimbal lock
    (``cos y < 1e-9``) ``x = 0`` and ``z`` takes the whole remaining rotation
    (``atan2(-r01, r11)``).
    """
    m, single = _stack(R, 2)
    y = -np.arcsin(np.clip(m[:, 2, 0], -1.0, 1.0))
    z = np.arctan2(m[:, 1, 0], m[:, 0, 0])
    x = np.arctan2(m[:, 2, 1], m[:, 2, 2])
    lock = np.hypot(m[:, 0, 0], m[:, 1, 0]) < 1e-9
    if np.any(lock):
        z = np.where(lock, np.arctan2(-m[:, 0, 1], m[:, 1, 1]), z)
        x = np.where(lock, 0.0, x)
    out = np.stack([z, y, x], axis=-1)
    return out[0] if single else out


def project_to_so3(M: np.ndarray) -> np.ndarray:
    """Nearest rotation matrix (Frobenius norm) to ``M`` via SVD, with det = +1."""
    m, single = _stack(M, 2)
    u, _, vt = np.linalg.svd(m)
    d = np.sign(np.linalg.det(u @ vt))
    u[:, :, -1] *= d[:, None]
    out = u @ vt
    return out[0] if single else out


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (rad) between vectors, numerically safe near 0 and pi."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


def rotation_aligning(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotation ``R`` with ``R @ a_hat == b_hat`` (Wang 2023 eq 10-12).

    Axis ``a x b`` (eq 11), angle ``arccos(a.b / |a||b|)`` (eq 10), matrix by Rodrigues (eq 12).
    Parallel vectors give the identity; anti-parallel vectors a half-turn about an axis
    perpendicular to ``a``.
    """
    a_hat = normalize(a)
    b_hat = normalize(b)
    axis = np.cross(a_hat, b_hat)
    s = np.linalg.norm(axis)
    angle = angle_between(a_hat, b_hat)
    if s < 1e-12:
        if angle < 1.0:
            return np.eye(3)
        perp = np.cross(a_hat, [1.0, 0.0, 0.0])
        if np.linalg.norm(perp) < 1e-6:
            perp = np.cross(a_hat, [0.0, 1.0, 0.0])
        return exp3(normalize(perp) * np.pi)
    return exp3(axis / s * angle)


def matrix_from_euler_xyz_fixed(angles: np.ndarray) -> np.ndarray:
    """Space-fixed X-Y-Z angles ``(a, b, c)``: ``R = Rz(c) @ Ry(b) @ Rx(a)`` (OpenSense's
    ``sensor_to_opensim_rotations``). Radians, ``(3,)`` or ``(N, 3)``."""
    e = np.asarray(angles, dtype=float)
    return rot_z(e[..., 2]) @ rot_y(e[..., 1]) @ rot_x(e[..., 0])


def euler_xyz_fixed_from_matrix(R: np.ndarray) -> np.ndarray:
    """Inverse of :func:`matrix_from_euler_xyz_fixed`: ``(a, b, c)``, ``b`` in [-pi/2, pi/2]
    (space-fixed X-Y-Z is body-fixed Z-Y-X read backwards)."""
    return euler_zyx_from_matrix(R)[..., ::-1]


def matrix_from_euler_zxy(euler: np.ndarray) -> np.ndarray:
    """``R = Rz(e0) @ Rx(e1) @ Ry(e2)``: the ISB / Grood & Suntay joint coordinate system order.

    Flexion about the proximal z, then ab/adduction about the floating x, then axial rotation about
    the distal y (Wu et al. 2002; Hu et al. 2021 eq 38-42). Radians, ``(3,)`` or ``(N, 3)``.
    """
    e = np.asarray(euler, dtype=float)
    return rot_z(e[..., 0]) @ rot_x(e[..., 1]) @ rot_y(e[..., 2])


def euler_zxy_from_matrix(R: np.ndarray, *, gimbal_tol: float = 1e-9) -> np.ndarray:
    """Inverse of :func:`matrix_from_euler_zxy`: ``[z, x, y]`` angles, ``x`` in [-pi/2, pi/2].

    Hu et al. 2021 eq 40-42 (1-based ``r_ij``): ``x = atan2(r32, sqrt(r12^2 + r22^2))``, computed
    as ``arcsin(r32)`` (the same angle for a rotation matrix), ``z = atan2(-r12, r22)``,
    ``y = atan2(-r31, r33)``. At gimbal lock (``cos x < gimbal_tol``)
    only ``z + y`` (``x = +pi/2``) or ``y - z`` (``x = -pi/2``) is defined: ``z = 0`` and
    ``y = atan2(r13, -r23)`` or ``atan2(r13, r23)`` (eq 41-42).
    """
    R = np.asarray(R, dtype=float)
    r = lambda i, j: R[..., i - 1, j - 1]  # noqa: E731  (1-based like the paper)
    cx = np.sqrt(r(1, 2) ** 2 + r(2, 2) ** 2)
    x = np.arcsin(np.clip(r(3, 2), -1.0, 1.0))  # eq 40
    z = np.arctan2(-r(1, 2), r(2, 2))
    y = np.arctan2(-r(3, 1), r(3, 3))
    lock = cx < gimbal_tol
    if np.any(lock):
        up = r(3, 2) > 0
        z = np.where(lock, 0.0, z)  # eq 41-42
        y = np.where(lock & up, np.arctan2(r(1, 3), -r(2, 3)), y)
        y = np.where(lock & ~up, np.arctan2(r(1, 3), r(2, 3)), y)
    return np.stack([z, x, y], axis=-1)


def rotation_aligning_with_twist(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray
) -> np.ndarray:
    """Rotation ``R`` with ``R a_hat = b_hat`` exactly whose twist about ``b`` best aligns the
    pairs ``R c_k ~ d_k`` (Wahba's problem with one exact pair).

    ``R = exp3(phi b_hat) @ rotation_aligning(a, b)`` with ``phi = atan2(sum b.(u_k x w_k),
    sum u_k.w_k)``, where ``u_k`` and ``w_k`` are ``R0 c_k`` and ``d_k`` projected onto the plane
    orthogonal to ``b`` (this maximises ``sum_k (R c_k).d_k``); ``c``, ``d``: (3,) or (K, 3).
    With ``c = I`` and ``d = R_ref^T`` it is the rotation nearest to ``R_ref`` (Frobenius norm).
    If every ``c_k`` or ``d_k`` is parallel to ``b`` the twist is undetermined and ``phi = 0``.
    """
    b_hat = normalize(b)
    R0 = rotation_aligning(a, b_hat)
    u = np.atleast_2d(np.asarray(c, dtype=float)) @ R0.T
    w = np.atleast_2d(np.asarray(d, dtype=float))
    u = u - np.outer(u @ b_hat, b_hat)
    w = w - np.outer(w @ b_hat, b_hat)
    phi = np.arctan2(np.sum(np.cross(u, w) @ b_hat), np.sum(u * w))
    return exp3(phi * b_hat) @ R0
