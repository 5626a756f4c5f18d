"""Where shipped data lives: the ``pipeline.models`` package (the repository's ``models/`` folder,
installed inside the package so that wheels carry it) and example-robot-data."""

from __future__ import annotations

import importlib
import sys
from functools import lru_cache
from pathlib import Path

__all__ = ["example_robot_data_share", "human_urdf", "models_file"]


def models_file(name: str) -> Path:
    """Path of a shipped file of ``pipeline.models``; raises ``FileNotFoundError`` naming it.
    The package's folder from its ``__file__`` (installed or editable, the files are on disk;
    ``importlib.resources`` would import ``zipfile`` for it)."""
    path = Path(importlib.import_module("pipeline.models").__file__).parent / name
    if not path.is_file():
        raise FileNotFoundError(f"shipped model file missing: {path}")
    return path


_HUMAN_URDF = "human_description/robots/human.urdf"


@lru_cache(maxsize=1)
def example_robot_data_share() -> Path:
    """``.../share/example-robot-data`` of the installed example-robot-data distribution.

    Found through the distribution's file list (DESIGN.md §8), not a hard-coded path: the
    ``RECORD`` of its ``.dist-info`` folder on ``sys.path``, read directly (importing
    ``importlib.metadata`` costs a command ~35 ms), else ``importlib.metadata.files``.
    """
    for folder in map(Path, sys.path):
        for info in folder.glob("example_robot_data-*.dist-info") if folder.is_dir() else ():
            try:
                lines = (info / "RECORD").read_text(encoding="utf-8").splitlines()
            except OSError:
                continue
            for line in lines:
                name = line.rsplit(",", 2)[0]
                if name.endswith(_HUMAN_URDF) and (folder / name).is_file():
                    return (folder / name).resolve().parents[3]
    import importlib.metadata  # an installation without a RECORD file

    for f in importlib.metadata.files("example-robot-data") or []:
        if str(f).endswith(_HUMAN_URDF):
            return Path(f.locate()).resolve().parents[3]
    raise FileNotFoundError(f"example-robot-data's {_HUMAN_URDF} not found")


def human_urdf() -> Path:
    """Gepetto's human model URDF shipped by example-robot-data."""
    return example_robot_data_share() / "robots" / "human_description" / "robots" / "human.urdf"
