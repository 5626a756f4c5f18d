"""Heading drift between two sensors held consistent by a hinge joint (magnetometer-free).

Without a magnetometer (or with a disturbed one) an attitude filter observes each sensor's
inclination from gravity but not its heading: every sensor's world turns about the vertical by a
heading error ``delta_i(t)`` of its own (a constant from its start plus the integrated vertical
gyro bias). A hinge joint ties two sensors together: its axis, fixed in each sensor's frame
(``j_1`` in the proximal sensor, ``j_2`` in the distal one), is one line in the world,

    R_1(t) j_1 = R_2(t) j_2                                                   (hinge)

(Seel et al. 2014's knee constraint, Hu 2021 eq 4-6 in terms of the gyroscopes). With filtered
orientations ``R_i = Rz(delta_i) R_i^true`` this reads ``u(t) = Rz(psi(t)) v(t)`` with
``u = R_1 j_1``, ``v = R_2 j_2`` and ``psi = delta_1 - delta_2``: the distal sensor's heading
relative to the proximal one. Over a window of samples ``k``, the least-squares heading

    psi = argmin sum_k |u_k - Rz(psi) v_k|^2
        = atan2(sum_k g . (v_k x u_k), sum_k (u_k^h . v_k^h))                 (1)

(``g`` the unit vertical, ``^h`` the horizontal part: ``u . Rz(psi) v = cos(psi) u^h . v^h +
sin(psi) g . (v x u) + (u . g)(v . g)``), is exact for a hinge and weights each sample by how
horizontal the axis is (a vertical axis says nothing about heading). :func:`hinge_heading`
solves (1) on overlapping windows and interpolates between their centres (exact for a constant
heading; a heading that drifts linearly within a window gives its weighted mean there, the
centre's value when the weights are equal); turning the distal sensor's orientations by
``Rz(psi(t))`` puts it in the proximal sensor's world for the whole trial.

A ball joint (hip, ankle) gives the same equation with ``u = R_1 f_1`` and ``v = R_2 f_2``, the
specific force at the joint centre (Hu 2021 eq 2, ``f_i = a_i + Gamma_i(o_i)`` with the joint
positions ``o_i`` of its spherical calibration, eq 1-3) seen by each sensor: one physical vector
whose horizontal part, while the joint accelerates, fixes the heading between the sensors
(Laidig et al. 2017; Weygers et al. 2020 use the same constraint for drift-free joint angles).

The knee is not a perfect hinge (a few degrees of ab/adduction and rotation in gait): that part
enters (1) as noise that the window averages. The vertical components of ``u`` and ``v`` must
agree whatever the heading (gravity observes them): their disagreement is reported as a check.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.io.gaps import true_runs
from pipeline.rotations import exp3, normalize

__all__ = [
    "MIN_ACCELERATION",
    "MIN_AGREEMENT",
    "MIN_HORIZONTAL",
    "WINDOW_S",
    "HeadingDrift",
    "heading_between",
    "hinge_heading",
    "turn_about_vertical",
    "vertical_turn",
]

#: Window length (s) of (1); the windows overlap by half.
WINDOW_S = 2.0
#: A window is used when its mean ``|u^h| |v^h|`` (the product of the two axes' horizontal
#: lengths) is at least this: the hinge axis within ~60 deg of horizontal on average.
MIN_HORIZONTAL = 0.25
#: For a ball joint the vector is the specific force at the joint centre (Hu 2021 eq 2) as each
#: sensor sees it, one physical vector: its horizontal part (m/s^2) observes the heading. A window
#: is used when the mean product of the two horizontal lengths is at least this squared (standing
#: still says nothing; walking gives 1-3 m/s^2).
MIN_ACCELERATION = 0.3
#: A window is used only when its samples agree on the heading: the weighted mean resultant length
#: ``|sum_k (cos_k, sin_k)| / sum_k |u_k^h| |v_k^h|`` of eq (1) is at least this (1: every sample
#: gives the same heading; 0.9: a circular spread of ~26 deg). A joint that breaks the constraint
#: in a window (impacts, soft tissue, a knee far from a hinge) leaves that window out.
MIN_AGREEMENT = 0.9


@dataclass(frozen=True)
class HeadingDrift:
    """``psi`` (N,) rad: the heading that turns the distal sensor's world into the proximal's
    (continuous, unwrapped); ``residual_deg``: RMS angle between ``u`` and ``Rz(psi) v`` after
    the turn, and ``before_deg`` with the trial's mean heading only (a constant offset, what a
    standing calibration absorbs); ``vertical_deg``: RMS disagreement of the axes' elevations
    (independent of heading: a check of the axes and the filter's inclination); ``windows`` /
    ``used``: windows solved / informative (:data:`MIN_HORIZONTAL`)."""

    psi: np.ndarray
    residual_deg: float
    before_deg: float
    vertical_deg: float
    windows: int
    used: int

    @property
    def drift_deg(self) -> float:
        """Range of ``psi`` over the trial (deg): how far the two headings drifted apart."""
        return float(np.degrees(np.nanmax(self.psi) - np.nanmin(self.psi)))


def turn_about_vertical(R: np.ndarray, psi: np.ndarray, up: np.ndarray) -> np.ndarray:
    """``Rz(psi_k) R_k`` for (N, 3, 3) ``R`` and (N,) ``psi`` (rad), the turn about the unit
    world vertical ``up`` (:func:`pipeline.rotations.exp3` of ``psi_k up``)."""
    g = normalize(np.asarray(up, float))
    return exp3(np.outer(psi, g)) @ R


def vertical_turn(after: np.ndarray, before: np.ndarray) -> np.ndarray:
    """(N,) rad: the turn about the y-up vertical that takes orientations ``before`` (N, 3, 3)
    to ``after`` (:func:`turn_about_vertical`'s ``psi``, read back; NaN where either is)."""
    M = np.asarray(after, float) @ np.swapaxes(np.asarray(before, float), 1, 2)
    return np.arctan2(M[:, 0, 2], M[:, 0, 0])


def hinge_heading(
    R_1: np.ndarray,
    R_2: np.ndarray,
    axis_1: np.ndarray,
    axis_2: np.ndarray,
    rate_hz: float,
    *,
    up: np.ndarray = (0.0, 1.0, 0.0),
    window_s: float = WINDOW_S,
    breaks: np.ndarray | None = None,
) -> HeadingDrift:
    """Eq (1) of the module docstring for a hinge: ``u = R_1 j_1``, ``v = R_2 j_2``.

    ``R_1``, ``R_2``: (N, 3, 3) sensor -> world orientations of the proximal and distal sensor
    (filter output, world vertical ``up``); ``axis_1``, ``axis_2``: the hinge axis in each
    sensor's frame, signed alike (both pointing to the subject's right, say). Windows whose axis
    is too close to vertical (:data:`MIN_HORIZONTAL`) are skipped; ``breaks`` as
    :func:`heading_between` takes them."""
    R_1, R_2 = np.asarray(R_1, float), np.asarray(R_2, float)
    if R_1.shape != R_2.shape or R_1.ndim != 3 or R_1.shape[1:] != (3, 3):
        raise InputError(f"expected two (N, 3, 3) orientation series of one length, got "
                         f"{R_1.shape} and {R_2.shape}", field="orientations")
    u = R_1 @ normalize(np.asarray(axis_1, float))
    v = R_2 @ normalize(np.asarray(axis_2, float))
    return heading_between(u, v, rate_hz, up=up, window_s=window_s, min_weight=MIN_HORIZONTAL,
                           breaks=breaks)


def heading_between(
    u: np.ndarray,
    v: np.ndarray,
    rate_hz: float,
    *,
    up: np.ndarray = (0.0, 1.0, 0.0),
    window_s: float = WINDOW_S,
    min_weight: float = MIN_HORIZONTAL,
    min_agreement: float = MIN_AGREEMENT,
    breaks: np.ndarray | None = None,
) -> HeadingDrift:
    """Eq (1) on windows of ``window_s`` (half overlapping) for world vectors ``u`` (N, 3), seen
    by the proximal sensor, and ``v``, the same vector seen by the distal one.

    A window is informative when its mean ``|u^h| |v^h|`` is at least ``min_weight`` (units of
    ``u`` times ``v``) and its samples agree (``min_agreement``, :data:`MIN_AGREEMENT`); ``psi``
    is interpolated linearly between the informative windows' centres (held at the ends). Rows
    with NaN are ignored. ``breaks`` (N,) bool: rows across which the heading may jump (a filter
    that started again after a sensor's gap, with a heading of its own): no window crosses them,
    each run between them has its own headings, NaN over a run without an informative window
    (:func:`_psi_by_runs`). Refused
    (:class:`InputError`) when no window is informative, saying why. The residuals of
    :class:`HeadingDrift` are over the informative windows' samples."""
    u, v = np.asarray(u, float), np.asarray(v, float)
    if u.shape != v.shape or u.ndim != 2 or u.shape[1] != 3:
        raise InputError(f"expected two (N, 3) vector series of one length, got {u.shape} and "
                         f"{v.shape}", field="orientations")
    if not (np.isfinite(rate_hz) and rate_hz > 0 and window_s > 0):
        raise InputError(f"expected a positive rate and window, got {rate_hz}, {window_s}",
                         field="rate_hz")
    g = normalize(np.asarray(up, float))
    n = len(u)
    ok = np.all(np.isfinite(u), axis=1) & np.all(np.isfinite(v), axis=1)
    u, v = np.where(ok[:, None], u, 0.0), np.where(ok[:, None], v, 0.0)
    u_h = u - np.outer(u @ g, g)
    v_h = v - np.outer(v @ g, g)
    sin_w = np.cross(v, u) @ g  # |u^h||v^h| sin(psi_k)
    cos_w = np.einsum("ni,ni->n", u_h, v_h)  # |u^h||v^h| cos(psi_k)
    weight = np.linalg.norm(u_h, axis=1) * np.linalg.norm(v_h, axis=1)

    width = max(2, int(round(window_s * rate_hz)))
    runs = [(0, n)] if breaks is None or not np.any(breaks) else true_runs(~np.asarray(breaks))
    windows = _windows(runs, width)
    centres, angles = [], []
    used_rows = np.zeros(n, dtype=bool)
    horizontal = 0
    for rows in windows:
        count = int(ok[rows].sum())
        if count == 0 or weight[rows].sum() / count < min_weight:
            continue
        horizontal += 1
        # the weighted per-sample headings' mean resultant length: 1 when they all agree
        if np.hypot(sin_w[rows].sum(), cos_w[rows].sum()) < min_agreement * weight[rows].sum():
            continue
        angles.append(np.arctan2(sin_w[rows].sum(), cos_w[rows].sum()))
        centres.append(0.5 * (rows.start + rows.stop - 1))
        used_rows[rows] = True
    if not horizontal:
        raise InputError("the vectors are too close to vertical in every window (mean "
                         f"|u_h||v_h| < {min_weight:g}): the heading between the two sensors is "
                         "not observable", field="orientations")
    if not angles:
        raise InputError(f"the two sensors' views of it do not agree within any window "
                         f"(agreement < {min_agreement:g}): the joint does not hold the constraint",
                         field="orientations")
    psi = _psi_by_runs(runs, n, centres, angles)
    sel = ok & used_rows

    def rms_deg(turn: np.ndarray) -> float:
        b = turn_about_vertical(v[sel][..., None], turn[sel], g)[..., 0]
        c = np.einsum("ni,ni->n", _unit(u[sel]), _unit(b))
        return float(np.degrees(np.sqrt(np.mean(np.arccos(np.clip(c, -1.0, 1.0)) ** 2))))

    mean_psi = np.full(n, np.arctan2(sin_w[sel].sum(), cos_w[sel].sum()))
    el_u = np.arcsin(np.clip(_unit(u[sel]) @ g, -1, 1))
    el_v = np.arcsin(np.clip(_unit(v[sel]) @ g, -1, 1))
    return HeadingDrift(psi, rms_deg(psi), rms_deg(mean_psi),
                        float(np.degrees(np.sqrt(np.mean((el_u - el_v) ** 2)))), len(windows),
                        len(angles))


def _psi_by_runs(runs: list[tuple[int, int]], n: int, centres: list[float],
                 angles: list[float]) -> np.ndarray:
    """``psi`` per row: within each run from that run's informative windows alone (interpolated
    between their centres, held at the run's ends), NaN over a run without one (the heading is
    not observed there); the break rows between runs interpolated across (a sensor missing
    there)."""
    psi = np.interp(np.arange(n), centres, np.unwrap(angles))
    if len(runs) < 2:
        return psi
    c, ang = np.asarray(centres), np.asarray(angles)
    for a, b in runs:
        mine = (c >= a) & (c < b)
        rows = np.arange(a, b)
        psi[a:b] = np.interp(rows, c[mine], np.unwrap(ang[mine])) if mine.any() else np.nan
    return psi


def _windows(runs: list[tuple[int, int]], width: int) -> list[slice]:
    """Half-overlapping windows of ``width`` rows within each run (one window of a run shorter
    than ``width``)."""
    hop = max(1, width // 2)
    out = []
    for a, b in runs:
        out += [slice(s, min(s + width, b)) for s in range(a, max(b - width, a) + 1, hop)]
    return out


def _unit(x: np.ndarray) -> np.ndarray:
    """Rows of ``x`` made unit; zero rows stay zero (an acceleration may vanish)."""
    n = np.linalg.norm(x, axis=1, keepdims=True)
    return x / np.where(n > 0, n, 1.0)
