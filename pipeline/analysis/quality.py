"""Quality gate of an IK run: implausible results flagged with their likely cause.

* **Residual:** the median orientation residual (the RMS over the sensors of the angle between
  each measured and modelled sensor orientation) above :data:`RESIDUAL_BOUND_DEG`: the sensors'
  orientations do not fit one skeleton. On the real OpenSense walking trial the median is 1.5 deg
  with the file's ``w, x, y, z`` order and 21.7 deg with the quaternions read as ``x, y, z, w``.
  Likely causes: the quaternion order, the sensor-to-segment mapping, ``--sensor-to-model``.
* **Joint limits:** a joint at one of its limits for more than :data:`AT_LIMIT_SHARE` of the
  frames: the IK pushes against the model (a mis-mounted sensor, a wrong heading, or a knee
  model that cannot follow the data). A straight knee at its extension limit while the subject
  stands still (the ``still`` samples: a standing trial's knees rest there) is not counted.
* **A leg at its limits:** on one leg, some joint at a limit in more than
  :data:`AT_LIMIT_LEG_SHARE` of the frames (a knee's ab/adduction swinging between its limits
  while the ankle sits at one, each joint alone below :data:`AT_LIMIT_SHARE`; a straight knee,
  at its extension limit, is not counted): that leg's sensors are likely faulty, mis-mounted or
  mis-mapped.
* **Heading:** the hip and knee flexion axes disagree (see
  :func:`pipeline.calibration.heading.anatomical_right`), or a thigh's heading could not be put
  in the pelvis's (6-D, neither its hip nor the other thigh could align it:
  :mod:`pipeline.process.heading_alignment`).
"""

from __future__ import annotations

import numpy as np

from pipeline.model.skeleton import Skeleton
from pipeline.quantiles import nanmedian

__all__ = ["AT_LIMIT_LEG_SHARE", "AT_LIMIT_SHARE", "AT_LIMIT_TOL", "RESIDUAL_BOUND_DEG",
           "quality_flags"]

RESIDUAL_BOUND_DEG = 5.0
AT_LIMIT_SHARE = 0.5
AT_LIMIT_TOL = 1e-3  # rad from the limit counts as at the limit
AT_LIMIT_LEG_SHARE = 0.3


def quality_flags(
    skeleton: Skeleton,
    q: np.ndarray,
    residual_rms: np.ndarray,
    notes: list[str] = (),
    joints: list[str] | None = None,
    still: np.ndarray | None = None,
) -> list[str]:
    """The flags of the module docstring, one line each (empty when the run looks plausible).

    ``joints``: the joints whose limits are checked (default all; unobserved joints held at a
    fixed value are better left out); ``still``: (N,) bool, the samples in which every sensor
    rests (:mod:`pipeline.process.still`)."""
    flags = []
    res = np.degrees(nanmedian(residual_rms))
    if not res <= RESIDUAL_BOUND_DEG:
        flags.append(
            f"median orientation residual {res:.1f} deg (plausible: below "
            f"{RESIDUAL_BOUND_DEG:g} deg): the sensors' orientations do not fit one skeleton; "
            "check the quaternion order (w, x, y, z), the sensor-to-segment mapping and "
            "--sensor-to-model"
        )
    ok = np.isfinite(q).all(axis=1)
    moving = ok if still is None else ok & ~np.asarray(still, dtype=bool)
    at_limit, legs = [], {}
    for joint in skeleton.joint_names if joints is None else joints:
        jm = skeleton.model.joints[skeleton.model.getJointId(joint)]
        if jm.nq != 1 or not ok.any():
            continue
        i = jm.idx_q
        lo, hi = skeleton.lower_limits[i], skeleton.upper_limits[i]
        held = (q[ok, i] <= lo + AT_LIMIT_TOL) | (q[ok, i] >= hi - AT_LIMIT_TOL)
        if joint.endswith(("_knee_Z", "_knee")):  # straight while standing still: the pose
            held &= moving[ok] | (q[ok, i] >= hi - AT_LIMIT_TOL)
        share = float(np.mean(held))
        if share > AT_LIMIT_SHARE:
            at_limit.append(f"{joint} ({100 * share:.0f}% of frames)")
        side = joint.split("_", 1)[0]
        if joint.endswith(("_knee_Z", "_knee")):  # a straight knee (its lower limit) is normal
            held = q[ok, i] >= hi - AT_LIMIT_TOL
        if held.any() and side in ("right", "left"):
            legs.setdefault(side, []).append((joint, held))
    for side, held in legs.items():
        share = float(np.mean(np.any([h for _, h in held], axis=0)))
        if share > AT_LIMIT_LEG_SHARE and not any(a.startswith(side) for a in at_limit):
            names = ", ".join(j for j, h in held if h.any())
            flags.append(f"the {side} leg has a joint at its limit in {100 * share:.0f}% of the "
                         f"frames ({names}): its sensors may be faulty, mis-mounted or mis-mapped")
    if at_limit:
        flags.append(
            "joints at their limits for a long share of the trial: " + ", ".join(at_limit)
            + "; likely a mis-mounted or mis-mapped sensor, a wrong heading, or a knee model "
            "that cannot follow the data (try --knee free)"
        )
    flags += [n for n in notes if "disagree" in n or "keeps its thigh sensor's heading" in n]
    return flags
