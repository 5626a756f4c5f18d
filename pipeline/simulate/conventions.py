"""The simulated motions' names, importable at no cost (the CLI's choices come from here).

``gait`` (walking, both legs), ``supine_hip_flexion`` (lying, right hip and knee flexing),
``still_thigh`` (seated knee extension, the thigh nearly still) and ``static`` (standing still);
the motions themselves are :mod:`pipeline.simulate.motions`.
"""

from __future__ import annotations

__all__ = ["MOTIONS", "STANDING_S"]

MOTIONS = ("gait", "supine_hip_flexion", "still_thigh", "static")
#: Seconds standing still first (the calibration pose) where the motion's rest pose is standing:
#: the default of ``pipeline simulate`` (gait, static) and ``pipeline demo``.
STANDING_S = 2.0
