"""Stage 1 of the Wang 2023 reproduction: the optical data of all 38 subjects (Wang §II.A,
§III.A-B): hip centre, segment frames, knee AoR (eq 1-8), landmark positions in segment frames,
body dimensions, the regression equations of Table I refitted with K-fold cross-validation, and
the population AoR of Table III."""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from pipeline.calibration.aor import PopulationAoR, population_aor
from pipeline.errors import InputError
from pipeline.io.tables import csv_text
from pipeline.reproduce.wang2023.dataset import Subject, load_subject, subject_paths
from pipeline.reproduce.wang2023.omc import OmcResult, process_subject
from pipeline.reproduce.wang2023.regression import (
    FitResult,
    SubjectSample,
    fit_results_to_rows,
    fit_table,
)

__all__ = ["OmcStage", "hip_centred_paths", "omc_tables", "run_omc_stage", "subject_sample"]


SUBJECT_COLUMNS = (
    "subject_id", "sex", "height_mm", "shank_lateral_mm", "shank_medial_mm", "knee_width_mm",
    "ankle_width_mm", "hip_fit_rms_mm", "n_frames",
)
LANDMARK_COLUMNS = ("subject_id", "landmark", "frame", "x_mm", "y_mm", "z_mm")
AOR_COLUMNS = (
    "subject_id", "sex", "femur_x", "femur_y", "femur_z", "tibia_x", "tibia_y", "tibia_z",
    "n_pairs", "sd_angle_femur_deg", "sd_angle_tibia_deg",
)
REGRESSION_COLUMNS = (
    "sex", "equation", "landmark", "axis", "b0", "b1", "b2", "r2", "p", "cv_mean_mm", "cv_sd_mm",
)


@dataclass
class OmcStage:
    """Everything stage 1 computes; stage 2 reuses the subjects and the population AoRs."""

    subjects: list[Subject]
    results: list[OmcResult]
    fits: list[FitResult]
    population: dict[str, PopulationAoR]
    seconds: float
    notes: list[str] = field(default_factory=list)

    def result(self, subject_id: int) -> OmcResult:
        return next(r for r in self.results if r.subject_id == subject_id)


def run_omc_stage(data_dir: str | Path, *, k_folds: int = 5, progress: bool = True) -> OmcStage:
    """Load and process every subject's optical data, fit Table I, average the AoRs (Table III)."""
    t0 = time.perf_counter()
    paths = subject_paths(data_dir)
    if not paths:
        raise InputError("no rawDataNN.mat files found", file=data_dir)
    subjects, results, notes = [], [], []
    for path in tqdm(paths, desc="optical data", unit="subject", disable=not progress):
        subject = load_subject(path)
        subjects.append(subject)
        results.append(process_subject(subject.omc))
        notes.extend(f"subject {subject.omc.subject_id}: {n}" for n in subject.omc.notes)
    samples = [subject_sample(s, r) for s, r in zip(subjects, results, strict=True)]
    fits = fit_table(samples, k_folds=k_folds, seed=0)
    population = {
        sex: population_aor([r.knee_aor for r in results if sex == "all" or r.sex == sex])
        for sex in ("m", "f", "all")
    }
    return OmcStage(subjects, results, fits, population, time.perf_counter() - t0, notes)


def subject_sample(subject: Subject, r: OmcResult) -> SubjectSample:
    d = r.dims
    return SubjectSample(
        subject_id=r.subject_id,
        sex=r.sex,
        height_m=subject.omc.height_m,
        shank_lateral_m=d.s_L,
        shank_medial_m=d.s_M,
        knee_width_m=d.k,
        ankle_width_m=d.a,
        efm=r.landmarks_femur["EFM"],
        efl=r.landmarks_femur["EFL"],
        mm=r.landmarks_tibia["MM"],
        lm=r.landmarks_tibia["LM"],
    )


def omc_tables(stage: OmcStage) -> dict[str, str]:
    """The stage-1 CSV files as text, in mm and degrees."""
    subj, lms, aor = [], [], []
    for s, r in zip(stage.subjects, stage.results, strict=True):
        d = r.dims
        subj.append(
            dict(
                subject_id=r.subject_id, sex=r.sex, height_mm=1e3 * s.omc.height_m,
                shank_lateral_mm=1e3 * d.s_L, shank_medial_mm=1e3 * d.s_M,
                knee_width_mm=1e3 * d.k, ankle_width_mm=1e3 * d.a,
                hip_fit_rms_mm=1e3 * r.hip_fit_rms_m, n_frames=r.n_frames,
            )
        )
        for frame, landmarks in (("femur", r.landmarks_femur), ("tibia", r.landmarks_tibia)):
            for name, p in landmarks.items():
                x, y, z = 1e3 * np.asarray(p)
                lms.append(dict(subject_id=r.subject_id, landmark=name, frame=frame,
                                x_mm=x, y_mm=y, z_mm=z))
        a = r.knee_aor
        aor.append(
            dict(
                subject_id=r.subject_id, sex=r.sex,
                femur_x=a.femur_axis[0], femur_y=a.femur_axis[1], femur_z=a.femur_axis[2],
                tibia_x=a.tibia_axis[0], tibia_y=a.tibia_axis[1], tibia_z=a.tibia_axis[2],
                n_pairs=a.n_pairs, sd_angle_femur_deg=float(np.degrees(a.sd_angle_femur)),
                sd_angle_tibia_deg=float(np.degrees(a.sd_angle_tibia)),
            )
        )
    return {
        "subjects.csv": csv_text(subj, SUBJECT_COLUMNS),
        "landmarks_in_segments.csv": csv_text(lms, LANDMARK_COLUMNS),
        "knee_aor.csv": csv_text(aor, AOR_COLUMNS),
        "regression.csv": csv_text(fit_results_to_rows(stage.fits), REGRESSION_COLUMNS),
    }


def hip_centred_paths(subject, r) -> dict[str, np.ndarray]:
    """The optical landmark paths with the hip as origin (lab axes), and the knee centre
    ``KJC`` midway between the epicondyles."""
    paths = {n: subject.omc.landmarks[n] - r.hjc for n in ("EFM", "EFL", "MM", "LM")}
    paths["KJC"] = 0.5 * (paths["EFM"] + paths["EFL"])
    return paths
