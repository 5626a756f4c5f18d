"""Where shipped data lives: the repository's ``models/`` folder and example-robot-data."""

from __future__ import annotations

import importlib.metadata
from functools import lru_cache
from pathlib import Path

MODELS_DIR = Path(__file__).resolve().parents[1] / "models"


def models_file(name: str) -> Path:
    """Path of a shipped file in ``models/``; raises ``FileNotFoundError`` naming it."""
    path = MODELS_DIR / name
    if not path.exists():
        raise FileNotFoundError(f"shipped model file missing: {path} (is the install editable?)")
    return path


@lru_cache(maxsize=1)
def example_robot_data_share() -> Path:
    """``.../share/example-robot-data`` of the installed example-robot-data distribution.

    Found through the distribution's file list (DESIGN.md §8), not a hard-coded path.
    """
    for f in importlib.metadata.files("example-robot-data") or []:
        s = str(f)
        if s.endswith("human_description/robots/human.urdf"):
            return Path(f.locate()).resolve().parents[3]
    raise FileNotFoundError("example-robot-data's human_description/robots/human.urdf not found")


def human_urdf() -> Path:
    """Gepetto's human model URDF shipped by example-robot-data."""
    return example_robot_data_share() / "robots" / "human_description" / "robots" / "human.urdf"
