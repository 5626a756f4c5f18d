"""The simulated motions' names, importable at no cost (the CLI's choices come from here).

``gait`` (walking, both legs), ``supine_hip_flexion`` (lying, right hip and knee flexing),
``still_thigh`` (seated knee extension, the thigh nearly still) and ``static`` (standing still);
the motions themselves are :mod:`pipeline.simulate.motions`.
"""

from __future__ import annotations

__all__ = ["MOTIONS"]

MOTIONS = ("gait", "supine_hip_flexion", "still_thigh", "static")
