"""``pipeline scale``: a subject-scaled URDF from the regression equations (Wang 2023 Table I)."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from pipeline.model.conventions import DEFAULT_KNEE
from pipeline.model.measures import Measures
from pipeline.model.scaling import scale_model

__all__ = ["run_scale"]


def run_scale(
    measures: Measures,
    out: str | Path,
    *,
    knee: str = DEFAULT_KNEE,
    knee_axis_femur: Sequence[float] | None = None,
    knee_axis_tibia: Sequence[float] | None = None,
) -> str:
    """Write the scaled URDF to ``out`` (see :func:`pipeline.model.scaling.scale_model`); return
    the line to print."""
    path = scale_model(measures, out, knee=knee, knee_axis_femur=knee_axis_femur,
                       knee_axis_tibia=knee_axis_tibia)
    return f"wrote {path}"
