"""Xsens MVN against optical capture: the reproduction stage (Wang et al. 2023, Table II and
Tables VI-VII).

Data: ``xsens/`` of the published dataset (README there). Reading and modelling the MVN and
optical files (labels, hip centre, segment frames, one trial's comparison) is
:mod:`pipeline.reproduce.wang2023.xsens_mvn`; the Markdown section is
:mod:`pipeline.reproduce.wang2023.xsens_report`.

**Table II, MVN scaling.** The five static MVN models (``XsensStatic_c3d/``,
:func:`pipeline.reproduce.wang2023.xsens_mvn.static_model`) get the right HJC offset averaged over
the MVN motion exports (:func:`pipeline.reproduce.wang2023.xsens_mvn.mvn_hip_offset`). Each MVN
coordinate is linear in height (fit over the five heights) and evaluated at every optical subject's
height: Table II = mean±SD over subjects of ``MVN(h) - OMC`` (the paper's SDs equal the
between-subject SDs of Table I, so this is what it did). Also given: MVN minus the paper's Table I
height equations at the five heights.

**Tables VI-VII, MVN trajectories.** The four ``Subject{1,2}/HipF{1,2}`` trials (:data:`TRIALS`),
each by :func:`pipeline.reproduce.wang2023.xsens_mvn.compare_trial`; Subject 1 HipF2 has no MVN
export and uses ``rawData.mat``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from itertools import product
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.c3d import read_c3d
from pipeline.io.tables import csv_text
from pipeline.model.anthropometry import load_table1
from pipeline.reproduce.wang2023.dataset import load_subject, subject_paths
from pipeline.reproduce.wang2023.omc import process_subject
from pipeline.reproduce.wang2023.xsens_mvn import (
    LANDMARKS,
    UNIFICATIONS,
    MvnStaticModel,
    TrialResult,
    compare_trial,
    linear_in_height,
    mvn_hip_offset,
    static_model,
)

TRIALS = (
    ("Subject1", "HipF1", "Subject 1, calibration 1 (non-standard)"),
    ("Subject1", "HipF2", "Subject 1, calibration 2"),
    ("Subject2", "HipF1", "Subject 2, calibration 1"),
    ("Subject2", "HipF2", "Subject 2, calibration 1 (2nd trial)"),
)
GROUPS = ("m", "f", "all")
COORDS = (("EFM", "femur"), ("EFL", "femur"), ("MM", "tibia"), ("LM", "tibia"))

# Paper, Table II (mm, MVN - OMC, mean±SD): (landmark, axis) per group; '' where not printed.
PAPER_TABLE_II = {
    "m": {
        "EFM": ("", "-9.9±21.5", "11.4±4.3"),
        "EFL": ("", "-9.0±22.1", "-11.4±4.3"),
        "MM": ("-14.3±6.6", "-27.2±13.8", "-3.1±3.9"),
        "LM": ("14.3±6.6", "-17.3±15.4", "-2.0±3.8"),
    },
    "f": {
        "EFM": ("", "-18.6±22.2", "12.3±4.2"),
        "EFL": ("", "-18.8±19.6", "-12.3±4.2"),
        "MM": ("-9.6±4.0", "-30.2±18.4", "-3.1±2.3"),
        "LM": ("9.6±4.0", "-19.9±19.4", "-1.7±2.3"),
    },
    "all": {
        "EFM": ("0.0±0.0", "-14.0±22.0", "11.9±4.2"),
        "EFL": ("0.0±0.0", "-13.7±21.3", "-11.9±4.2"),
        "MM": ("-12.1±6.0", "-28.6±16.0", "-3.1±3.2"),
        "LM": ("12.1±6.0", "-18.5±17.2", "-1.9±3.2"),
    },
}
# Paper, Table VI (RMS mm: EFM, EFL, MM, LM) and Table VII (deg: femur Z Y X, tibia Z Y X).
PAPER_TABLE_VI = {
    ("Subject1", "HipF1"): (46.5, 62.4, 248.8, 267.7),
    ("Subject1", "HipF2"): (43.9, 61.4, 126.7, 145.1),
    ("Subject2", "HipF1"): (78.0, 56.5, 136.1, 119.2),
    ("Subject2", "HipF2"): (86.3, 69.5, 145.3, 133.2),
}
PAPER_TABLE_VII = {
    ("Subject1", "HipF1"): (4.5, 17.0, 12.1, 36.6, 5.7, 3.1),
    ("Subject1", "HipF2"): (4.2, 5.7, 5.9, 17.2, 7.9, 2.1),
    ("Subject2", "HipF1"): (11.1, 9.8, 13.8, 5.8, 6.4, 12.7),
    ("Subject2", "HipF2"): (12.2, 13.6, 14.6, 3.1, 9.6, 12.9),
}


# --------------------------------------------------------------------------------------------
# Table II statistics


def scaling_differences(line: dict, subjects: list[tuple[str, float, dict]]) -> list[dict]:
    """``MVN(h) - OMC`` per subject, landmark and axis (m). ``subjects``: (sex, height m,
    {landmark: position in its segment frame})."""
    rows = []
    for sex, h, lms in subjects:
        for n in LANDMARKS:
            a, b = line[n]
            d = a + b * h - np.asarray(lms[n], float)
            rows.append(dict(sex=sex, height_m=h, landmark=n, dx=d[0], dy=d[1], dz=d[2]))
    return rows


def summarise_differences(rows: list[dict]) -> dict:
    """{group: {landmark: (mean (3,), sd (3,), n)}} in metres, sample SD, groups m, f, all."""
    out: dict = {}
    for g in GROUPS:
        out[g] = {}
        for n in LANDMARKS:
            sel = [r for r in rows if r["landmark"] == n and (g == "all" or r["sex"] == g)]
            D = np.array([[r["dx"], r["dy"], r["dz"]] for r in sel]).reshape(-1, 3)
            sd = D.std(axis=0, ddof=1) if len(D) > 1 else np.zeros(3)
            out[g][n] = (D.mean(axis=0), sd, len(D))
    return out


# --------------------------------------------------------------------------------------------
# stage


@dataclass
class XsensStage:
    statics: list[MvnStaticModel]
    hip_offsets: list[tuple[str, np.ndarray, float]]
    line: dict
    line_residual_m: float
    differences: list[dict]
    summary: dict
    vs_table1: dict
    trials: list[TrialResult]
    seconds: float
    notes: list[str] = field(default_factory=list)


def _xsens_dir(data_dir: Path) -> Path:
    for d in (data_dir / "xsens", data_dir):
        if (d / "XsensStatic_c3d").is_dir():
            return d
    raise InputError(
        "no xsens/XsensStatic_c3d folder (expected the wang2023 dataset)", file=data_dir
    )


def _omc_subjects(data_dir: Path, omc_stage) -> list[tuple[str, float, dict]]:
    if omc_stage is None:
        pairs = []
        for p in subject_paths(data_dir):
            s = load_subject(p)
            pairs.append((s, process_subject(s.omc)))
    else:
        pairs = list(zip(omc_stage.subjects, omc_stage.results, strict=True))
    return [(r.sex, s.omc.height_m, r.landmarks_femur | r.landmarks_tibia) for s, r in pairs]


def _vs_table1(line: dict, subjects: list[tuple[str, float, dict]]) -> dict:
    """MVN minus the paper's Table I height equations (the group's rows: m, f or all) at each
    optical subject's height, mean±SD over subjects (m). OLS lines pass through the means, so
    the mean is what the paper's Table II would show with the paper's own subjects' positions;
    the SD holds only the slope difference."""

    table = load_table1()
    out: dict = {}
    for g in GROUPS:
        out[g] = {}
        heights = [h for sex, h, _ in subjects if g == "all" or sex == g]
        for n in LANDMARKS:
            D = []
            for h in heights:
                ref = np.zeros(3)
                for i, ax in enumerate("xyz"):
                    if not (n in ("EFM", "EFL") and ax == "x"):
                        ref[i] = table.get(g, "h", n, ax).evaluate_mm({"h": 1e3 * h}) / 1e3
                a, b = line[n]
                D.append(a + b * h - ref)
            D = np.array(D)
            out[g][n] = (D.mean(axis=0), D.std(axis=0, ddof=1), len(D))
    return out


def run_xsens_stage(data_dir: str | Path, omc_stage=None) -> XsensStage:
    """Table II from the static MVN models and the optical subjects (``omc_stage`` from
    :func:`pipeline.reproduce.wang2023.run.run_omc_stage`, else processed here), and Tables VI-VII
    from the four MVN/optical trials."""
    t0 = time.perf_counter()
    data_dir = Path(data_dir)
    xdir = _xsens_dir(data_dir)
    notes: list[str] = []
    trials, offsets = [], []
    for subject, trial, label in TRIALS:
        folder = xdir / subject / trial
        if not (folder / f"OMC{trial}.c3d").is_file():
            notes.append(f"{subject}/{trial}: no optical file; skipped")
            continue
        result = compare_trial(folder, label)
        trials.append(result)
        if result.source == "rawData.mat":
            notes.append(f"{subject}/{trial}: no xsens{trial}.c3d; MVN landmarks from rawData.mat")
        export = folder / f"xsens{trial}.c3d"
        if export.is_file():
            off, rms = mvn_hip_offset(read_c3d(export))
            offsets.append((f"{subject}/{trial}", off, rms))
    if not offsets:
        raise InputError("no MVN motion export to locate the hip centre in the pelvis", file=xdir)
    hip_offset = np.mean([o for _, o, _ in offsets], axis=0)
    files = sorted((xdir / "XsensStatic_c3d").glob("*.c3d"))
    statics = sorted((static_model(f, hip_offset) for f in files), key=lambda s: s.height_m)
    line, resid = linear_in_height(statics)
    subjects = _omc_subjects(data_dir, omc_stage)
    diffs = scaling_differences(line, subjects)
    return XsensStage(
        statics=statics,
        hip_offsets=offsets,
        line=line,
        line_residual_m=resid,
        differences=diffs,
        summary=summarise_differences(diffs),
        vs_table1=_vs_table1(line, subjects),
        trials=trials,
        seconds=time.perf_counter() - t0,
        notes=notes,
    )


# --------------------------------------------------------------------------------------------
# report and tables


def xsens_tables(stage: XsensStage) -> dict[str, str]:
    """CSV files (mm, degrees): static landmarks, Table II, Table VI, Table VII."""
    static = [
        dict(
            height_mm=1e3 * s.height_m,
            model_height_mm=1e3 * s.model_height_m,
            landmark=n,
            x_mm=1e3 * p[0],
            y_mm=1e3 * p[1],
            z_mm=1e3 * p[2],
        )
        for s in stage.statics
        for n, p in s.segment_landmarks.items()
    ]
    t2 = []
    for g in GROUPS:
        for n in LANDMARKS:
            mean, sd, k = stage.summary[g][n]
            for i, ax in enumerate("xyz"):
                t2.append(
                    dict(
                        group=g,
                        landmark=n,
                        axis=ax,
                        mean_mm=1e3 * mean[i],
                        sd_mm=1e3 * sd[i],
                        n=k,
                        paper=PAPER_TABLE_II[g][n][i],
                    )
                )
    t6 = [
        dict(
            subject=t.subject,
            trial=t.trial,
            source=t.source,
            lag=t.lag,
            unification=how,
            landmark=n,
            rms_mm=1e3 * t.rms_m[(how, n)],
            paper_mm=PAPER_TABLE_VI.get((t.subject, t.trial), ("",) * 4)[LANDMARKS.index(n)],
        )
        for t in stage.trials
        for how in UNIFICATIONS
        for n in LANDMARKS
    ]
    t7 = []
    for t in stage.trials:
        paper = PAPER_TABLE_VII.get((t.subject, t.trial), ("",) * 6)
        for how, (j, seg), frame in product(
            UNIFICATIONS, enumerate(("femur", "tibia")), ("world", "body")
        ):
            z, y, x = np.degrees(t.orientation_rad[(how, seg, frame)])
            t7.append(
                dict(
                    subject=t.subject,
                    trial=t.trial,
                    unification=how,
                    segment=seg,
                    error_frame=frame,
                    z_deg=z,
                    y_deg=y,
                    x_deg=x,
                    paper_z=paper[3 * j],
                    paper_y=paper[3 * j + 1],
                    paper_x=paper[3 * j + 2],
                )
            )
    return {
        "xsens_static_landmarks.csv": csv_text(
            static, ("height_mm", "model_height_mm", "landmark", "x_mm", "y_mm", "z_mm")
        ),
        "xsens_table2.csv": csv_text(
            t2, ("group", "landmark", "axis", "mean_mm", "sd_mm", "n", "paper")
        ),
        "xsens_trajectory_errors.csv": csv_text(
            t6,
            ("subject", "trial", "source", "lag", "unification", "landmark", "rms_mm", "paper_mm"),
        ),
        "xsens_orientation_errors.csv": csv_text(
            t7,
            (
                "subject",
                "trial",
                "unification",
                "segment",
                "error_frame",
                "z_deg",
                "y_deg",
                "x_deg",
                "paper_z",
                "paper_y",
                "paper_x",
            ),
        ),
    }
