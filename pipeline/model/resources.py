"""Where shipped data lives: the ``pipeline.models`` package (the repository's ``models/`` folder,
installed inside the package so that wheels carry it) and example-robot-data."""

from __future__ import annotations

import importlib.metadata
import importlib.resources
from functools import lru_cache
from pathlib import Path

__all__ = ["example_robot_data_share", "human_urdf", "models_file"]


def models_file(name: str) -> Path:
    """Path of a shipped file of ``pipeline.models``; raises ``FileNotFoundError`` naming it."""
    path = Path(str(importlib.resources.files("pipeline.models").joinpath(name)))
    if not path.is_file():
        raise FileNotFoundError(f"shipped model file missing: {path}")
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
