"""What real recordings carry and an ideal simulation does not: soft-tissue motion of each sensor
on its segment, gyro bias that wanders, accelerometer bias, a magnetic field bent near the floor.

:class:`Artefacts` holds their sizes; :func:`pipeline.simulate.model.simulate_trial` applies them
(``artefacts=Artefacts()``) exactly, so that gyroscope, accelerometer, magnetometer and
orientation stay consistent with one another:

* **Soft tissue** (Leardini et al. 2005, Gait Posture 21:212-225: thigh markers move 10-30 mm on
  the bone, mostly about the femur's long axis; the shank's less): each sensor turns on its
  segment by ``delta(t) = C (phi(t) - phi(0))``, linear in the angles of the joints next to it
  (hip and knee flexion for the thigh, knee and ankle for the shank, the ankle's two for the
  foot, both hips for the pelvis: correlated with the gait cycle, zero at the standing start),
  plus on the thigh a wobble about its long axis at :data:`WOBBLE_HZ` that grows with the motion;
  and moves by ``d(t) = D (phi(t) - phi(0))``. ``C`` leans to the segment's long axis; both are
  scaled to the RMS sizes given (thigh; the other segments by :data:`SEGMENT_SCALE`). The
  sensor's frame is ``R_s = R_i exp(delta)``, its origin ``p_s = p_i + R_i d``; so its angular
  velocity is ``exp(delta)^T w_i + J_r(delta) delta'`` (``J_r`` the right Jacobian of SO(3)) and
  its specific force ``exp(delta)^T (R_i^T (p_i'' - g) + d'' + 2 w_i x d' + w_i' x d
  + w_i x (w_i x d))``, all from the exact joint velocities and accelerations.
* **Gyro bias** that wanders: a random walk of :attr:`Artefacts.gyro_bias_walk` rad/s per
  sqrt(s) on top of the simulator's constant bias (MEMS bias instability);
  **accelerometer bias**: a constant per axis.
* **The floor's field**: ``B_0 exp(-z / lambda) u(x, y)`` added to the earth's field, with ``z``
  the sensor's height and ``u`` a direction that turns over the room (reinforced concrete, floor
  heating): the feet's sensors see their field's strength and dip change as they walk, the
  thighs' hardly.

A knee that is not a hinge is a free-knee skeleton (knee ab/adduction and rotation move with the
stride, :mod:`pipeline.simulate.motions`; in the walk, with flexion and the stride,
:mod:`pipeline.simulate.knee`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.rotations import exp3, skew

__all__ = ["SEGMENT_SCALE", "WOBBLE_HZ", "Artefacts", "floor_field", "soft_tissue_motion",
           "with_soft_tissue"]

#: Soft-tissue sizes of each segment relative to the thigh's.
SEGMENT_SCALE = {"pelvis": 0.3, "femur": 1.0, "tibia": 0.5, "foot": 0.4}
#: Frequency of the thigh sensor's wobble (Hz): the thigh's soft tissue rings at 5-10 Hz.
WOBBLE_HZ = 7.0


@dataclass(frozen=True)
class Artefacts:
    """Sizes of the module docstring's artefacts: ``soft_tissue_deg`` / ``soft_tissue_m`` the
    RMS turn and shift of the thigh's sensor on its segment, ``wobble_deg`` the amplitude of its
    axial wobble, ``gyro_bias_walk`` (rad/s per sqrt(s)), ``acc_bias_sd`` (m/s^2 per axis),
    ``floor_field_ut`` the floor's field at the floor (uT) and ``floor_decay_m`` its decay
    height."""

    soft_tissue_deg: float = 3.0
    soft_tissue_m: float = 0.008
    wobble_deg: float = 1.0
    gyro_bias_walk: float = 2e-4
    acc_bias_sd: float = 0.05
    floor_field_ut: float = 25.0
    floor_decay_m: float = 0.15


def _right_jacobian(delta: np.ndarray) -> np.ndarray:
    """``J_r(delta)`` (N, 3, 3): ``I - (1 - cos t)/t^2 [d]x + (t - sin t)/t^3 [d]x^2``."""
    t = np.linalg.norm(delta, axis=1)[:, None, None]
    K = skew(delta)
    small = t < 1e-8
    t = np.where(small, 1.0, t)
    a = np.where(small, 0.5, (1 - np.cos(t)) / t**2)
    b = np.where(small, 1.0 / 6.0, (t - np.sin(t)) / t**3)
    return np.eye(3) - a * K + b * (K @ K)


def soft_tissue_motion(
    rng: np.random.Generator,
    drive: tuple[np.ndarray, np.ndarray, np.ndarray],
    long_axis: np.ndarray,
    turn_rms: float,
    shift_rms: float,
    wobble: tuple[float, np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray]] | None = None,
) -> tuple[tuple[np.ndarray, ...], tuple[np.ndarray, ...]]:
    """``((delta, delta', delta''), (d, d', d''))`` (N, 3) each, sensor frame (module docstring).

    ``drive``: the joint angles next to the segment and their first two derivatives, (N, k)
    each; ``long_axis``: the segment's long axis in the sensor frame; ``wobble``: ``(amplitude
    rad, t, (s, s', s''))`` with ``t`` the time (s) and ``s`` the motion's ramp (0 standing,
    1 moving), or None."""
    phi, dphi, ddphi = (np.asarray(x, float) for x in drive)
    phi = phi - phi[0]
    k = phi.shape[1]
    C = 0.7 * np.outer(long_axis, rng.choice([-1.0, 1.0], k)) + 0.3 * rng.normal(size=(3, k))
    D = rng.normal(size=(3, k))

    def scaled(M: np.ndarray, rms: float) -> np.ndarray:
        size = np.sqrt(np.mean(np.sum((phi @ M.T) ** 2, axis=1)))
        return M * (rms / size if size > 0 else 0.0)

    C, D = scaled(C, turn_rms), scaled(D, shift_rms)
    turn = [phi @ C.T, dphi @ C.T, ddphi @ C.T]
    if wobble is not None:  # a s(t) sin(w t + ph) about the long axis, exact derivatives
        amp, t, (s, ds, dds) = wobble
        w, ph = 2 * np.pi * WOBBLE_HZ, rng.uniform(0, 2 * np.pi)
        f, df, ddf = np.sin(w * t + ph), w * np.cos(w * t + ph), -(w**2) * np.sin(w * t + ph)
        for m, g in enumerate((s * f, ds * f + s * df, dds * f + 2 * ds * df + s * ddf)):
            turn[m] = turn[m] + np.outer(amp * g, long_axis)
    return tuple(turn), (phi @ D.T, dphi @ D.T, ddphi @ D.T)


def with_soft_tissue(R, W, AW, A, delta, d) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The sensor's ``(R_s, gyro, specific force without gravity)`` from the nominal frame's
    orientation ``R`` (N, 3, 3), body angular velocity ``W``, angular acceleration ``AW`` and
    classical acceleration ``A`` (sensor frame), and the soft tissue's ``delta`` and ``d`` triples
    (module docstring). The caller subtracts gravity: ``f = E^T (A_s - R^T g)``; here ``A_s`` is
    returned in the nominal frame, with ``E``'s transpose applied by the caller too."""
    (dl, ddl, _), (d0, dd0, ddd0) = delta, d
    E = exp3(dl)
    W_s = np.einsum("nji,nj->ni", E, W) + np.einsum("nij,nj->ni", _right_jacobian(dl), ddl)
    A_loc = (A + ddd0 + 2 * np.cross(W, dd0) + np.cross(AW, d0)
             + np.cross(W, np.cross(W, d0)))
    return R @ E, W_s, A_loc


def floor_field(P: np.ndarray, rng: np.random.Generator, b0_ut: float, decay_m: float):
    """The floor's field (N, 3) uT in the world at positions ``P`` (N, 3) (module docstring)."""
    k, ph = 2 * np.pi / 1.5, rng.uniform(0, 2 * np.pi, 2)
    u = np.stack([np.cos(k * P[:, 0] + ph[0]), np.sin(k * P[:, 1] + ph[1]),
                  np.full(len(P), 0.6)], axis=1)
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return b0_ut * np.exp(-np.clip(P[:, 2], 0.0, None) / decay_m)[:, None] * u
