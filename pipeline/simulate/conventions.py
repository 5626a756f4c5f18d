"""The simulated motions' names, importable at no cost (the CLI's choices come from here).

``gait`` (walking in place: both legs turn by sinusoids while the pelvis moves), ``walk``
(walking through the room: feet that stand on the floor, :mod:`pipeline.simulate.walk`),
``supine_hip_flexion`` (lying, right hip and knee flexing),
``still_thigh`` (seated knee extension, the thigh nearly still) and ``static`` (standing still);
the motions themselves are :mod:`pipeline.simulate.motions`.
"""

from __future__ import annotations

__all__ = ["MOTIONS", "STANDING_S"]

MOTIONS = ("gait", "walk", "supine_hip_flexion", "still_thigh", "static")
#: Seconds standing still first (the calibration pose) where the motion's rest pose is standing:
#: the default of ``pipeline simulate`` (gait, static) and ``pipeline demo``.
STANDING_S = 2.0
