"""Landmark positions in segment frames from body dimensions (Wang et al. 2023, eq 14, Table I).

Eq 14, ``p_landmark = f(d_1, ..., d_n)``, is a set of linear regressions of one coordinate of an
anatomical landmark on one or two body dimensions, all in millimetres:

    p = b0 + b1 h              (equation "h")
    p = b0 + b1 h + b2 s_L     ("h+sL"),    s_L = |EFL - LM|  lateral shank length
    p = b0 + b1 h + b2 s_M     ("h+sM"),    s_M = |EFM - MM|  medial shank length
    p = b0 + b1 k              ("k"),       k   = |EFM - EFL| knee width
    p = b0 + b1 h + b2 a       ("h+a"),     a   = |MM - LM|   ankle width

EFM and EFL are given in the femoral frame (origin at the hip centre), MM and LM in the tibial frame
(origin at the knee centre = mid EFM-EFL); ISB axes of the RIGHT leg (x anterior, y proximal,
z right). A left leg uses the same numbers with z negated (:meth:`LandmarkPositions.for_left_leg`).
Femoral x is 0 by construction (x is normal to the plane hip centre-EFM-EFL). The coefficients ship
in ``models/wang2023_table1.csv`` (provenance and the reconstructed rows: ``wang2023_table1.md``).
Inside this module everything public is in metres; coefficients and fit reports stay in the
paper's millimetres (b1, b2 are dimensionless, so p[m] = b0/1000 + b1 d1[m] + b2 d2[m]).

Prediction (:func:`predict_landmarks`) takes, per coordinate, the usable equation with the smallest
cross-validated test-error SD (Wang §III.C). Fitting the equations (Wang §III.A: OLS per sex
group, R², overall F-test, K-fold cross-validation) is paper-only code:
:mod:`pipeline.reproduce.wang2023.regression`, whose fitted equations are this module's
:class:`RegressionEquation`.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.model.measures import Measures
from pipeline.model.resources import models_file

__all__ = [
    "AXES",
    "CSV_COLUMNS",
    "EQUATION_INPUTS",
    "EQUATION_TARGETS",
    "FEMUR_LANDMARKS",
    "GROUPS",
    "TIBIA_LANDMARKS",
    "LandmarkPositions",
    "RegressionEquation",
    "RegressionTable",
    "load_table1",
    "predict_landmarks",
    "select_equation",
]

TABLE1_FILE = "wang2023_table1.csv"
GROUPS = ("m", "f", "all")
FEMUR_LANDMARKS = ("EFM", "EFL")
TIBIA_LANDMARKS = ("MM", "LM")
AXES = ("x", "y", "z")
CSV_COLUMNS = ("sex", "equation", "landmark", "axis", "b0", "b1", "b2", "r2", "p")
CSV_COLUMNS += ("cv_mean_mm", "cv_sd_mm")
#: Inputs of each equation family, in the order of b1, b2.
EQUATION_INPUTS: dict[str, tuple[str, ...]] = {
    "h": ("h",),
    "h+sL": ("h", "s_L"),
    "h+sM": ("h", "s_M"),
    "k": ("k",),
    "h+a": ("h", "a"),
}
_ALL_H = tuple((lm, ax) for lm in FEMUR_LANDMARKS for ax in "yz")
_ALL_H += tuple((lm, ax) for lm in TIBIA_LANDMARKS for ax in AXES)
#: Which coordinates each family is fitted for in Table I.
EQUATION_TARGETS: dict[str, tuple[tuple[str, str], ...]] = {
    "h": _ALL_H,
    "h+sL": (("MM", "y"), ("LM", "y")),
    "h+sM": (("MM", "y"), ("LM", "y")),
    "k": (("EFM", "z"), ("EFL", "z")),
    "h+a": (("MM", "x"), ("MM", "z"), ("LM", "x"), ("LM", "z")),
}
@dataclass(frozen=True)
class RegressionEquation:
    """One row of Table I: p[mm] = b0 + b1 d1[mm] + b2 d2[mm], d = EQUATION_INPUTS[equation]."""

    sex: str
    equation: str
    landmark: str
    axis: str
    b0: float
    b1: float
    b2: float
    r2: float
    p: float
    cv_mean_mm: float
    cv_sd_mm: float
    source: str = "table"

    def __post_init__(self) -> None:
        if self.sex not in GROUPS:
            raise InputError(f"expected one of {GROUPS}, got {self.sex!r}", field="sex")
        if self.equation not in EQUATION_INPUTS:
            msg = f"expected one of {tuple(EQUATION_INPUTS)}, got {self.equation!r}"
            raise InputError(msg, field="equation")
        if (self.landmark, self.axis) not in EQUATION_TARGETS[self.equation]:
            msg = f"Table I has no {self.landmark} {self.axis} for equation {self.equation!r}"
            raise InputError(msg, field="landmark")
        for name in ("b0", "b1", "b2", "r2", "p", "cv_mean_mm", "cv_sd_mm"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise InputError(f"expected a finite number, got {value}", field=name)
            object.__setattr__(self, name, value)

    @property
    def inputs(self) -> tuple[str, ...]:
        """Names of the body dimensions multiplied by b1 (and b2)."""
        return EQUATION_INPUTS[self.equation]

    def evaluate_mm(self, inputs_mm: Mapping[str, float]) -> float:
        """b0 + b1 d1 + b2 d2 with the inputs in mm (KeyError if one is missing)."""
        d = [inputs_mm[name] for name in self.inputs] + [0.0]
        return self.b0 + self.b1 * d[0] + self.b2 * d[1]

    def label(self) -> str:
        return f"{self.sex}:{self.equation}"


@dataclass(frozen=True)
class RegressionTable:
    """A set of :class:`RegressionEquation` (at most one per sex, equation, landmark, axis)."""

    equations: tuple[RegressionEquation, ...]
    origin: str = ""

    def __post_init__(self) -> None:
        seen = set()
        for e in self.equations:
            key = (e.sex, e.equation, e.landmark, e.axis)
            if key in seen:
                raise InputError(f"duplicate row {key}", file=self.origin or None, field="equation")
            seen.add(key)

    def __iter__(self) -> Iterator[RegressionEquation]:
        return iter(self.equations)

    def __len__(self) -> int:
        return len(self.equations)

    def get(self, sex: str, equation: str, landmark: str, axis: str) -> RegressionEquation:
        for e in self.equations:
            if (e.sex, e.equation, e.landmark, e.axis) == (sex, equation, landmark, axis):
                return e
        raise KeyError(f"no row {sex}, {equation}, {landmark} {axis} in {self.origin or 'table'}")

    def candidates(self, sex: str, landmark: str, axis: str) -> list[RegressionEquation]:
        return [e for e in self.equations if (e.sex, e.landmark, e.axis) == (sex, landmark, axis)]


def load_table1(path: str | Path | None = None) -> RegressionTable:
    """Read Table I (or a table in the same CSV format; '#' lines are comments)."""
    path = models_file(TABLE1_FILE) if path is None else Path(path)
    if not path.is_file():
        raise InputError("regression table not found", file=path)
    with open(path, newline="", encoding="utf-8") as fh:
        lines = [line for line in fh if line.strip() and not line.lstrip().startswith("#")]
    reader = csv.DictReader(lines)
    missing = [c for c in CSV_COLUMNS if c not in (reader.fieldnames or [])]
    if missing:
        raise InputError(f"expected columns {CSV_COLUMNS}, missing {missing}", file=path)
    rows = []
    for i, row in enumerate(reader, start=1):
        try:
            numbers = {c: float(row[c]) for c in CSV_COLUMNS[4:]}
            rows.append(
                RegressionEquation(
                    sex=row["sex"].strip(),
                    equation=row["equation"].strip(),
                    landmark=row["landmark"].strip(),
                    axis=row["axis"].strip(),
                    source=(row.get("source") or "table").strip(),
                    **numbers,
                )
            )
        except (ValueError, TypeError, AttributeError) as exc:
            field = getattr(exc, "field", None)
            msg = getattr(exc, "message", str(exc))
            raise InputError(f"data row {i}: {msg}", file=path, field=field) from None
    return RegressionTable(tuple(rows), origin=str(path))


@lru_cache(maxsize=1)
def _shipped_table() -> RegressionTable:
    return load_table1()


@dataclass(frozen=True)
class LandmarkPositions:
    """Landmarks in their segment frames (m): femur EFM, EFL (femoral frame, origin hip centre);
    tibia MM, LM (tibial frame, origin knee centre). Right leg. ``equations[(landmark, axis)]`` is
    the Table I row used for that coordinate (None for femoral x, 0 by construction)."""

    femur: dict[str, np.ndarray]
    tibia: dict[str, np.ndarray]
    equations: dict[tuple[str, str], RegressionEquation | None]

    @property
    def knee_centre(self) -> np.ndarray:
        """Knee centre (mid EFM-EFL) in the femoral frame."""
        return 0.5 * (self.femur["EFM"] + self.femur["EFL"])

    @property
    def ankle_centre(self) -> np.ndarray:
        """Ankle centre (mid MM-LM) in the tibial frame."""
        return 0.5 * (self.tibia["MM"] + self.tibia["LM"])

    @property
    def thigh_length(self) -> float:
        return float(np.linalg.norm(self.knee_centre))

    @property
    def shank_length(self) -> float:
        return float(np.linalg.norm(self.ankle_centre))

    @property
    def knee_width(self) -> float:
        return float(np.linalg.norm(self.femur["EFM"] - self.femur["EFL"]))

    @property
    def ankle_width(self) -> float:
        return float(np.linalg.norm(self.tibia["MM"] - self.tibia["LM"]))

    def for_left_leg(self) -> LandmarkPositions:
        """The same landmarks for a left leg: z negated, so that z still points to the right."""
        flip = np.array([1.0, 1.0, -1.0])
        return LandmarkPositions(
            {k: v * flip for k, v in self.femur.items()},
            {k: v * flip for k, v in self.tibia.items()},
            dict(self.equations),
        )

    def describe(self) -> list[str]:
        """One line per coordinate: value in mm and the equation used (for reports)."""
        lines = []
        for seg in (self.femur, self.tibia):
            for landmark, p in seg.items():
                for i, axis in enumerate(AXES):
                    e = self.equations[(landmark, axis)]
                    how = "0 by construction" if e is None else f"{e.label()} (SD {e.cv_sd_mm} mm)"
                    lines.append(f"{landmark} {axis} = {1000 * p[i]:8.1f} mm  [{how}]")
        return lines


def select_equation(
    candidates: Sequence[RegressionEquation], inputs_mm: Mapping[str, float]
) -> RegressionEquation | None:
    """Among the equations whose inputs are all available, the one with the smallest test-error SD
    (Wang §III.C: "the regression equation with the smallest SD"); ties go to fewer inputs, then
    to Table I order (h, h+sL, h+sM, k, h+a). None if no candidate is usable."""
    order = list(EQUATION_INPUTS)
    usable = [e for e in candidates if all(name in inputs_mm for name in e.inputs)]
    if not usable:
        return None
    return min(usable, key=lambda e: (e.cv_sd_mm, len(e.inputs), order.index(e.equation)))


def predict_landmarks(
    measures: Measures, table: RegressionTable | None = None, sex_specific: bool = True
) -> LandmarkPositions:
    """Eq 14: every landmark coordinate from the best available Table I equation, in metres.

    ``sex_specific`` picks the subject's sex rows, else the 'all' rows."""
    table = _shipped_table() if table is None else table
    group = measures.sex if sex_specific else "all"
    inputs = measures.inputs_mm()
    used: dict[tuple[str, str], RegressionEquation | None] = {}
    out: dict[str, np.ndarray] = {}
    for landmark in FEMUR_LANDMARKS + TIBIA_LANDMARKS:
        p = np.zeros(3)
        for i, axis in enumerate(AXES):
            if landmark in FEMUR_LANDMARKS and axis == "x":
                used[(landmark, axis)] = None
                continue
            e = select_equation(table.candidates(group, landmark, axis), inputs)
            if e is None:
                have = sorted(inputs)
                msg = f"no equation for {landmark} {axis} in group {group!r} with inputs {have}"
                raise InputError(msg, file=table.origin or None, field=f"{landmark}.{axis}")
            p[i] = e.evaluate_mm(inputs) / 1000.0
            used[(landmark, axis)] = e
        out[landmark] = p
    femur = {k: out[k] for k in FEMUR_LANDMARKS}
    tibia = {k: out[k] for k in TIBIA_LANDMARKS}
    return LandmarkPositions(femur, tibia, used)


# Fitting the equations (Wang §III.A) lives in :mod:`pipeline.reproduce.wang2023.regression`.
