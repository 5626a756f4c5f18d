"""A foot sensor's path through the room by strapdown integration with zero-velocity updates.

Between two rests (:func:`pipeline.analysis.gait_events.rest_periods`) the sensor's orientation
is the gyroscope's integral, ``R_{k+1} = R_k exp((w_k + w_{k+1}) dt / 2)``; at each rest its tilt
is reset so that the mean specific force points up (``R a = |a| z``: the smallest rotation, the
heading kept), as the zero-velocity-aided inertial navigation of Foxlin 2005 (IEEE CG&A 25(6))
and Skog et al. 2010. The acceleration in the world, ``R a - g z``, integrates to a velocity that
must be zero at the next rest: its error, which grows with the integration time, is removed
linearly over the swing (Mariani et al. 2010, J Biomech 43(15), "de-drifting"); the velocity
integrates to the position; on a level floor (the default) each swing's remaining height drift
is removed the same way, so that the foot rests at one height. The world is z up with the
heading of the sensor's first rest; lengths and heights need no more.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.rotations import exp3, rotation_aligning

__all__ = ["FootTrajectory", "foot_trajectory"]

G = 9.81
UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class FootTrajectory:
    """``position`` (N, 3) m and ``rotation`` (N, 3, 3) sensor -> world (z up) of one foot
    sensor; NaN before its first rest and after its last."""

    position: np.ndarray
    rotation: np.ndarray


def _levelled(R: np.ndarray, acc_at_rest: np.ndarray) -> np.ndarray:
    """``R`` turned by the smallest rotation that makes the mean specific force point up."""
    return rotation_aligning(R @ acc_at_rest, UP) @ R


def _orientations(gyr: np.ndarray, acc: np.ndarray, rate_hz: float, rests: np.ndarray):
    n, dt = len(gyr), 1.0 / rate_hz
    R = np.full((n, 3, 3), np.nan)
    a0, b0 = rests[0]
    R[a0] = _levelled(np.eye(3), np.nanmean(acc[a0:b0], axis=0))
    rest_start = {int(a): int(b) for a, b in rests}
    g = np.nan_to_num(gyr)
    steps = exp3(0.5 * (g[:-1] + g[1:]) * dt)  # the rate over each interval: trapezoidal
    last = int(rests[-1][1])
    for k in range(a0, last - 1):
        if k in rest_start and k != a0:
            R[k] = _levelled(R[k], np.nanmean(acc[k:rest_start[k]], axis=0))
        R[k + 1] = R[k] @ steps[k]
    return R


def _level(p: np.ndarray, rests: np.ndarray, up: int) -> None:
    """Each swing's height (coordinate ``up``) drift removed linearly, so that every rest is at
    the first one's height (in place)."""
    for (_, a), (b, _) in zip(rests[:-1], rests[1:], strict=True):
        if b <= a:
            continue
        rise = p[b, up] - p[a - 1, up]
        p[a:b, up] -= rise * np.arange(1, b - a + 1) / (b - a + 1)
        p[b:, up] -= rise


def foot_trajectory(gyr: np.ndarray, acc: np.ndarray, rate_hz: float, rests: np.ndarray,
                    level_floor: bool = True, rotation: np.ndarray | None = None,
                    up: int = 2) -> FootTrajectory:
    """The sensor's path and orientation from its first rest to its last (module docstring);
    ``level_floor``: every rest at the same height (a level floor; off for stairs or slopes).
    ``rotation`` (N, 3, 3) sensor -> world: orientations known already (e.g. the IK's, in the
    model's world, whose vertical is axis ``up``: 1 for y up) instead of the integration here."""
    n = len(gyr)
    if len(rests) == 0:
        return FootTrajectory(np.full((n, 3), np.nan), np.full((n, 3, 3), np.nan))
    vertical = np.eye(3)[up]
    R = _orientations(gyr, acc, rate_hz, rests) if rotation is None else np.array(rotation)
    free = np.einsum("nij,nj->ni", R, np.nan_to_num(acc)) - G * vertical
    dt = 1.0 / rate_hz
    v = np.zeros((n, 3))
    for (_, a), (b, _) in zip(rests[:-1], rests[1:], strict=True):
        if b <= a:
            continue
        vel = np.cumsum(free[a:b] * dt, axis=0)
        drift = vel[-1] * (np.arange(1, b - a + 1) / (b - a))[:, None]
        v[a:b] = vel - drift
    first, last = int(rests[0][0]), int(rests[-1][1])
    p = np.full((n, 3), np.nan)
    p[first:last] = np.cumsum(v[first:last] * dt, axis=0)
    if level_floor:
        _level(p, rests, up)
    R[:first] = np.nan
    R[last:] = np.nan
    return FootTrajectory(p, R)
