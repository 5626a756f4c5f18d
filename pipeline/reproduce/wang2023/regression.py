"""Fitting the landmark regressions of Table I on a set of subjects (Wang et al. 2023, §III.A).

For each sex group ('m', 'f', 'all') and each equation family of :data:`EQUATION_TARGETS`
(inputs :data:`EQUATION_INPUTS`, millimetres as in the paper):

* OLS on the whole group, ``y = X b`` with ``X = [1, d1, (d2)]``, ``b = argmin |y - X b|^2``;
* R² ``= 1 - SS_res / SS_tot``;
* the overall F-test of the regression, ``F = ((SS_tot - SS_res) / q) / (SS_res / (n - q - 1))``
  with ``q`` inputs, ``p = P(F_{q, n-q-1} > F)``;
* K-fold cross-validation: the subjects are split once into K seeded parts shared by every
  equation of the group; each fold fits on K-1 parts and tests on the held-out one. The reported
  coefficients are the mean of the K folds' coefficients, the test error (measured - predicted,
  pooled over folds) gives ``cv_mean_mm`` and ``cv_sd_mm``.

The results convert to :class:`~pipeline.model.anthropometry.RegressionEquation` rows, so a fitted
table is used by :func:`~pipeline.model.anthropometry.predict_landmarks` exactly like the shipped
Table I. These names are also importable from :mod:`pipeline.model.anthropometry` (where they used
to live).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy import stats

from pipeline.errors import InputError
from pipeline.io.atomic import write_text_atomic
from pipeline.io.tables import csv_text
from pipeline.model.anthropometry import (
    AXES,
    CSV_COLUMNS,
    EQUATION_INPUTS,
    EQUATION_TARGETS,
    GROUPS,
    RegressionEquation,
    RegressionTable,
)
from pipeline.model.measures import FIELD_OF_INPUT, Measures

__all__ = [
    "FitResult",
    "SubjectSample",
    "fit_results_to_rows",
    "fit_table",
    "kfold_indices",
    "table_from_fits",
    "write_fit_csv",
]


@dataclass(frozen=True)
class SubjectSample:
    """One subject's dimensions (m) and landmarks in segment frames (m): efm, efl in the femoral
    frame (origin hip centre), mm, lm in the tibial frame (origin knee centre)."""

    subject_id: str | int
    sex: str
    height_m: float
    shank_lateral_m: float
    shank_medial_m: float
    knee_width_m: float
    ankle_width_m: float
    efm: np.ndarray
    efl: np.ndarray
    mm: np.ndarray
    lm: np.ndarray

    def __post_init__(self) -> None:
        names = ["sex", *FIELD_OF_INPUT.values()]  # the regression's inputs
        try:
            for n in names:
                if getattr(self, n) is None:
                    raise InputError("required for fitting, got None", field=n)
            m = Measures(**{n: getattr(self, n) for n in names})
            for n in names:
                object.__setattr__(self, n, getattr(m, n))
            for n in ("efm", "efl", "mm", "lm"):
                try:
                    v = np.asarray(getattr(self, n), dtype=float)
                except (TypeError, ValueError):
                    raise InputError("expected 3 numbers (m)", field=n) from None
                if v.shape != (3,) or not np.all(np.isfinite(v)):
                    raise InputError(f"expected 3 finite numbers (m), got {v!r}", field=n)
                if np.linalg.norm(v) > 1.0:
                    raise InputError(f"expected metres in a segment frame, got {v}", field=n)
                object.__setattr__(self, n, v)
        except InputError as exc:
            msg = f"subject {self.subject_id}: {exc.message}"
            raise InputError(msg, field=exc.field) from None

    def measures(self) -> Measures:
        return Measures(self.sex, self.height_m, self.shank_lateral_m, self.shank_medial_m,
                        self.knee_width_m, self.ankle_width_m)

    def coordinate_mm(self, landmark: str, axis: str) -> float:
        return 1000.0 * float(getattr(self, landmark.lower())[AXES.index(axis)])


@dataclass(frozen=True)
class FitResult(RegressionEquation):
    """One fitted equation: a :class:`RegressionEquation` (``source='fit'``) whose b0..b2 are the
    mean over the K folds' coefficients (mm, mm/mm; b2 = 0 for one input); r2, p: OLS on the whole
    group and its overall F-test; cv_*: held-out test error (measured - predicted, pooled over
    folds), mean and SD (ddof 1). Adds the group size ``n``, ``k_folds``, the whole-group OLS
    coefficients ``coef_full_mm`` and the per-fold ones ``coef_folds_mm`` (K, 3)."""

    n: int = 0
    k_folds: int = 0
    coef_full_mm: tuple[float, float, float] = (math.nan, math.nan, math.nan)
    coef_folds_mm: np.ndarray | None = None

    def to_equation(self) -> RegressionEquation:
        values = {c: getattr(self, c) for c in CSV_COLUMNS}
        return RegressionEquation(**values, source="fit")


def kfold_indices(n: int, k_folds: int, seed: int = 0) -> list[np.ndarray]:
    """K near-equal disjoint parts of range(n) after a seeded random permutation."""
    perm = np.random.default_rng(seed).permutation(n)
    return [np.sort(part) for part in np.array_split(perm, k_folds)]


def _min_group_size(k_folds: int, n_coef: int) -> int:
    n = k_folds
    while n - math.ceil(n / k_folds) < n_coef + 1:  # each training set: more rows than unknowns
        n += 1
    return n


def _ols(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return np.linalg.lstsq(x, y, rcond=None)[0]


def _fit_one(x: np.ndarray, y: np.ndarray, folds: list[np.ndarray]) -> dict:
    n, n_coef = x.shape
    coef = _ols(x, y)
    ss_res = float(np.sum((y - x @ coef) ** 2))
    ss_tot = float(np.sum((y - y.mean()) ** 2))
    r2 = 1.0 - ss_res / ss_tot if ss_tot > 0 else float("nan")
    q, dof = n_coef - 1, n - n_coef
    if ss_tot <= 0:
        p = float("nan")
    elif ss_res <= 1e-12 * ss_tot:
        p = 0.0
    else:
        p = float(stats.f.sf(((ss_tot - ss_res) / q) / (ss_res / dof), q, dof))
    fold_coefs, errors = [], []
    for test in folds:
        train = np.setdiff1d(np.arange(n), test)
        c = _ols(x[train], y[train])
        fold_coefs.append(c)
        errors.append(y[test] - x[test] @ c)
    e = np.concatenate(errors)
    pad = np.zeros((len(folds), 3))
    pad[:, :n_coef] = fold_coefs
    full = np.zeros(3)
    full[:n_coef] = coef
    b0, b1, b2 = (float(v) for v in pad.mean(axis=0))
    return dict(b0=b0, b1=b1, b2=b2, r2=r2, p=p, cv_mean_mm=float(e.mean()),
                cv_sd_mm=float(e.std(ddof=1)), coef_full_mm=tuple(float(v) for v in full),
                coef_folds_mm=pad)


def fit_table(
    samples: Sequence[SubjectSample],
    k_folds: int = 5,
    seed: int = 0,
    groups: Sequence[str] = GROUPS,
) -> list[FitResult]:
    """Fit every Table I family for each sex group by OLS with K-fold cross-validation.

    Per group the subjects (in the given order) are split once into K seeded parts shared by all
    equations, so mirrored targets (MM x = -LM x, ...) give exactly mirrored results as in
    Table I. Each fold fits on K-1 parts and tests on the held-out one (Wang §III.A)."""
    samples = list(samples)
    if isinstance(k_folds, bool) or not isinstance(k_folds, int) or k_folds < 2:
        raise InputError(f"expected an integer k_folds >= 2, got {k_folds!r}", field="k_folds")
    ids = [s.subject_id for s in samples]
    if len(set(ids)) != len(ids):
        raise InputError("subject ids must be unique", field="subject_id")
    results = []
    for group in groups:
        if group not in GROUPS:
            raise InputError(f"expected groups among {GROUPS}, got {group!r}", field="groups")
        members = [s for s in samples if group == "all" or s.sex == group]
        n, n_min = len(members), _min_group_size(k_folds, 3)
        if n < n_min:
            msg = (
                f"group {group!r} has {n} subjects; {k_folds}-fold cross-validation of a "
                f"3-coefficient equation needs at least {n_min} (or leave the group out)"
            )
            raise InputError(msg, field="samples")
        folds = kfold_indices(n, k_folds, seed)
        inputs = [s.measures().inputs_mm() for s in members]
        for equation, targets in EQUATION_TARGETS.items():
            names = EQUATION_INPUTS[equation]
            x = np.column_stack([np.ones(n)] + [[d[k] for d in inputs] for k in names])
            if np.linalg.matrix_rank(x) < x.shape[1]:
                msg = f"group {group!r}: inputs {names} do not vary independently; cannot fit"
                raise InputError(msg, field="samples")
            for landmark, axis in targets:
                y = np.array([s.coordinate_mm(landmark, axis) for s in members])
                fit = _fit_one(x, y, folds)
                results.append(
                    FitResult(group, equation, landmark, axis, **fit, source="fit", n=n,
                              k_folds=k_folds)
                )
    return results


def fit_results_to_rows(results: Sequence[FitResult]) -> list[dict[str, str | float]]:
    """Rows with exactly the columns of :data:`CSV_COLUMNS` (Table I's, in mm)."""
    return [{c: getattr(r, c) for c in CSV_COLUMNS} for r in results]


def table_from_fits(results: Sequence[FitResult], origin: str = "fit") -> RegressionTable:
    """A :class:`RegressionTable` of fitted equations, usable by :func:`predict_landmarks`."""
    return RegressionTable(tuple(r.to_equation() for r in results), origin=origin)


def write_fit_csv(results: Sequence[FitResult], path: str | Path) -> Path:
    """Write :func:`fit_results_to_rows` as CSV (numbers with 6 significant digits)."""
    return write_text_atomic(Path(path), csv_text(fit_results_to_rows(results), CSV_COLUMNS))
