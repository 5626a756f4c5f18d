"""From a subject's measures to a scaled model: Wang eq 14 (Table I) + the population knee AoR.

``scale_model`` is what ``pipeline scale`` runs: the regression equations give the landmark
positions in the segment frames (:func:`pipeline.model.anthropometry.predict_landmarks`), the knee
AoR defaults to the sex-specific population mean computed from the Wang 2023 dataset
(``models/wang2023_knee_aor.csv``), and :func:`pipeline.model.builder.build_urdf` writes the URDF,
which is then the single source of truth for every dimension downstream.
"""

from __future__ import annotations

import csv
import dataclasses
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.model.anthropometry import LandmarkPositions, RegressionTable, predict_landmarks
from pipeline.model.builder import build_urdf
from pipeline.model.geometry import (
    TEMPLATE_HEIGHT_M,
    TEMPLATE_HIP_OFFSET,
    SubjectGeometry,
    mirror_point,
)
from pipeline.model.measures import Measures
from pipeline.model.resources import models_file
from pipeline.rotations import normalize

KNEE_AOR_FILE = "wang2023_knee_aor.csv"

__all__ = ["HIP_SHARE_OF_PELVIS_WIDTH", "REGRESSION_HEIGHTS_M", "PopulationKneeAxis",
           "geometry_from_measures", "hip_centre", "population_knee_axis", "scale_model"]


@dataclass(frozen=True)
class PopulationKneeAxis:
    """Mean knee AoR of a sex group (unit vectors, right-leg ISB frames) and its spread (rad)."""

    sex: str
    n_subjects: int
    femur_axis: np.ndarray
    tibia_axis: np.ndarray
    sd_femur_transverse: float
    sd_femur_frontal: float
    sd_tibia_transverse: float
    sd_tibia_frontal: float


@lru_cache(maxsize=4)
def _aor_table(path: str) -> dict[str, PopulationKneeAxis]:
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(line for line in fh if not line.startswith("#")))
    out = {}
    for r in rows:
        try:
            f = np.array([float(r[f"femur_{a}"]) for a in "xyz"])
            t = np.array([float(r[f"tibia_{a}"]) for a in "xyz"])
            sds = [np.radians(float(r[k])) for k in (
                "sd_femur_transverse_deg", "sd_femur_frontal_deg",
                "sd_tibia_transverse_deg", "sd_tibia_frontal_deg")]
            out[r["sex"]] = PopulationKneeAxis(
                r["sex"], int(r["n_subjects"]), normalize(f), normalize(t), *sds
            )
        except (KeyError, ValueError) as exc:
            raise InputError(f"malformed row {r}: {exc}", file=path) from None
    return out


def population_knee_axis(sex: str = "all", path: str | Path | None = None) -> PopulationKneeAxis:
    """The shipped population knee AoR for ``sex`` in ('m', 'f', 'all')."""
    table = _aor_table(str(models_file(KNEE_AOR_FILE) if path is None else Path(path)))
    if sex not in table:
        raise InputError(f"expected sex among {sorted(table)}, got {sex!r}", field="sex")
    return table[sex]


def geometry_from_measures(
    measures: Measures,
    *,
    knee_axis_femur: np.ndarray | None = None,
    knee_axis_tibia: np.ndarray | None = None,
    table: RegressionTable | None = None,
    body_mass_kg: float | None = None,
    foot_length_m: float | None = None,
) -> tuple[SubjectGeometry, LandmarkPositions]:
    """Right-leg :class:`SubjectGeometry` from the regression equations (Wang eq 14).

    Knee axes default to the population mean of the subject's sex. Returns the geometry and the
    predicted landmarks (which carry the Table I row used for every coordinate, for reports).
    """
    landmarks = _landmarks_at(measures, table)
    aor = population_knee_axis(measures.sex)
    right_hip = hip_centre(measures)
    geometry = SubjectGeometry(
        sex=measures.sex,
        height_m=measures.height_m,
        femur_landmarks=landmarks.femur,
        tibia_landmarks=landmarks.tibia,
        knee_axis_femur=aor.femur_axis if knee_axis_femur is None else knee_axis_femur,
        knee_axis_tibia=aor.tibia_axis if knee_axis_tibia is None else knee_axis_tibia,
        body_mass_kg=body_mass_kg,
        foot_length_m=foot_length_m,
        right_hip=right_hip,
        left_hip=None if right_hip is None else mirror_point(right_hip),
    )
    return geometry, landmarks


#: The heights (m) the regression equations are used at, by sex: Wang 2023's subjects' (men
#: 1.69-1.88 m, women 1.55-1.75) and 0.1 m beyond. Linear in height with an intercept, they
#: extrapolate to proportions no body has (a 1.2 m woman's thigh 12 % of her height, a 2.4 m
#: man's 32 %); a subject outside is given the landmarks at the nearest bound, scaled by the
#: heights' ratio (geometric similarity, OpenSim's scaling by height).
REGRESSION_HEIGHTS_M = {"m": (1.59, 1.98), "f": (1.45, 1.85)}


def _landmarks_at(measures: Measures, table: RegressionTable | None) -> LandmarkPositions:
    """Eq 14 at the subject's height, or, outside :data:`REGRESSION_HEIGHTS_M` with height the
    only measure, at the nearest bound scaled by the heights' ratio."""
    low, high = REGRESSION_HEIGHTS_M[measures.sex]
    h = measures.height_m
    if low <= h <= high or set(measures.inputs_mm()) != {"h"}:
        return predict_landmarks(measures, table=table)
    bound = min(max(h, low), high)
    at = predict_landmarks(dataclasses.replace(measures, height_m=bound), table=table)
    k = h / bound
    return LandmarkPositions({n: k * p for n, p in at.femur.items()},
                             {n: k * p for n, p in at.tibia.items()}, at.equations)


#: The hip centre's distance from the midline as a share of the inter-ASIS distance: Bell et al.
#: 1989 (Hum Mov Sci 8:3-16) place it 14 % of that distance medial of each ASIS.
HIP_SHARE_OF_PELVIS_WIDTH = 0.5 - 0.14


def hip_centre(measures: Measures) -> np.ndarray | None:
    """The right hip centre in the pelvis frame when the pelvis width is measured: the
    template's, scaled with height, moved laterally to :data:`HIP_SHARE_OF_PELVIS_WIDTH` of the
    width; None when it is not (:class:`~pipeline.model.geometry.SubjectGeometry` then scales
    the template's)."""
    width = getattr(measures, "pelvis_width_m", None)  # the reproduction's samples have none
    if width is None:
        return None
    p = TEMPLATE_HIP_OFFSET * (measures.height_m / TEMPLATE_HEIGHT_M)
    p[2] = HIP_SHARE_OF_PELVIS_WIDTH * width
    return p


def scale_model(
    measures: Measures,
    out_path: str | Path,
    *,
    knee: str = "free",
    legs: tuple[str, ...] = ("right", "left"),
    knee_axis_femur: np.ndarray | None = None,
    knee_axis_tibia: np.ndarray | None = None,
) -> Path:
    """Write the subject's scaled URDF (``pipeline scale``) and return its path."""
    out_path = Path(out_path)
    if out_path.suffix.lower() != ".urdf":
        raise InputError("expected an output file ending in .urdf", file=out_path)
    geometry, _ = geometry_from_measures(
        measures, knee_axis_femur=knee_axis_femur, knee_axis_tibia=knee_axis_tibia
    )
    return build_urdf(geometry, out_path, knee=knee, legs=legs)
