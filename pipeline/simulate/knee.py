"""The simulated walk's knee: a free knee that is not a hinge, and the flexion that lets a leg
reach its foot (:mod:`pipeline.simulate.walk`).

A free knee's adduction ``b`` and tibial internal rotation ``r`` follow its flexion ``k`` and the
stride, per leg,

    b = c_x k + A_x s^2 sin(theta + phi_x),
    r = c_y k + S (1 - exp(-k / k_s)) + A_y s^2 sin(theta + phi_y),                     (1)

with ``theta = 2 pi tau / T`` the stride's phase and ``s`` the motion's ramp (zero standing):

* the tibia turns internally as the knee flexes and adducts or abducts with it (healthy knees
  walking, biplane radiography of 39 knees, J Biomech Eng 142:121001, 2020: ranges 67.3 deg
  flexion, 11.5 deg internal rotation, 3.7 deg ab/adduction);
* most of that turn comes in the first degrees of flexion, the screw-home mechanism
  (``S`` over ``k_s`` = :data:`SCREW_HOME_RAD`): the knee's axis shifts with flexion;
* the rest does not follow flexion at all: at one flexion angle the knee takes different
  rotations and ab/adductions through the stride (bone pins walking, Benoit et al. 2007, Clin
  Orthop Relat Res 454:81-88), here a sinusoid at the stride's rate.

The sizes are drawn per leg from :data:`KNEE_COUPLING`. A hinge knee stays a hinge.

The leg's IK (:func:`flexion_reaching`) sets the flexion from the hip centre's distance to the
ankle centre's: ``d^2(k)`` with (1)'s flexion terms is a cubic spline over ``k`` (errors ~1e-13
m^2), rising to the straightest knee and falling after (one root each side, Newton); the
stride's terms are then put right by secant steps on the model's exact distance.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import pinocchio as pin
from scipy.interpolate import CubicSpline
from scipy.optimize import brentq

from pipeline.errors import InputError
from pipeline.model.skeleton import Skeleton

__all__ = ["KNEE_COUPLING", "SCREW_HOME_RAD", "Knee", "draw_knee", "flexion_reaching",
           "hip_ankle_distance_sq"]

#: Ranges (uniform) of (1)'s sizes: ``|c_x|`` (of either sign: subjects differ in the frontal
#: plane) and ``c_y`` (rad per rad of flexion), the screw-home turn ``S`` and the stride's
#: amplitudes ``A_x``, ``A_y`` (deg). Over a stride (flexion 0-60 deg) they give 6-17 deg of
#: internal rotation and 2-6 deg of ab/adduction, about the biplane study's averages.
KNEE_COUPLING = {"adduction": (0.02, 0.05), "rotation": (0.04, 0.10), "screw_home_deg": (3.0, 6.0),
                 "stride_adduction_deg": (1.0, 2.0), "stride_rotation_deg": (2.0, 4.0)}
#: The flexion (rad, ~14 deg) over which the screw-home turn ``S`` mostly happens.
SCREW_HOME_RAD = 0.25


@dataclass(frozen=True)
class Knee:
    """One leg's knee: q indices of its flexion and (free knee) of its adduction and rotation,
    (1)'s sizes ``coupling = (c_x, c_y, S)`` and ``stride = (A_x, phi_x, A_y, phi_y)`` (rad),
    ``d^2(k)`` without the stride's terms as a spline, the straightest knee's flexion and
    ``sides``: ``(a, b, d^2(a), d^2(b))`` where ``d^2`` rises (``a < b``: some) and falls."""

    flexion: int
    coupled: tuple[int, ...] = ()
    coupling: tuple[float, ...] = ()
    stride: tuple[float, ...] = ()
    reach: CubicSpline | None = None
    straight: float = 0.0
    sides: tuple = ()

    def stride_angles(self, theta: np.ndarray, ramp: np.ndarray) -> np.ndarray:
        """(N, 2) (1)'s stride terms of ``b`` and ``r`` at phase ``theta`` (rad), ramped by
        ``ramp**2``; zeros for a hinge."""
        if not self.coupled:
            return np.zeros((np.size(theta), 2))
        a_x, phi_x, a_y, phi_y = self.stride
        return ramp[:, None] ** 2 * np.stack([a_x * np.sin(theta + phi_x),
                                               a_y * np.sin(theta + phi_y)], axis=1)

    def set(self, q: np.ndarray, k: float, extra: np.ndarray | None = None) -> None:
        """Put flexion ``k`` and the angles (1) couples to it (plus ``extra``, the stride's
        terms) into ``q``."""
        q[self.flexion] = k
        if self.coupled:
            c_x, c_y, screw = self.coupling
            e = (0.0, 0.0) if extra is None else extra
            q[self.coupled[0]] = c_x * k + e[0]
            q[self.coupled[1]] = c_y * k + screw * (1 - np.exp(-k / SCREW_HOME_RAD)) + e[1]


def draw_knee(skeleton: Skeleton, side: str, rng: np.random.Generator) -> Knee:
    """The leg's :class:`Knee`; a free knee draws (1)'s sizes (:data:`KNEE_COUPLING`), a hinge
    draws nothing."""
    names = skeleton.leg_joints(side, "knee")
    knee = Knee(skeleton.q_index(names[0]))
    if len(names) == 3:
        r = {name: rng.uniform(*span) for name, span in KNEE_COUPLING.items()}
        c_x = r["adduction"] * rng.choice([-1.0, 1.0])
        knee = replace(knee, coupled=(skeleton.q_index(names[1]), skeleton.q_index(names[2])),
                       coupling=(c_x, r["rotation"], np.deg2rad(r["screw_home_deg"])),
                       stride=(np.deg2rad(r["stride_adduction_deg"]), rng.uniform(0, 2 * np.pi),
                               np.deg2rad(r["stride_rotation_deg"]),
                               rng.uniform(0, 2 * np.pi)))
    q = skeleton.neutral()
    k = 0.0025 * np.arange(-20, 1258)  # -0.05 .. pi rad, the straight knee on the grid
    d2 = []
    for x in k:
        knee.set(q, x)
        d2.append(hip_ankle_distance_sq(skeleton, q, side))
    reach = CubicSpline(k, d2)
    top = np.concatenate([k[[0, -1]], reach.derivative().solve(0.0, extrapolate=False)])
    straight = float(top[np.argmax(reach(top))])
    sides = tuple((a, b, float(reach(a)), float(reach(b)))
                  for a, b in ((max(k[0], 0.0), straight), (straight, k[-1])))
    return replace(knee, reach=reach, straight=straight, sides=sides)


def hip_ankle_distance_sq(skeleton: Skeleton, q: np.ndarray, side: str) -> float:
    """The hip centre's squared distance to the ankle centre's at ``q`` (m^2)."""
    pin.framesForwardKinematics(skeleton.model, skeleton.data, q)
    o, frame = skeleton.data.oMf, skeleton.frame_id
    d = o[frame(f"{side}_AJC")].translation - o[frame(f"{side}_HJC")].translation
    return float(d @ d)


def flexion_reaching(
    skeleton: Skeleton, knee: Knee, q: np.ndarray, d2: float, extra: np.ndarray, side: str,
) -> None:
    """Set the knee in ``q`` (flexion >= 0 and the angles (1) couples to it, ``extra`` the
    stride's terms) so that the ankle centre lies ``sqrt(d2)`` from the hip's: the root on the
    last sample's side of the straightest knee (the other side's if this one has none; the
    straightest knee where the leg is just long enough), then the stride's terms put right."""
    f, straight, last = knee.reach, knee.straight, float(q[knee.flexion])
    rising, falling = knee.sides
    if d2 > rising[3] * (1 + 1e-9):
        raise InputError(f"the {side} leg cannot reach its foot's pose in the simulated walk",
                         field="motion")
    k = max(straight, 0.0)
    for a, b, fa, fb in (falling, rising) if last >= straight else (rising, falling):
        if a < b and (fa - d2) * (fb - d2) <= 0:
            k = _root_between(f, d2, a, b, min(max(last, a), b))
            break
    knee.set(q, k, extra)
    if knee.coupled and np.any(extra) and k > straight:
        _secant(skeleton, knee, q, d2, extra, side)


def _root_between(f: CubicSpline, d2: float, a: float, b: float, k: float) -> float:
    """``f(k) = d2`` in ``[a, b]`` (where ``f`` is monotonic) by Newton from ``k`` on the
    spline's cubic pieces (Brent's method if a step leaves ``[a, b]``)."""
    for _ in range(8):
        i = min(max(int(np.searchsorted(f.x, k)) - 1, 0), f.x.size - 2)
        c3, c2, c1, c0 = f.c[:, i]
        h = k - f.x[i]
        slope = (3 * c3 * h + 2 * c2) * h + c1
        step = (((c3 * h + c2) * h + c1) * h + c0 - d2) / slope if slope != 0 else np.inf
        if not a <= k - step <= b:
            break
        k -= step
        if abs(step) < 1e-13:
            return float(k)
    return float(brentq(lambda x: f(x) - d2, a, b, xtol=1e-14))


def _secant(skeleton: Skeleton, knee: Knee, q: np.ndarray, d2: float, extra, side: str) -> None:
    """Secant steps on the flexion in ``q`` until the model's exact distance is ``sqrt(d2)``
    (the stride's terms move it by well under a millimetre: two or three steps)."""
    k0 = float(q[knee.flexion])
    g0 = hip_ankle_distance_sq(skeleton, q, side) - d2
    k1 = k0 + 1e-4
    for _ in range(12):
        knee.set(q, k1, extra)
        g1 = hip_ankle_distance_sq(skeleton, q, side) - d2
        if abs(g1) < 1e-14 or g1 == g0:
            return
        k0, k1, g0 = k1, k1 - g1 * (k1 - k0) / (g1 - g0), g1
        k1 = max(k1, 0.0)
    raise InputError(f"the {side} leg's knee did not converge in the simulated walk",
                     field="motion")
