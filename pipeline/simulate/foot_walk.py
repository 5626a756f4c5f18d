"""A foot sensor walking through the room, with known events, strides and path.

Each stride of period ``T`` (from an initial contact, IC) turns the foot about its lateral axis
in three raised-cosine lobes of angular velocity: the loading response (``[0, 0.1 T]``, the foot
turning flat from ``+20 deg``), the push-off (``[0.45 T, 0.75 T]``, ``-40 deg``, fastest at the
final contact FC ``= 0.6 T``) and the swing (``[0.75 T, T]``, ``+60 deg``, ending at the next IC);
the foot rests flat in ``[0.1 T, 0.45 T]``. Between FC and the next IC the foot moves forward by
the stride length on a minimum-jerk path (Flash & Hogan 1985), lifted by the clearance on a
``sin^2`` profile, and turns by the stride's turn about the vertical. The sensor is mounted at a
random orientation; its gyroscope and specific force are exact with white noise added, and each
heel strike adds a damped transient to the specific force (:data:`IMPACT`). The walk starts and
ends standing. What :mod:`pipeline.analysis.gait_events`,
:mod:`pipeline.analysis.foot_trajectory` and :mod:`pipeline.analysis.strides` must recover.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.rotations import exp3, rot_z

__all__ = ["FC_SHARE", "LOBES", "RUN", "FootWalk", "Pace", "bump_integral", "foot_walk",
           "min_jerk"]

G = 9.81
#: The lobes of the sagittal rate at the default pace: (start, end, turn in deg) as shares of the
#: stride (their turns are every pace's).
LOBES = ((0.0, 0.1, -20.0), (0.45, 0.75, -40.0), (0.75, 1.0, 60.0))
FC_SHARE = 0.6
#: A fast walk's stance rolls the foot by this much per m/s beyond 1.4 m/s (deg; :meth:`Pace.at`).
ROLL_DEG_PER_M_S = 45.0


@dataclass(frozen=True)
class Pace:
    """How a stride is timed: its period ``stride_time_s`` and length ``length_m``, and as shares
    of it from the IC the end of the loading response (``loading``: the foot turning flat from the
    heel, :data:`LOBES`' first lobe) and the toe leaving (``fc``: the push-off's fastest
    rotation, its lobe ``fc -+ 0.15``; the swing from its end to the next IC). The foot rests
    flat between the two; a loading response that reaches into the push-off overlaps them, and
    the foot never rests (:meth:`at`)."""

    stride_time_s: float = 1.1
    length_m: float = 1.3
    loading: float = LOBES[0][1]
    fc: float = FC_SHARE
    roll_deg: float = 0.0

    def lobes(self) -> tuple[tuple[float, float, float], ...]:
        """The lobes of the sagittal rate (as :data:`LOBES`, whose turns they take) at this
        pace, and the stance's roll (``roll_deg`` over ``[0, fc]``, the heel rising as the body
        passes over the foot), which the swing turns back."""
        half = 0.5 * (LOBES[1][1] - LOBES[1][0])
        lobes = ((0.0, self.loading, LOBES[0][2]), (self.fc - half, self.fc + half, LOBES[1][2]),
                 (self.fc + half, 1.0, LOBES[2][2] - self.roll_deg))
        return lobes + (((0.0, self.fc, self.roll_deg),) if self.roll_deg else ())

    @staticmethod
    def running(speed_m_s: float = 3.0) -> Pace:
        """A run at ``speed_m_s`` (:data:`RUN`)."""
        return _running(speed_m_s)

    @classmethod
    def at(cls, speed_m_s: float) -> Pace:
        """A walk at ``speed_m_s``: cadence ``64.8 + 37.4 v`` steps/min (a linear fit of
        cadence to speed over 0.6-2.2 m/s, after Grieve & Gear 1966's cadence-speed relation),
        the stance share ``0.66 - 0.045 v`` (62 % at 1 m/s, shorter as the walk speeds up: Perry &
        Burnfield 2010), and beyond 1.4 m/s a loading response lasting ``0.1 + 0.2 (v - 1.4)`` of
        the stride and the stance rolling by :data:`ROLL_DEG_PER_M_S` ``(v - 1.4)``: the
        simulator's choice, sized so that the foot's stillest moment in stance spans what real
        walks show: still at slow and preferred speeds, turning through the whole stance fast (a
        real fast walk at 1.9 m/s: 0.43-0.92 rad/s at its stillest 50 ms)."""
        T = 120.0 / (64.8 + 37.4 * speed_m_s)
        fast = max(0.0, speed_m_s - 1.4)
        return cls(T, speed_m_s * T, 0.1 + 0.2 * fast, 0.66 - 0.045 * speed_m_s,
                   -ROLL_DEG_PER_M_S * fast)


@dataclass(frozen=True)
class FootWalk:
    """Signals (``gyr`` rad/s, ``acc`` m/s^2, sensor frame) at ``rate_hz`` and the truth: ``ic``
    and ``fc`` times (s), the foot's ``position`` (N, 3; z up) and per stride its ``length`` (m)
    and ``turn_deg``."""

    time: np.ndarray
    rate_hz: float
    gyr: np.ndarray
    acc: np.ndarray
    ic: np.ndarray
    fc: np.ndarray
    position: np.ndarray
    length: np.ndarray
    turn_deg: np.ndarray


#: A run's pace (:meth:`Pace.running`): stride time (s), stance share, the loading response's
#: share and the stance's roll (deg): Novacheck 1998 (Gait Posture 7:77): stance 39 % of a
#: running stride at 3.2 m/s, ~170 steps/min; the foot never rests.
RUN = (0.72, 0.38, 0.2, -30.0)


def _running(speed_m_s: float) -> Pace:
    T, fc, loading, roll = RUN
    return Pace(T, speed_m_s * T, loading, fc, roll)


def _bump(s: np.ndarray) -> np.ndarray:
    """A raised cosine on ``[0, 1]`` with unit integral (zero outside)."""
    inside = (s >= 0) & (s <= 1)
    return np.where(inside, 1.0 - np.cos(2 * np.pi * np.clip(s, 0, 1)), 0.0)


def bump_integral(s: np.ndarray) -> np.ndarray:
    """The integral of :func:`_bump` from 0 to ``s`` (0 before, 1 after)."""
    c = np.clip(s, 0, 1)
    return c - np.sin(2 * np.pi * c) / (2 * np.pi)


def min_jerk(s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Minimum-jerk position and second derivative (per unit duration^2) on ``[0, 1]``."""
    s = np.clip(s, 0, 1)
    return 10 * s**3 - 15 * s**4 + 6 * s**5, 60 * s - 180 * s**2 + 120 * s**3


#: The heel strike's transient in the vertical specific force (m/s^2 per m/s of walking speed,
#: Hz, s): a damped oscillation after each IC (the shoe's impact; foot sensors read 1-5 g peaks in
#: walking, more with speed).
IMPACT = (15.0, 25.0, 0.015)


def _impacts(time: np.ndarray, ic: np.ndarray, speed_m_s: float) -> np.ndarray:
    """The vertical specific force of the heel strikes at ``ic`` (:data:`IMPACT`)."""
    gain, freq, tau = IMPACT
    out = np.zeros_like(time)
    for t0 in ic:
        after = time - t0
        on = (after >= 0) & (after < 8 * tau)
        t = after[on]
        out[on] += gain * speed_m_s * np.exp(-t / tau) * np.sin(2 * np.pi * freq * t)
    return out


def foot_walk(strides: int = 8, pace: Pace = Pace(), clearance_m: float = 0.12,
              turns_deg: tuple[float, ...] = (), rate_hz: float = 100.0, standing_s: float = 2.0,
              seed: int = 0) -> FootWalk:
    """A walk of ``strides`` strides at ``pace`` (module docstring); ``turns_deg[k]`` turns
    stride ``k``."""
    rng = np.random.default_rng(seed)
    T, dt, length_m, lobes = pace.stride_time_s, 1.0 / rate_hz, pace.length_m, pace.lobes()
    t0 = standing_s - 0.1 * T  # the first lobe: the loading response of an IC at t0
    n = int(round((t0 + strides * T + 0.1 * T + standing_s) * rate_hz))
    time = np.arange(n) * dt
    pitch_rate, pitch = np.zeros(n), np.zeros(n)
    yaw_rate, yaw_angle = np.zeros(n), np.zeros(n)
    pos, acc_w = np.zeros((n, 3)), np.zeros((n, 3))
    ic = t0 + T * np.arange(strides + 1)
    turns = np.zeros(strides)
    turns[: len(turns_deg)] = turns_deg[:strides]
    heading, base = 0.0, np.zeros(2)
    for k in range(strides + 1):
        for a, b, turn in lobes:
            if k == strides and a > 0:  # the last IC: its loading response only
                break
            s = (time - ic[k] - a * T) / ((b - a) * T)
            pitch_rate += np.radians(turn) * _bump(s) / ((b - a) * T)
            pitch += np.radians(turn) * bump_integral(s)
        if k == strides:
            break
        d = (1 - pace.fc) * T
        s = (time - ic[k] - pace.fc * T) / d
        x, xdd = min_jerk(s)
        swing = (s >= 0) & (s <= 1)
        yaw = np.radians(turns[k])
        step = length_m * np.array([np.cos(heading + yaw / 2), np.sin(heading + yaw / 2)])
        pos[:, :2] += np.where(s[:, None] > 1, step, x[:, None] * step * (s[:, None] >= 0))
        acc_w[:, :2] += np.where(swing[:, None], xdd[:, None] * step / d**2, 0.0)
        pos[:, 2] += np.where(swing, clearance_m * np.sin(np.pi * s) ** 2, 0.0)
        acc_w[:, 2] += np.where(swing, clearance_m * 2 * (np.pi / d) ** 2 * np.cos(2 * np.pi * s),
                                0.0)
        yaw_rate += yaw * _bump(s) / d
        yaw_angle += yaw * bump_integral(s)
        heading += yaw
        base += step
    mount = exp3(rng.normal(size=3) * 0.6)
    R_foot = rot_z(yaw_angle) @ np.stack([exp3(np.array([0.0, p, 0.0])) for p in pitch])
    R = R_foot @ mount
    w_world = yaw_rate[:, None] * np.array([0.0, 0.0, 1.0]) + np.einsum(
        "nij,j->ni", rot_z(yaw_angle), np.array([0.0, 1.0, 0.0])) * pitch_rate[:, None]
    gyr = np.einsum("nji,nj->ni", R, w_world) + rng.normal(0, 0.01, (n, 3))
    acc_w[:, 2] += _impacts(time, ic[1:], pace.length_m / T)
    acc = np.einsum("nji,nj->ni", R, acc_w + [0.0, 0.0, G]) + rng.normal(0, 0.05, (n, 3))
    return FootWalk(time, rate_hz, gyr, acc, ic, ic[:-1] + pace.fc * T, pos,
                    np.full(strides, length_m), turns)
