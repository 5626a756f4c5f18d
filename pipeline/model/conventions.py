"""Names and modes of the subject model, importable at no cost (the CLI's choices come from here).

Segments per leg ``femur``, ``tibia``, ``foot`` (ISB frames, Wu 2002); anatomical landmarks per
leg ``HJC``, ``KJC``, ``AJC`` (joint centres), ``EFM``, ``EFL``, ``MM``, ``LM`` (epicondyles,
malleoli; Wang 2023) and ``HEE``, ``MT1``, ``MT5``, ``TOE`` (heel, first and fifth metatarsal
heads, toe tip); knee models ``free`` (Z-X-Y, Wang eq 15-17) and ``hinge`` (one rotation
about the knee AoR); ankle models ``universal`` (flexion, inversion) and ``free`` (a third
rotation, the foot's about its vertical axis relative to the tibia: the simulator's, for a tibia
that turns on its planted foot).
"""

from __future__ import annotations

__all__ = ["ANKLE_MODES", "DEFAULT_KNEE", "JOINT_SEGMENTS", "KNEE_MODES", "LANDMARKS",
           "LANDMARK_SEGMENT", "SEGMENTS", "landmark_segment", "other_side"]

KNEE_MODES = ("hinge", "free")
#: The knee model used when none is asked for, by the library and the CLI alike.
DEFAULT_KNEE = "free"
#: Ankle models, the first the model's (the subject model is always built with it).
ANKLE_MODES = ("universal", "free")
LANDMARKS = ("HJC", "KJC", "AJC", "EFM", "EFL", "MM", "LM", "HEE", "MT1", "MT5", "TOE")
SEGMENTS = ("femur", "tibia", "foot")
#: The segment each landmark is fixed in.
LANDMARK_SEGMENT = {"HJC": "femur", "KJC": "femur", "EFM": "femur", "EFL": "femur",
                    "AJC": "tibia", "MM": "tibia", "LM": "tibia",
                    "HEE": "foot", "MT1": "foot", "MT5": "foot", "TOE": "foot"}
#: Joint -> (proximal, distal) segment of one leg (the pelvis has no side), from the pelvis down.
JOINT_SEGMENTS = {"hip": ("pelvis", "femur"), "knee": ("femur", "tibia"),
                  "ankle": ("tibia", "foot")}


def landmark_segment(frame: str) -> str:
    """The segment a sided landmark is fixed in: ``'right_KJC'`` -> ``'right_femur'``."""
    side, landmark = frame.split("_", 1)
    return f"{side}_{LANDMARK_SEGMENT[landmark]}"


def other_side(side: str) -> str:
    """The other leg's side: ``'left'`` for ``'right'`` and back."""
    return "left" if side == "right" else "right"
