"""The simulated walk's plan and its feet (:mod:`pipeline.simulate.walk`, whose docstring
states the model): the path, the strides and footprints drawn once (:func:`walk_plan`), and each
foot's pose at every instant of the motion clock (:func:`foot_poses`), each stride computed on its
own samples (linear in the walk's length)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from pipeline.model.skeleton import Skeleton
from pipeline.rotations import rot_x, rot_z
from pipeline.simulate.chain import UPRIGHT
from pipeline.simulate.foot_walk import FC_SHARE, LOBES, bump_integral, min_jerk
from pipeline.simulate.knee import hip_ankle_distance_sq

__all__ = ["CLEARANCE_M", "FLAT", "MID_STANCE", "PUSH_OFF", "TURN_LENGTH_M", "WalkPlan",
           "arc_length", "foot_poses", "leg_length", "walk_plan"]

#: Where the foot lies flat in a stride from its IC (shares of the stride; the lobes between).
FLAT, PUSH_OFF = LOBES[0][1], LOBES[1][0]
CLEARANCE_M = 0.05
#: The right foot's mid-stance in the stride from its push-off (motion clock, strides).
MID_STANCE = 0.85
TURN_LENGTH_M = 3.0


@dataclass(frozen=True)
class WalkPlan:
    """The walk's design and truth: stride ``T`` (s of the motion clock), stride length ``L`` (m),
    ``turn`` (rad) starting at arc length ``turn_at_m``; per side the push-off starts ``po``
    (clock s; the first from the standing footprint) and footprints ``(k, 3)`` (the ankle
    centre when flat, world) with headings ``(k,)``."""

    T: float
    L: float
    turn: float
    turn_at_m: float
    push_off: dict[str, np.ndarray]
    footprints: dict[str, np.ndarray]
    headings: dict[str, np.ndarray]
    path: CubicSpline
    heading: CubicSpline

    @property
    def speed(self) -> float:
        return self.L / self.T

    def contacts(self, side: str) -> tuple[np.ndarray, np.ndarray]:
        """The foot's initial and final contacts (motion clock s): each IC lands on the
        footprint after the standing one, in order."""
        po = self.push_off[side]
        return po[:-1] + (1 - PUSH_OFF) * self.T, po + (FC_SHARE - PUSH_OFF) * self.T

    def stride_lengths(self, side: str) -> np.ndarray:
        """The horizontal length of each stride from one IC to the next (m)."""
        return np.linalg.norm(np.diff(self.footprints[side][1:, :2], axis=0), axis=1)


def _path(turn: float, turn_at: float, length: float) -> tuple[CubicSpline, CubicSpline]:
    """The path's horizontal position and heading as cubic splines of the arc length."""
    s = np.arange(-1.0, length + 1.0, 0.005)
    psi = turn * min_jerk((s - turn_at) / TURN_LENGTH_M)[0]
    d = np.stack([np.cos(psi), np.sin(psi)], axis=1)
    xy = np.concatenate([[[0.0, 0.0]], np.cumsum(0.5 * (d[1:] + d[:-1]) * 0.005, axis=0)])
    xy -= xy[np.searchsorted(s, 0.0)]
    return CubicSpline(s, xy), CubicSpline(s, psi)


def arc_length(plan_T: float, v: float, tau: np.ndarray) -> np.ndarray:
    c = 0.35 * plan_T
    return v * (tau - c) + v * c * np.exp(-np.asarray(tau) / c)


def leg_length(skeleton: Skeleton) -> float:
    return float(np.sqrt(hip_ankle_distance_sq(skeleton, skeleton.neutral(), "right")))


def walk_plan(skeleton: Skeleton, duration_s: float, rng: np.random.Generator,
              standing_feet: dict[str, np.ndarray]) -> WalkPlan:
    """Draw a walk (stride ``T ~ U(1.0, 1.15)`` s, length ``~U(1.25, 1.4)`` leg lengths, a turn of
    ``+-U(60, 120)`` deg after two strides) and place its footprints (module docstring)."""
    leg = leg_length(skeleton)
    T, L = rng.uniform(1.0, 1.15), leg * rng.uniform(1.25, 1.4)
    turn = np.deg2rad(rng.uniform(60, 120)) * rng.choice([-1.0, 1.0])
    turn_at = 2 * L
    n_strides = int(duration_s / T) + 2
    path, heading = _path(turn, turn_at, L * (n_strides + 2))
    half = abs(float(skeleton.relative_pose("right_HJC", "pelvis", skeleton.neutral())[2, 3]))
    floor_z = np.mean([f[2] for f in standing_feet.values()])
    push, prints, heads = {}, {}, {}
    for side, first in (("right", 0.0), ("left", 0.5 * T)):
        po = first + T * np.arange(n_strides)
        ic = po[:-1] + (1 - PUSH_OFF) * T  # the IC after each push-off
        s = arc_length(T, L / T, ic + (MID_STANCE - 1 + PUSH_OFF) * T)  # the foot's mid-stance
        psi = heading(s)
        lateral = np.stack([np.sin(psi), -np.cos(psi), 0 * psi], 1) * (1 if side == "right" else -1)
        xy = np.concatenate([path(s), np.zeros((s.size, 1))], axis=1) + half * lateral
        xy[:, 2] = floor_z
        push[side] = po
        prints[side] = np.concatenate([standing_feet[side][None], xy])
        heads[side] = np.concatenate([[0.0], psi])
    return WalkPlan(T, L, turn, turn_at, push, prints, heads, path, heading)


def _foot_frame(psi: np.ndarray, phi: np.ndarray, roll: np.ndarray | float = 0.0) -> np.ndarray:
    return rot_z(psi) @ UPRIGHT @ rot_z(phi) @ rot_x(roll)


def _ramps(tau: np.ndarray, windows, shape) -> np.ndarray:
    """``sum_k size_k shape((tau - a_k) / (b_k - a_k))`` for ``windows`` ``(a_k, b_k, size_k)``
    with ``shape`` 0 before its window and 1 after: each window computed on its own samples, the
    ones after it by a running sum (linear in the walk's length; ``tau`` non-decreasing)."""
    out, after = np.zeros_like(tau), np.zeros(tau.size + 1)
    for a, b, size in windows:
        i0, i1 = np.searchsorted(tau, [a, b])
        out[i0:i1] += size * shape((tau[i0:i1] - a) / (b - a))
        after[i1] += size
    return out + np.cumsum(after[:-1])


def foot_poses(plan: WalkPlan, side: str, tau: np.ndarray, heel: np.ndarray, toe: np.ndarray,
               inversion: tuple[float, float] = (0.0, 0.0)):
    """The foot frame's world rotation (N, 3, 3), origin (N, 3) and inversion (N,) (rad, the sole
    turned medially on either side) at clock times ``tau`` (non-decreasing); ``inversion`` (rad)
    the foot's at initial contact and at the end of push-off (module docstring)."""
    T, po = plan.T, plan.push_off[side]
    F, H = plan.footprints[side], plan.headings[side]
    at_ic, at_toe_off = inversion
    # per lobe (loading, push-off, swing): the pitch's turn and the inversion's
    rolls = (-at_ic, at_toe_off, at_ic - at_toe_off)
    lobes = [(p - PUSH_OFF * T + a * T, p - PUSH_OFF * T + b * T, turn, r)
             for j, p in enumerate(po) for (a, b, turn), r in zip(LOBES, rolls, strict=True)
             if not (j == 0 and a == 0.0)]  # the standing footprint: no loading response
    phi = _ramps(tau, [(a, b, np.deg2rad(turn)) for a, b, turn, _ in lobes], bump_integral)
    roll = _ramps(tau, [(a, b, r) for a, b, _, r in lobes], bump_integral)
    inverted = roll.copy()
    roll *= 1.0 if side == "right" else -1.0  # the sole turned medially; z points right
    steps = po[: len(F) - 1]
    swings = [(p + (FC_SHARE - PUSH_OFF) * T, p + (1 - PUSH_OFF) * T) for p in steps]
    psi = _ramps(tau, [(fc, nxt, H[j + 1] - H[j]) for j, (fc, nxt) in enumerate(swings)],
                 lambda u: min_jerk(u)[0])
    pos = np.repeat(F[:1], tau.size, axis=0)
    for j, p in enumerate(steps):  # each stride's samples: up to the next push-off
        k = slice(*np.searchsorted(tau, [p, steps[j + 1] if j + 1 < len(steps) else np.inf]))
        pos[k] = _stride_positions(tau[k], (phi[k], roll[k]), (F[j], F[j + 1]),
                                   (H[j], H[j + 1]), swings[j], (heel, toe), T)
    return _foot_frame(psi, phi, roll), pos, inverted


def _stride_positions(tau, pitch_roll, prints, heads, swing_span, heel_toe, T) -> np.ndarray:
    """The foot's origin over one stride's samples (from its push-off): pivoting on the last
    footprint's toe, swinging (minimum jerk, lifted by the clearance), pivoting on the next
    footprint's heel, then flat on it."""
    phi, roll = pitch_roll
    (f0, f1), (h0, h1), (fc, nxt), (heel, toe) = prints, heads, swing_span, heel_toe
    u = (tau - fc) / (nxt - fc)
    m = min_jerk(u)[0]
    a = f0 + _foot_frame(h0, 0.0) @ toe - _foot_frame(np.full_like(tau, h0), phi, roll) @ toe
    b = f1 + _foot_frame(h1, 0.0) @ heel - _foot_frame(np.full_like(tau, h1), phi, roll) @ heel
    lift = 64 * CLEARANCE_M * np.clip(u, 0, 1) ** 3 * (1 - np.clip(u, 0, 1)) ** 3
    pos = np.where((tau < fc)[:, None], a, (1 - m)[:, None] * a + m[:, None] * b
                   + lift[:, None] * [0.0, 0.0, 1.0])
    pos = np.where((tau >= nxt)[:, None], b, pos)
    return np.where((tau >= nxt + FLAT * T)[:, None], f1, pos)
