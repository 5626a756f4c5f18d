"""Motions of the model-based simulator: exact joint trajectories on a free-flyer skeleton.

Joint trajectories are sums of sinusoids (:class:`pipeline.simulate.chain.Sinusoids`), so ``q``,
``v`` and ``a`` are exact. The skeleton has a free-flyer root (``q[:7]`` = pelvis position and
quaternion ``x, y, z, w``; ``v[:6]`` = pelvis velocity in the pelvis frame, linear then angular;
``a[:6]`` its time derivative). World frame: z up; segment frames ISB (x anterior, y proximal, z
right). Motions:

* ``'gait'``: walking at ~1.2 m/s along a weaving path (heading +-15-22 deg
  at 0.08 Hz), stride ~0.9 Hz, pelvis yaw/obliquity/tilt and bounce, both legs half a stride apart
  (hip Z-X-Y, knee 4-72 deg, ankle Z-X);
* ``'supine_hip_flexion'``: lying on a table (pelvis fixed), right hip and knee flexing together
  at ~0.25 Hz (hip 1-69 deg, knee 3-93 deg), small hip ab/adduction and rotation (as in the Wang
  2023 recordings); left leg still;
* ``'still_thigh'``: seated (pelvis fixed), thigh horizontal with tremor < 0.5 deg, right knee
  swinging 7-103 deg (poor excitation: the thigh axis is nearly unobservable);
* ``'static'``: standing still in the neutral pose (a gravity reference).

Every angle is designed to stay inside the model's joint limits (amplitudes are only ever scaled
down, by U(0.9, 1)); :func:`pipeline.simulate.model.simulate_trial` checks it. Stride frequency,
phases and amplitude scales come from the seeded generator passed in.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from pipeline.errors import InputError
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import quat_xyzw_from_matrix
from pipeline.simulate.chain import UPRIGHT, Sinusoids, chain_kinematics
from pipeline.simulate.conventions import MOTIONS

__all__ = ["RAMP_S", "SINUSOIDAL", "joint_trajectories", "motion_name", "ramp", "standing_height",
           "standing_start"]

_X, _Y, _Z = np.eye(3)
_SUPINE = np.array([[0.0, 1, 0], [0, 0, 1], [1, 0, 0]])  # pelvis x -> up, y -> +x (head)

# joint suffix -> (offset deg, ((amplitude deg, frequency x base, phase rad), ...))
_Spec = dict[str, tuple[float, tuple[tuple[float, float, float], ...]]]
_GAIT: _Spec = {
    "hip_Z": (12.0, ((22.0, 1.0, 0.0), (3.0, 2.0, 0.5))),
    "hip_X": (1.0, ((5.0, 1.0, 1.0), (2.0, 2.0, 0.3))),
    "hip_Y": (0.0, ((5.0, 1.0, 2.0), (2.0, 2.0, 1.0))),
    "knee": (38.0, ((26.0, 1.0, -1.2), (8.0, 2.0, 0.4))),
    "knee_X": (0.0, ((2.0, 1.0, 0.3),)),
    "knee_Y": (0.0, ((5.0, 1.0, -1.0),)),
    "ankle_Z": (2.0, ((10.0, 1.0, -0.6), (5.0, 2.0, 0.2))),
    "ankle_X": (1.0, ((5.0, 1.0, 0.8),)),
}
_SUPINE_RIGHT: _Spec = {
    "hip_Z": (35.0, ((30.0, 1.0, 0.0), (4.0, 2.4, 0.7))),
    "hip_X": (0.0, ((1.5, 1.5, 0.2), (0.7, 4.4, 1.0))),
    "hip_Y": (0.0, ((2.0, 1.2, 0.5), (0.8, 3.6, 0.1))),
    "knee": (48.0, ((40.0, 1.0, -0.3), (5.0, 2.4, 0.9))),
    "knee_X": (0.0, ((1.0, 1.0, 0.0),)),
    "knee_Y": (0.0, ((3.0, 1.0, 0.4),)),
    "ankle_Z": (0.0, ((5.0, 1.0, 1.0),)),
    "ankle_X": (0.0, ((2.0, 1.3, 0.0),)),
}
_STILL_RIGHT: _Spec = {
    "hip_Z": (90.0, ((0.3, 1.0, 0.0), (0.1, 6.2, 1.0))),
    "hip_X": (0.0, ((0.2, 1.4, 0.3), (0.1, 5.4, 0.0))),
    "hip_Y": (0.0, ((0.2, 1.2, 0.8),)),
    "knee": (55.0, ((40.0, 1.0, 0.0), (8.0, 2.2, 0.5))),
    "knee_X": (0.0, ((0.5, 1.0, 0.0),)),
    "knee_Y": (0.0, ((2.0, 1.0, 0.3),)),
    "ankle_Z": (0.0, ((5.0, 1.0, 0.5),)),
    "ankle_X": (0.0, ((2.0, 1.0, 0.0),)),
}
_STATIC = {"knee": 0.0}
_STILL_LEFT = {"hip_Z": 90.0, "knee": 90.0}
_SUPINE_LEFT = {"knee": 5.0}
#: ``s, s', s'', tau`` of :func:`ramp` on the trial's samples.
_Clock = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
_BASE_HZ = {"gait": (0.85, 1.0), "supine_hip_flexion": (0.22, 0.28), "still_thigh": (0.45, 0.55)}
#: The motions defined here (``'walk'`` is :mod:`pipeline.simulate.walk`'s).
SINUSOIDAL = tuple(m for m in MOTIONS if m != "walk")


def motion_name(motion: str) -> str:
    m = motion
    if m not in MOTIONS:
        raise InputError(f"expected a motion in {MOTIONS}, got {motion!r}", field="motion")
    return m


def _angle_fns(
    motion: str, side: str, rng: np.random.Generator, base: float, phase: float
) -> dict[str, Sinusoids]:
    """Per joint suffix (``hip_Z``, ``knee``, ``knee_Z``, ...) a seeded :class:`Sinusoids`."""
    if motion == "static":
        const = _STATIC
    elif motion == "still_thigh" and side == "left":
        const = _STILL_LEFT
    elif motion == "supine_hip_flexion" and side == "left":
        const = _SUPINE_LEFT
    else:
        const = None
    if const is not None:
        out = {k: Sinusoids(np.deg2rad(v)) for k, v in const.items()}
        out["knee_Z"] = out["knee"]
        return out
    spec = {"gait": _GAIT, "supine_hip_flexion": _SUPINE_RIGHT, "still_thigh": _STILL_RIGHT}
    # one stride rate and phase per trial; the left leg half a stride (pi) after the right
    shift = phase + (np.pi if side == "left" else 0.0)
    out = {}
    for name, (off, terms) in spec[motion].items():
        scale = rng.uniform(0.9, 1.0, len(terms))  # never beyond the designed (limit-safe) range
        out[name] = Sinusoids(
            np.deg2rad(off),
            [np.deg2rad(a) * s for (a, _, _), s in zip(terms, scale, strict=True)],
            [base * f for _, f, _ in terms],
            [shift * f + p for _, f, p in terms],
        )
    out["knee_Z"] = out["knee"]
    return out


def _heading(amp_m: float, freq: float, phase: float, speed: float) -> Callable:
    """Heading ``psi = atan(y'/x')`` of the path ``(speed t, amp sin(2 pi f t + phase))``."""
    path = Sinusoids(0.0, [amp_m], [freq], [phase])

    def fn(t: np.ndarray):
        _, dy, ddy = path(t)
        w = 2 * np.pi * freq
        dddy = -(w**2) * dy
        u, du, ddu = dy / speed, ddy / speed, dddy / speed
        s = 1.0 + u * u
        return np.arctan(u), du / s, (ddu * s - 2 * u * du * du) / (s * s)

    return fn


def _follow(fn: Callable, clock: _Clock | None) -> Callable:
    """``fn`` on the motion clock: ``g(tau)``, ``s g'``, ``s' g' + s^2 g''`` (None: ``fn``)."""
    if clock is None:
        return fn
    s, ds, _, tau = clock

    def warped(_t: np.ndarray):
        g, dg, ddg = fn(tau)
        return g, s * dg, ds * dg + s * s * ddg

    return warped


def _grow(fn: Callable, clock: _Clock | None, start: float = 0.0) -> Callable:
    """``fn`` grown from ``start`` by the ramp: ``c + s (g(tau) - c)``, ``s' (g - c) + s^2 g'``,
    ``s'' (g - c) + 3 s s' g' + s^3 g''`` with ``c = start`` (None: ``fn``)."""
    if clock is None:
        return fn
    s, ds, dds, tau = clock

    def warped(_t: np.ndarray):
        g, dg, ddg = fn(tau)
        g = g - start
        return start + s * g, ds * g + s * s * dg, dds * g + 3 * s * ds * dg + s**3 * ddg

    return warped


def _pelvis(
    motion: str, t: np.ndarray, rng: np.random.Generator, height: float, f: float,
    clock: _Clock | None = None,
):
    """Pelvis ``R (N,3,3)``, body ``w``, ``dw``, world ``p``, ``dp``, ``ddp`` (N,3).

    With a ``clock`` (:func:`standing_start`) the heading and the path follow the motion clock
    and the pelvis's own rotation, obliquity and tilt grow from zero with the ramp: the subject
    stands upright before walking."""
    n = t.size
    if motion != "gait":
        R0 = {"supine_hip_flexion": _SUPINE, "still_thigh": UPRIGHT}.get(motion, UPRIGHT)
        z = {"supine_hip_flexion": 0.15, "still_thigh": 0.55}.get(motion, height)
        p = np.tile([0.0, 0.0, z], (n, 1))
        zero = np.zeros((n, 3))
        return np.broadcast_to(R0, (n, 3, 3)).copy(), zero, zero, p, zero, zero
    ph = rng.uniform(0, 2 * np.pi, 6)
    speed, weave, fw = rng.uniform(1.1, 1.3), rng.uniform(0.7, 0.9), 0.08
    R, w, dw = chain_kinematics(
        t,
        [
            (_Z, _follow(_heading(weave, fw, ph[0], speed), clock)),
            UPRIGHT,
            (_Y, _grow(Sinusoids(0.0, [np.deg2rad(5.0)], [f], ph[1:2]), clock)),  # rotation
            (_X, _grow(Sinusoids(0.0, [np.deg2rad(4.0)], [f], ph[2:3]), clock)),  # obliquity
            (_Z, _grow(Sinusoids(np.deg2rad(3.0), [np.deg2rad(2.0)], [2 * f], ph[3:4]), clock)),
        ],
    )
    xyz = [
        Sinusoids(0.0, [0.01], [2 * f], ph[4:5], rate=speed),
        Sinusoids(0.0, [weave, 0.02], [fw, f], [ph[0], ph[5]]),
        Sinusoids(height, [0.02], [2 * f], ph[3:4]),
    ]
    p, dp, ddp = (np.stack([_follow(c, clock)(t)[k] for c in xyz], axis=1) for k in range(3))
    return R, w, dw, p, dp, ddp


def standing_height(skeleton: Skeleton) -> float:
    """Pelvis origin height with the ankle centres 8 cm above the floor, neutral pose."""
    q = skeleton.neutral()
    side = skeleton.legs[0]
    return 0.08 - float(skeleton.relative_pose(f"{side}_AJC", "pelvis", q)[1, 3])


def joint_trajectories(
    skeleton: Skeleton, motion: str, time: np.ndarray, seed: int | np.random.Generator = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact ``q (N,nq)``, ``v (N,nv)``, ``a (N,nv)`` of ``motion`` on a free-flyer ``skeleton``.

    Free-flyer: ``q[:3] = p``, ``q[3:7]`` = quaternion (x, y, z, w) of ``R``; ``v[:3] = R^T p'``,
    ``v[3:6] = w`` (body); ``a[:3] = R^T p'' - w x v[:3]``, ``a[3:6] = w'``.
    """
    return _trajectories(skeleton, motion, time, seed, None)


def _trajectories(
    skeleton: Skeleton, motion: str, time: np.ndarray, seed: int | np.random.Generator,
    clock: _Clock | None, posture: dict[str, float] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    if skeleton.root != "freeflyer":
        raise InputError("expected a skeleton with root='freeflyer'", field="root")
    motion = motion_name(motion)
    if motion not in SINUSOIDAL:
        raise InputError(f"motion {motion!r} is pipeline.simulate.walk.walk_trajectories's",
                         field="motion")
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    t = np.asarray(time, dtype=float)
    model = skeleton.model
    q = np.zeros((t.size, model.nq))
    v = np.zeros((t.size, model.nv))
    a = np.zeros((t.size, model.nv))
    base = rng.uniform(*_BASE_HZ[motion]) if motion in _BASE_HZ else 1.0  # stride rate, Hz
    phase = rng.uniform(0, 2 * np.pi)
    R, w, dw, p, dp, ddp = _pelvis(motion, t, rng, standing_height(skeleton), base, clock)
    vl = np.einsum("nji,nj->ni", R, dp)
    q[:, :3], q[:, 3:7] = p, quat_xyzw_from_matrix(R)
    v[:, :3], v[:, 3:6] = vl, w
    a[:, :3], a[:, 3:6] = np.einsum("nji,nj->ni", R, ddp) - np.cross(w, vl), dw
    for side in skeleton.legs:
        fns = _angle_fns(motion, side, rng, base, phase)
        for name in skeleton.joint_names:
            if not name.startswith(side + "_"):
                continue
            j = model.joints[model.getJointId(name)]
            fn = fns.get(name[len(side) + 1 :], Sinusoids(0.0))
            start = (posture or {}).get(name, 0.0)
            q[:, j.idx_q], v[:, j.idx_v], a[:, j.idx_v] = _grow(fn, clock, start)(t)
    return q, v, a


#: Duration (s) of the smooth transition from the standing pose into the motion.
RAMP_S = 1.5


def ramp(t: np.ndarray, start: float) -> tuple[np.ndarray, ...]:
    """``s, s', s'', tau``: a quintic smoothstep from 0 (before ``start``) to 1 (after
    ``start + RAMP_S``), C2, and its integral ``tau = int_0^t s``."""
    x = np.clip((t - start) / RAMP_S, 0.0, 1.0)
    inside = (t > start) & (t < start + RAMP_S)
    s = x**3 * (10 - 15 * x + 6 * x**2)
    ds = np.where(inside, 30 * x**2 * (1 - x) ** 2 / RAMP_S, 0.0)
    dds = np.where(inside, 60 * x * (1 - x) * (1 - 2 * x) / RAMP_S**2, 0.0)
    tau = RAMP_S * x**4 * (2.5 - 3 * x + x**2) + np.clip(t - start - RAMP_S, 0.0, None)
    return s, ds, dds, tau


def standing_start(
    skeleton: Skeleton, motion: str, time: np.ndarray, standing_s: float,
    seed: int | np.random.Generator = 0, posture: dict[str, float] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``q, v, a`` of ``motion`` preceded by ``standing_s`` s still in a standing pose (the
    joints at ``posture``, joint name -> angle in rad, zero where not given; the pelvis upright
    at the motion's starting place and heading), then a :data:`RAMP_S` s transition.

    Exact: with the ramp ``s(t)`` and the motion clock ``tau(t) = int s`` (:func:`ramp`), the
    path and heading follow the motion at ``tau`` (``x' = s x_m'(tau)``,
    ``x'' = s' x_m' + s^2 x_m''``) and each joint angle and the pelvis's own rotation,
    obliquity and tilt are ``s g(tau)`` (``g' -> s' g + s^2 g'``,
    ``g'' -> s'' g + 3 s s' g' + s^3 g''``); the pelvis chain composes them exactly
    (:func:`pipeline.simulate.chain.chain_kinematics`). Standing upright, not leaning with the
    gait's pelvis tilt: the posture a standing calibration asks of the subject.
    """
    t = np.asarray(time, dtype=float)
    return _trajectories(skeleton, motion, t, seed, ramp(t, float(standing_s)), posture)
