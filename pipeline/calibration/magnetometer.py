"""Whether a sensor's magnetometer can be trusted for its heading: its field against the other
sensors' and over time.

A 9-D filter (and a vendor's fusion) takes the horizontal part of the measured field as magnetic
north. Near floors, furniture and the body's own electronics the field bends: its strength and
its dip (the angle between the field and the horizontal plane) leave the values the undisturbed
local field has everywhere in the room, and the heading that follows from it is wrong, by up to
180 deg. Per sample ``k`` of a sensor, with the world's vertical ``u_k`` in the sensor frame
(the sensor's inclination, which gravity observes whatever the field):

    norm_k = |m_k|,   dip_k = asin(m_k . u_k / |m_k|)                            (1)

The reference is what the sensors agree on: the median over the sensors of each sensor's median
norm and dip (with one sensor, its own). A sample is disturbed when its norm is more than
:data:`NORM_TOL` (relative) or its dip more than :data:`DIP_TOL_DEG` from the reference (VQF's
own thresholds for magnetic disturbance, ``magNormTh`` 0.1 and ``magDipTh`` 10 deg, Laidig & Seel
2023); a sensor is trusted when at most :data:`MAX_DISTURBED` of its samples are. Measured: on
the real walk ``gaittoolbox_s02`` the pelvis and thigh sensors have 0 % disturbed samples, the
shanks 30 and 93 %, the feet 40 and 70 %; on the x-IMU3 recording the pelvis 0 %, the thighs
5.5 and 25 %, shanks and feet 38-49 %.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

__all__ = ["DIP_TOL_DEG", "MAX_DISTURBED", "NORM_TOL", "FieldTrust", "field_trust"]

NORM_TOL = 0.10
DIP_TOL_DEG = 10.0
MAX_DISTURBED = 0.10


@dataclass(frozen=True)
class FieldTrust:
    """One sensor's field: ``trusted``; ``disturbed``: the share of disturbed samples;
    ``norm_range`` (2nd and 98th percentiles, relative to the reference) and ``dip_range_deg``;
    ``reference_dip_deg``; ``evidence``: the sentence a summary prints."""

    trusted: bool
    disturbed: float
    norm_range: tuple[float, float]
    dip_range_deg: tuple[float, float]
    reference_dip_deg: float
    evidence: str


def _norm_dip(mag: np.ndarray, up: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    m = np.asarray(mag, dtype=float)
    n = np.linalg.norm(m, axis=1)
    s = np.sum(m * np.asarray(up, dtype=float), axis=1) / np.where(n > 0, n, 1.0)
    return n, np.degrees(np.arcsin(np.clip(s, -1.0, 1.0)))


def field_trust(fields: Mapping[str, tuple[np.ndarray, np.ndarray]]) -> dict[str, FieldTrust]:
    """Sensor name -> :class:`FieldTrust` from ``(mag (N, 3), up (N, 3))`` per sensor, both in
    the sensor's frame (eq (1) of the module docstring). A sensor whose field is all zero or not
    finite is not trusted."""
    per = {name: _norm_dip(m, u) for name, (m, u) in fields.items()}
    alive = {k: v for k, v in per.items() if np.all(np.isfinite(v[0])) and np.median(v[0]) > 0}
    out: dict[str, FieldTrust] = {}
    if alive:
        ref_n = float(np.median([np.median(n) for n, _ in alive.values()]))
        ref_d = float(np.median([np.median(d) for _, d in alive.values()]))
    for name, (n, d) in per.items():
        if name not in alive:
            out[name] = FieldTrust(False, 1.0, (0.0, 0.0), (0.0, 0.0), float("nan"),
                                   "the magnetometer reads no field (all zero or not finite)")
            continue
        bad = (np.abs(n / ref_n - 1.0) > NORM_TOL) | (np.abs(d - ref_d) > DIP_TOL_DEG)
        share = float(bad.mean())
        nr = tuple(float(x) for x in np.percentile(n / ref_n, [2, 98]))
        dr = tuple(float(x) for x in np.percentile(d, [2, 98]))
        evidence = (f"field strength {nr[0]:.2f}-{nr[1]:.2f} of the sensors' common field, dip "
                    f"{dr[0]:.0f} to {dr[1]:.0f} deg (common {ref_d:.0f}); {100 * share:.0f}% of "
                    f"samples disturbed (beyond {100 * NORM_TOL:.0f}% or {DIP_TOL_DEG:g} deg)")
        out[name] = FieldTrust(share <= MAX_DISTURBED, share, nr, dr, ref_d, evidence)  # type: ignore[arg-type]
    return out
