"""``report.md`` of the Wang 2023 reproduction: our tables beside the paper's, causes named.

Every difference is compared on a scale that means something to a user: the landmark coordinate
each equation predicts at the group's mean inputs (paper's coefficients vs ours), next to the
cross-validated error SD. Causes are assigned per equation family from the facts documented in
the dataset README and measured here (e.g. the first-sample ablation below), not guessed per row.
"""

from __future__ import annotations

import numpy as np

from pipeline.io.tables import markdown_table, mean_sd
from pipeline.model.anthropometry import EQUATION_INPUTS, load_table1
from pipeline.reproduce.wang2023.evidence import evidence_section
from pipeline.reproduce.wang2023.factors import factors_section
from pipeline.reproduce.wang2023.imc import ImcStage
from pipeline.reproduce.wang2023.imc_report import imc_report_sections
from pipeline.reproduce.wang2023.limits import limits_section
from pipeline.reproduce.wang2023.omc import landmarks_in_frames
from pipeline.reproduce.wang2023.optical import OmcStage, subject_sample
from pipeline.reproduce.wang2023.regression import SubjectSample, fit_table
from pipeline.reproduce.wang2023.verdict import verdict_section
from pipeline.reproduce.wang2023.xsens import XsensStage
from pipeline.reproduce.wang2023.xsens_report import xsens_report_section

CAUSES = {
    "shank": (
        "shank-length definition. The paper's s_L/s_M come from the reference code, which "
        "subtracts a femoral-frame vector from a tibial-frame one at frame 1 and applies "
        "medial-shank coefficients to the lateral length for MM Y (dataset README, known quirks). "
        "We use the paper's definition s_L=|EFL-LM|, s_M=|EFM-MM|, measured on the extended leg "
        "(median of the 5 % most extended frames). With true lengths the relation is weaker: "
        "lower R², larger CV SD."
    ),
    "k": (
        "same method: EFM/EFL z = ∓k/2 holds by construction (knee centre on the femoral y axis "
        "of an equal-radius hip fit), so R² = 1 in both; residual differences are rounding."
    ),
    "position": (
        "landmark positions: median over the whole trial (ours) vs the first sample "
        "(reference); the six subjects with other lab axes processed frame-independently (the "
        "reference's rotation bug moved their AoR and tibial frame); K of the K-fold split is "
        "not stated in the paper (we use K=5, seeded). The first-sample ablation below "
        "quantifies the first cause."
    ),
    "reconstructed": (
        "the paper's row is reconstructed (label swapped or garbled in the published table; "
        "see models/wang2023_table1.md) — compare with care."
    ),
}


def _cause(equation: str, source: str) -> str:
    if source == "reconstructed":
        return "reconstructed"
    if equation in ("h+sL", "h+sM"):
        return "shank"
    if equation == "k":
        return "k"
    return "position"


def _group_mean_inputs(samples: list[SubjectSample], sex: str) -> dict[str, float]:
    members = [s for s in samples if sex == "all" or s.sex == sex]
    keys = {k for names in EQUATION_INPUTS.values() for k in names}
    values = [s.measures().inputs_mm() for s in members]
    return {k: float(np.mean([v[k] for v in values])) for k in keys}


def first_sample_samples(stage: OmcStage) -> list[SubjectSample]:
    """The reference's choice: landmark positions in segment frames at the first valid sample."""
    out = []
    for subject, r in zip(stage.subjects, stage.results, strict=True):
        first = np.zeros(r.n_frames, bool)
        first[np.flatnonzero(r.valid)[0]] = True
        lm = subject.omc.landmarks
        f = {
            n: landmarks_in_frames(lm[n], r.femur_R, r.femur_origin, first) for n in ("EFM", "EFL")
        }
        t = {n: landmarks_in_frames(lm[n], r.tibia_R, r.tibia_origin, first) for n in ("MM", "LM")}
        s = subject_sample(subject, r)
        out.append(
            SubjectSample(
                s.subject_id, s.sex, s.height_m, s.shank_lateral_m, s.shank_medial_m,
                s.knee_width_m, s.ankle_width_m, f["EFM"], f["EFL"], t["MM"], t["LM"],
            )
        )
    return out


def table1_section(stage: OmcStage) -> str:
    paper = load_table1()
    samples = [subject_sample(s, r) for s, r in zip(stage.subjects, stage.results, strict=True)]
    ablation = {
        (f.sex, f.equation, f.landmark, f.axis): f
        for f in fit_table(first_sample_samples(stage), k_folds=5, seed=0)
    }
    ours = {(f.sex, f.equation, f.landmark, f.axis): f for f in stage.fits}
    rows, causes_used, deltas = [], set(), []
    for e in paper:
        key = (e.sex, e.equation, e.landmark, e.axis)
        f = ours[key]
        x = _group_mean_inputs(samples, e.sex)
        d = f.to_equation().evaluate_mm(x) - e.evaluate_mm(x)
        deltas.append((key, d, f.cv_sd_mm))
        cause = _cause(e.equation, e.source)
        causes_used.add(cause)
        rows.append(
            [
                e.sex, e.equation, f"{e.landmark} {e.axis}",
                f"{e.b0:.3f} / {e.b1:.3f} / {e.b2:.3f}", f"{f.b0:.3f} / {f.b1:.3f} / {f.b2:.3f}",
                f"{e.r2:.3f} / {f.r2:.3f}", f"{e.cv_sd_mm:.1f} / {f.cv_sd_mm:.1f}",
                f"{ablation[key].cv_sd_mm:.1f}", f"{d:+.1f}", cause,
            ]
        )
    big = [(k, d, sd) for k, d, sd in deltas if abs(d) > max(sd, 2.0)]
    text = [
        "## Table I: regression equations of landmark positions in segment frames",
        "",
        f"{len(stage.results)} subjects; ours fitted with {stage.fits[0].k_folds}-fold "
        "cross-validation (coefficients = mean over folds; R² and p from the whole group). "
        "'Δ at mean' = our equation minus the paper's, evaluated at the group's mean inputs (mm): "
        "the difference a user would see. 'first-sample CV SD' refits with landmark positions "
        "taken at the first sample as the reference code did.",
        "",
        markdown_table(
            [
                "sex",
                "eq",
                "coord",
                "paper b0/b1/b2",
                "ours b0/b1/b2",
                "R² paper/ours",
                "CV SD mm paper/ours",
                "first-sample CV SD",
                "Δ at mean mm",
                "cause",
            ],
            rows,
        ),
        "",
        f"{len(big)} of {len(deltas)} rows differ at the mean inputs by more than "
        "max(our CV SD, 2 mm): "
        + (", ".join(f"{k[0]} {k[1]} {k[2]} {k[3]} ({d:+.1f} mm)" for k, d, _ in big) or "none")
        + ".",
        "",
        "Causes:",
        "",
    ]
    text += [f"- **{c}**: {CAUSES[c]}" for c in sorted(causes_used)]
    text += [
        "- **p-values**: the paper's p are not those of an overall F-test on its own R² "
        "(e.g. all/h/EFM y: R² 0.654 with n = 38 gives p ≈ 1e-9, printed 0.002); ours are the "
        "F-test's.",
    ]
    return "\n".join(text)


def table3_section(stage: OmcStage) -> str:
    rows = []
    for sex in ("m", "f", "all"):
        p = stage.population[sex]
        rows.append(
            [
                sex, p.n_subjects,
                "(" + ", ".join(f"{v:.3f}" for v in p.femur_axis) + ")",
                f"{np.degrees(p.sd_femur_transverse):.1f} / {np.degrees(p.sd_femur_frontal):.1f}",
                "(" + ", ".join(f"{v:.3f}" for v in p.tibia_axis) + ")",
                f"{np.degrees(p.sd_tibia_transverse):.1f} / {np.degrees(p.sd_tibia_frontal):.1f}",
            ]
        )
    sd_f = [np.degrees(r.knee_aor.sd_angle_femur) for r in stage.results]
    return "\n".join(
        [
            "## Table III: knee AoR unit vectors and projection angles",
            "",
            "Mean of the subjects' unit AoRs (Wang eq 6 and 8 per subject, then averaged) and the "
            "SD of their projection angles in the transverse (x-z) and frontal (y-z) planes.",
            "",
            markdown_table(
                [
                    "sex",
                    "n",
                    "femur AoR (x, y, z)",
                    "femur SD transverse / frontal (deg)",
                    "tibia AoR (x, y, z)",
                    "tibia SD transverse / frontal (deg)",
                ],
                rows,
            ),
            "",
            "The paper's Table III values are printed as an image that the text we have does not "
            "contain, so no number-by-number comparison is possible; the paper's text confirms "
            "the qualitative findings we also measure: the femoral AoR is not aligned with any "
            "femoral axis (its lateral end points posteriorly and distally: x and y clearly "
            "non-zero), while the tibial AoR nearly coincides with the tibial z axis (by "
            "construction of the tibial frame: z is the AoR projected ⟂ y). "
            "Within-subject dispersion of the per-pair axes: "
            f"{mean_sd(sd_f)} deg (femur). The reference code's rotation bug moved the AoR of "
            "subjects 17-19 and 28-30 by 2-33 deg (dataset README); ours processes every subject "
            "frame-independently, so the paper's Table III, which includes those subjects, is "
            "expected to differ from ours by that effect.",
        ]
    )


def subjects_section(stage: OmcStage) -> str:
    rows = []
    for sex, paper in (("m", "176.0±5.2"), ("f", "162.4±5.0")):
        rs = [(s, r) for s, r in zip(stage.subjects, stage.results, strict=True) if r.sex == sex]
        rows.append(
            [
                sex, len(rs), paper, mean_sd([1e3 * s.omc.height_m / 10 for s, _ in rs]),
                mean_sd([1e3 * r.hip_fit_rms_m for _, r in rs], 2),
                mean_sd([1e3 * r.dims.k for _, r in rs]), mean_sd([1e3 * r.dims.a for _, r in rs]),
                mean_sd([1e3 * r.dims.s_L for _, r in rs]),
            ]
        )
    return "\n".join(
        [
            "## Subjects",
            "",
            markdown_table(
                [
                    "sex",
                    "n",
                    "height cm (paper)",
                    "height cm (data)",
                    "hip-fit RMS mm",
                    "knee width mm",
                    "ankle width mm",
                    "s_L mm",
                ],
                rows,
            ),
            "",
            f"Optical stage: {len(stage.results)} subjects in {stage.seconds:.1f} s.",
        ]
        + ([""] + [f"- {n}" for n in stage.notes] if stage.notes else [])
    )


def render_report(
    stage: OmcStage,
    imc_stage: ImcStage | None = None,
    xsens_stage: XsensStage | None = None,
    figures: tuple[str, ...] = (),
) -> str:
    parts = [
        "# Wang et al. 2023 reproduction",
        "",
        "Generated by `pipeline reproduce wang2023`. Units: mm and degrees. Paper: Wang et al., "
        "IEEE TNSRE 31 (2023), doi:10.1109/TNSRE.2023.3285924.",
        "",
        verdict_section(stage, imc_stage),
        *(f"![{name.removesuffix('.png').removeprefix('fig_')}]({name})\n" for name in figures),
        "# Appendix: the tables",
        "",
        subjects_section(stage),
        "",
        table1_section(stage),
        "",
        table3_section(stage),
    ]
    if imc_stage is not None:
        parts += ["", imc_report_sections(imc_stage), "", evidence_section(imc_stage)]
        if imc_stage.limits:
            parts += ["", limits_section(imc_stage.limits)]
        if imc_stage.factors:
            parts += ["", factors_section(imc_stage.factors)]
    if xsens_stage is not None:
        parts += ["", xsens_report_section(xsens_stage)]
    return "\n".join(parts) + "\n"
