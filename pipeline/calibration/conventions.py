"""Names of the joint-constraint calibration, importable at no cost (the CLI's choices come
from here): the joints, the methods and the default one (see
:mod:`pipeline.calibration.calibrate` for what each method is)."""

from __future__ import annotations

__all__ = ["DEFAULT_METHOD", "JOINTS", "METHODS"]

METHODS = ("gn", "dwpso", "gwo", "ipopt")
DEFAULT_METHOD = "ipopt"
JOINTS = ("hinge", "spherical")
