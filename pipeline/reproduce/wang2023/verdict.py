"""The verdict that opens ``report.md``: what reproduces, what does not and why, what goes beyond
the paper, each sentence computed from this run's tables (nothing here is a copied number except
the paper's own, imported from the report sections)."""

from __future__ import annotations

import numpy as np

from pipeline.reproduce.wang2023.imc import LANDMARKS, ImcStage, rms_values, select_rows
from pipeline.reproduce.wang2023.imc_report import PAPER_TABLE_IV, PAPER_TABLE_V, paper_mean
from pipeline.reproduce.wang2023.optical import OmcStage

__all__ = ["TOLERANCE_MM", "table4_agreement", "verdict_section"]

TOLERANCE_MM = 5.0  # a Table IV cell "reproduces" when the group means differ by at most this


def _mean(values) -> float:
    v = np.asarray(list(values), dtype=float)
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else float("nan")


def table4_agreement(stage: ImcStage) -> list[tuple[str, str, str, str, float, float]]:
    """(positions, correction, sex, landmark, ours, paper) for every Table IV cell the paper has,
    ours from the stored tibia input (the paper's input); mean RMS over subjects, mm."""
    out = []
    for (positions, correction, sex), paper in PAPER_TABLE_IV.items():
        if correction not in stage.corrections:
            continue
        for name, cell in zip(LANDMARKS, paper, strict=True):
            rms = rms_values(stage.trajectory_rows, tibia_input="stored", positions=positions,
                             correction=correction, sex=sex, landmark=name)
            ours = _mean(rms)
            out.append((positions, correction, sex, name, ours, paper_mean(cell)))
    return out


def _malleoli(stage: ImcStage, tibia_input: str, correction: str) -> tuple[float, float]:
    return tuple(
        _mean(rms_values(stage.trajectory_rows, tibia_input=tibia_input, positions="regression",
                         correction=correction, landmark=name))
        for name in ("MM", "LM")
    )


def _tibia_z(stage: ImcStage, correction: str) -> float:
    rows = select_rows(stage.orientation_rows, tibia_input="stored", correction=correction,
                       segment="tibia", error_frame="world")
    return _mean(float(r["z_deg"]) for r in rows)


def _factors_text(imc_stage: ImcStage) -> str:
    rows = imc_stage.factors
    if not rows:
        return ""
    lm = {f: np.mean([r["LM_mm"] for r in rows if r["sex"] == "m" and r["factor"] == f])
          for f in dict.fromkeys(r["factor"] for r in rows)}
    paper = paper_mean(PAPER_TABLE_IV[("regression", "average", "m")][3])
    others = {f: v for f, v in lm.items() if f != "ours"}
    closest = min(others, key=lambda f: abs(others[f] - paper))
    return (f" With the paper's own method (`reference` rows) our male LM is {lm['ours']:.1f} mm "
            f"against {paper:.1f} mm; switching the reference code's documented choices in one "
            f"at a time (appendix, 'Table IV male LM') does not close the gap: the closest is "
            f"'{closest}' at {others[closest]:.1f} mm. The rest is in what the dataset does not "
            "document (the reference's shank lengths and its bug-affected female mean AoR).")


def verdict_section(stage: OmcStage, imc_stage: ImcStage | None) -> str:
    """Markdown: the report's first section."""
    lines = ["## Verdict", ""]
    lines.append(
        f"- **Optical stage (Table I, Table III):** all {len(stage.results)} subjects processed; "
        f"Table I refitted ({len(stage.fits)} equations, 5-fold cross-validation). Where our "
        "coefficients differ from the paper's, the appendix gives the difference at the group's "
        "mean inputs and its cause (the reference code's shank-length definition; first-sample "
        "vs trial-median landmark positions)."
    )
    if imc_stage is None:
        return "\n".join(lines) + "\n"
    cells = table4_agreement(imc_stage)
    close = [c for c in cells if abs(c[4] - c[5]) <= TOLERANCE_MM]
    far = sorted((c for c in cells if abs(c[4] - c[5]) > TOLERANCE_MM),
                 key=lambda c: -abs(c[4] - c[5]))
    far_text = "; ".join(f"{p}/{c}/{s} {n} {o:.1f} vs {q:.1f}" for p, c, s, n, o, q in far[:6])
    n_subjects = len({r["subject_id"] for r in imc_stage.trajectory_rows})
    lines.append(
        f"- **Table IV (landmark RMS errors, {n_subjects} IMC subjects):** {len(close)} of "
        f"{len(cells)} cells the paper reports are reproduced within {TOLERANCE_MM:g} mm (group "
        "means, stored tibia input as in the paper)."
        + (f" Not reproduced ({len(far)}, landmarks {'/'.join(sorted({c[3] for c in far}))}, "
           f"sex {'/'.join(sorted({c[2] for c in far}))}), largest first: {far_text} (ours vs "
           "paper, mm); the appendix's discussion quantifies the known factors (the reference "
           "code's female AoR for everyone: the `reference` rows)." if far else "")
        + _factors_text(imc_stage)
    )
    if {"none", "average"} <= set(imc_stage.corrections):
        z0, z1 = _tibia_z(imc_stage, "none"), _tibia_z(imc_stage, "average")
        p0, p1 = (paper_mean(PAPER_TABLE_V[c][3]) for c in ("none", "average"))
        lines.append(
            f"- **Table V (orientation errors):** the paper's pattern is that of the world-frame "
            f"error R_imc R_omcᵀ: the tibia's Z error falls from {z0:.1f} to {z1:.1f} deg with the "
            f"AoR correction (paper {p0:.1f} → {p1:.1f} deg)."
        )
    beyond, means = [], {}
    for correction in ("none", "average", "ipopt", "hinge_ik", "full_ipopt"):
        if correction in imc_stage.corrections:
            mm, lm = _malleoli(imc_stage, "uncorrected", correction)
            beyond.append(f"{correction} {mm:.0f}/{lm:.0f}")
            means[correction] = 0.5 * (mm + lm)
    if beyond:
        best = min(means, key=means.get)
        lines.append(
            "- **Beyond the paper:** on the tibia data as the suit delivered it (`uncorrected`: "
            "the stored data contain hand-tuned rotations), mean MM/LM RMS (mm, regression "
            "positions) by correction: " + ", ".join(beyond) + f". None needs hand tuning; the "
            f"best is `{best}`"
            + (" (the full sensor-to-segment rotation of both segments from the IMU data, "
               "priors fitted on the other subjects)" if best == "full_ipopt" else "")
            + ". The 42 mm goal and what limits it: appendix, 'What limits the IMU-only "
            "calibration'."
        )
    lines.append(
        "- **Time lag:** estimated from the signals (the reference code hand-set it); see the "
        "appendix for the comparison."
    )
    return "\n".join(lines) + "\n"
