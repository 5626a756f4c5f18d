"""Forward kinematics of a ``pin.Model`` as a CasADi expression graph (DESIGN.md §4, option b).

The PyPI ``pin`` wheel has no ``pinocchio.casadi``, so the graph is generated here from the model
itself; no dimension is copied by hand. For every joint ``j`` (parent ``λ(j)``):

    oMi[j] = oMi[λ(j)] · jointPlacements[j] · M_j(q_j),      oMi[0] = identity,

and for every frame ``f`` attached to joint ``i = frames[f].parentJoint``:

    oMf[f] = oMi[i] · frames[f].placement,

with ``M = (R, p)`` composed as ``(R_a R_b, R_a p_b + p_a)``; these are the recursions of
``pinocchio.forwardKinematics`` / ``updateFramePlacements``. Joint transforms ``M_j(q_j)``:

* revolute about a unit axis ``a`` (``JointModelRX/RY/RZ``: the coordinate axis;
  ``JointModelRevoluteUnaligned``: ``a`` read from the joint model):
  ``R = I + sin q [a]x + (1 - cos q) [a]x²`` (Rodrigues), ``p = 0``;
* unbounded revolute (``JointModelRUBX/Y/Z``, ``RevoluteUnboundedUnaligned``), ``q = (cos, sin)``:
  the same formula with ``cos q``, ``sin q`` replaced by the two coordinates, as Pinocchio does;
* prismatic (``JointModelPX/PY/PZ``, ``PrismaticUnaligned``): ``R = I``, ``p = q a``;
* free flyer, ``q = (x, y, z, qx, qy, qz, qw)``, and spherical, ``q = (qx, qy, qz, qw)``
  (Pinocchio's scalar-last order): ``R`` from the quaternion by the formula Eigen uses
  (``1 - 2(y² + z²)``, ...), which assumes a unit quaternion exactly as Pinocchio does (a
  non-unit ``q`` gives the same non-orthogonal matrix in both).

Any other joint type raises ``NotImplementedError``. Expressions are built once in ``SX`` on a
symbol ``q`` and wrapped in ``casadi.Function`` objects, so they can be called with ``SX``,
``MX`` or numbers and differentiated exactly (first and second order).

The module also holds the symbolic SO(3) helpers used by the CasADi formulations
(:func:`skew_sym`, :func:`axis_rotation_sym`, :func:`exp3_sym`, :func:`matrix_from_quat_xyzw_sym`);
they work on ``SX``, ``MX`` and ``DM`` alike. The NumPy versions live in :mod:`pipeline.rotations`.
"""

from __future__ import annotations

from collections.abc import Sequence

import casadi as ca
import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.model.skeleton import frame_ids

__all__ = [
    "CasadiKinematics",
    "axis_rotation_sym",
    "exp3_sym",
    "matrix_from_quat_xyzw_sym",
    "skew_sym",
]

_UNIT = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}
#: Below this squared angle :func:`exp3_sym` uses its Taylor series (error < 1e-20).
_SMALL_ANGLE_SQ = 1e-8


# --------------------------------------------------------------------------------------------
# symbolic SO(3) helpers


def skew_sym(v: ca.SX | ca.MX) -> ca.SX | ca.MX:
    """Cross-product matrix ``[v]x`` of a 3-vector (SX, MX or DM)."""
    return ca.vertcat(
        ca.horzcat(0, -v[2], v[1]),
        ca.horzcat(v[2], 0, -v[0]),
        ca.horzcat(-v[1], v[0], 0),
    )


def axis_rotation_sym(
    axis: Sequence[float], cos_q: ca.SX | ca.MX, sin_q: ca.SX | ca.MX
) -> ca.SX | ca.MX:
    """Rotation about a constant unit ``axis``: ``I + sin q [a]x + (1 - cos q) [a]x²``."""
    a = np.asarray(axis, dtype=float)
    K = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return ca.DM.eye(3) + sin_q * ca.DM(K) + (1 - cos_q) * ca.DM(K @ K)


def exp3_sym(w: ca.SX | ca.MX) -> ca.SX | ca.MX:
    """Exponential map so(3) -> SO(3) of a symbolic rotation vector, smooth at ``w = 0``.

    ``exp([w]x) = I + A [w]x + B [w]x²`` with ``A = sin t / t``, ``B = (1 - cos t) / t²``,
    ``t = |w|``; for ``t² < 1e-8`` the series ``A = 1 - t²/6 + t⁴/120``, ``B = 1/2 - t²/24 +
    t⁴/720`` is used (the other branch is evaluated at a dummy ``t = 1`` there, so neither value
    nor derivative is ever NaN).
    """
    t2 = ca.dot(w, w)
    small = t2 < _SMALL_ANGLE_SQ
    t = ca.sqrt(ca.if_else(small, 1.0, t2))
    A = ca.if_else(small, 1 - t2 / 6 + t2**2 / 120, ca.sin(t) / t)
    B = ca.if_else(small, 0.5 - t2 / 24 + t2**2 / 720, (1 - ca.cos(t)) / t**2)
    K = skew_sym(w)
    return ca.DM.eye(3) + A * K + B * ca.mtimes(K, K)


def matrix_from_quat_xyzw_sym(q: ca.SX | ca.MX) -> ca.SX | ca.MX:
    """Rotation matrix of a quaternion in Pinocchio's order ``(x, y, z, w)`` (Eigen's formula)."""
    x, y, z, w = q[0], q[1], q[2], q[3]
    return ca.vertcat(
        ca.horzcat(1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
        ca.horzcat(2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
        ca.horzcat(2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
    )


# --------------------------------------------------------------------------------------------
# joint transforms


def _joint_axis(jm) -> tuple[str, np.ndarray] | None:
    """``(kind, axis)`` for revolute / unbounded / prismatic joints, ``None`` otherwise."""
    name = jm.shortname()
    for prefix, kind in (("JointModelRUB", "unbounded"), ("JointModelR", "revolute")):
        if name in (prefix + "X", prefix + "Y", prefix + "Z"):
            return kind, np.array(_UNIT[name[-1]])
    if name in ("JointModelPX", "JointModelPY", "JointModelPZ"):
        return "prismatic", np.array(_UNIT[name[-1]])
    unaligned = {
        "JointModelRevoluteUnaligned": "revolute",
        "JointModelRevoluteUnboundedUnaligned": "unbounded",
        "JointModelPrismaticUnaligned": "prismatic",
    }
    if name in unaligned:
        axis = np.asarray(jm.extract().axis, dtype=float).reshape(3)
        return unaligned[name], axis / np.linalg.norm(axis)
    return None


def _joint_transform(jm, qj) -> tuple[ca.SX, ca.SX]:
    """``(R, p)`` of the joint's motion ``M_j(q_j)`` (module docstring)."""
    name = jm.shortname()
    axis = _joint_axis(jm)
    zero = ca.SX.zeros(3, 1)
    if axis is not None:
        kind, a = axis
        if kind == "revolute":
            return axis_rotation_sym(a, ca.cos(qj[0]), ca.sin(qj[0])), zero
        if kind == "unbounded":
            return axis_rotation_sym(a, qj[0], qj[1]), zero
        return ca.SX.eye(3), qj[0] * ca.DM(a)
    if name == "JointModelFreeFlyer":
        return matrix_from_quat_xyzw_sym(qj[3:7]), qj[0:3]
    if name == "JointModelSpherical":
        return matrix_from_quat_xyzw_sym(qj[0:4]), zero
    raise NotImplementedError(
        f"CasadiKinematics supports revolute, unbounded revolute, prismatic, free-flyer and "
        f"spherical joints; got {name}"
    )


def _se3(M: pin.SE3) -> tuple[ca.DM, ca.DM]:
    return ca.DM(np.asarray(M.rotation)), ca.DM(np.asarray(M.translation).reshape(3, 1))


def _compose(a, b):
    (Ra, pa), (Rb, pb) = a, b
    return ca.mtimes(Ra, Rb), ca.mtimes(Ra, pb) + pa


# --------------------------------------------------------------------------------------------
# the kinematics object


class CasadiKinematics:
    """Symbolic forward kinematics of every joint and frame of a ``pin.Model``.

    ``frame_rotation(name, q)`` / ``frame_position(name, q)`` / ``frame_placement(name, q)`` return
    CasADi expressions of whatever ``q`` is (SX, MX, DM or a NumPy vector of length ``nq``);
    ``function(frames)`` returns a ``casadi.Function`` ``q -> (R_0, p_0, R_1, p_1, ...)``.
    Frame names resolve like :class:`pipeline.model.Skeleton` (a BODY frame wins over a joint or
    fixed-joint frame of the same name); integer frame ids are accepted too.
    """

    def __init__(self, model: pin.Model) -> None:
        self.model = model
        self.nq = int(model.nq)
        self.q = ca.SX.sym("q", self.nq)
        placements: list[tuple] = [(ca.SX.eye(3), ca.SX.zeros(3, 1))]
        for j in range(1, model.njoints):
            jm = model.joints[j]
            qj = self.q[jm.idx_q : jm.idx_q + jm.nq]
            parent = placements[model.parents[j]]
            M = _compose(parent, _se3(model.jointPlacements[j]))
            placements.append(_compose(M, _joint_transform(jm, qj)))
        self._joints = placements
        self._frames = [
            _compose(placements[f.parentJoint], _se3(f.placement)) for f in model.frames
        ]
        self._frame_ids = frame_ids(model)
        self._cache: dict[int, ca.Function] = {}

    # ---- names --------------------------------------------------------------------------------
    @property
    def frame_names(self) -> list[str]:
        """Names of all frames, in model order (duplicates kept)."""
        return [f.name for f in self.model.frames]

    def frame_id(self, frame: str | int) -> int:
        """Frame index of a name (BODY frame preferred) or an index."""
        if isinstance(frame, (int, np.integer)):
            if not 0 <= int(frame) < len(self._frames):
                raise InputError(
                    f"expected a frame index in [0, {len(self._frames)}), got {frame}",
                    field="frame",
                )
            return int(frame)
        try:
            return self._frame_ids[frame]
        except KeyError:
            msg = f"expected a frame of the model, got {frame!r}"
            raise InputError(msg, field="frame") from None

    # ---- expressions --------------------------------------------------------------------------
    def _frame_function(self, fid: int) -> ca.Function:
        if fid not in self._cache:
            R, p = self._frames[fid]
            name = f"oMf_{fid}"
            self._cache[fid] = ca.Function(name, [self.q], [R, p], ["q"], ["R", "p"])
        return self._cache[fid]

    def frame_placement(self, frame: str | int, q) -> tuple:
        """World rotation (3x3, frame axes as columns) and position (3x1) of a frame at ``q``."""
        out = self._frame_function(self.frame_id(frame))(q)
        return out[0], out[1]

    def frame_rotation(self, frame: str | int, q: ca.SX | ca.MX | np.ndarray) -> ca.SX | ca.MX:
        """World rotation (3x3) of a frame at ``q``."""
        return self.frame_placement(frame, q)[0]

    def frame_position(self, frame: str | int, q: ca.SX | ca.MX | np.ndarray) -> ca.SX | ca.MX:
        """World position (3x1) of a frame's origin at ``q``."""
        return self.frame_placement(frame, q)[1]

    def joint_placement(self, joint: str | int, q) -> tuple:
        """World ``(R, p)`` of a joint frame (``oMi``) at ``q``; ``joint`` is a name or an index."""
        j = self.model.getJointId(joint) if isinstance(joint, str) else int(joint)
        if not 0 <= j < self.model.njoints:
            raise InputError(f"expected a joint of the model, got {joint!r}", field="joint")
        R, p = self._joints[j]
        return tuple(ca.Function(f"oMi_{j}", [self.q], [R, p])(q))

    def function(self, frames: Sequence[str | int], name: str = "frames_placement") -> ca.Function:
        """``casadi.Function`` ``q -> (R_f0, p_f0, R_f1, p_f1, ...)`` for the given frames.

        Outputs are named ``R_<frame>`` and ``p_<frame>``.
        """
        outs, names = [], []
        for f in frames:
            R, p = self._frames[self.frame_id(f)]
            label = f if isinstance(f, str) else self.model.frames[int(f)].name
            outs += [R, p]
            names += [f"R_{label}", f"p_{label}"]
        return ca.Function(name, [self.q], outs, ["q"], names)
