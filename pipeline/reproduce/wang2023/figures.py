"""Figures of the Wang 2023 reproduction (PNG, matplotlib), shown in ``report.md``.

* ``fig_table4.png``: Table IV as grouped bars, mean ± SD over subjects of each landmark's RMS
  error, per correction method, for both tibia inputs (regression landmark positions), with the
  paper's means as markers where the paper has the configuration;
* ``fig_malleoli_per_subject.png``: each subject's malleolus error (mean of MM and LM) per
  correction method, on the uncorrected tibia input: who improves with which method;
* ``fig_trajectories.png``: one subject's lateral malleolus trajectory over time, each axis, IMU
  (uncorrected tibia, no correction and the closed-form correction) against optical;
* ``fig_bland_altman.png``: Bland-Altman plots of that subject's malleolus coordinates (IMU minus
  optical against their mean, all samples and axes; bias and 95 % limits of agreement), before
  and after the correction.

matplotlib is imported here only (the Agg backend: no display needed).
"""

from __future__ import annotations

import io

import numpy as np

from pipeline.reproduce.wang2023.imc import LANDMARKS, ImcStage, rms_values
from pipeline.reproduce.wang2023.imc_report import PAPER_TABLE_IV, paper_mean

__all__ = ["FIGURES", "imc_figures"]

FIGURES = ("fig_table4.png", "fig_malleoli_per_subject.png", "fig_trajectories.png",
           "fig_bland_altman.png")


def _png(fig) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, bbox_inches="tight", metadata={"Software": None})
    return buf.getvalue()


def imc_figures(stage: ImcStage) -> dict[str, bytes]:
    """File name -> PNG bytes of the module docstring's figures."""
    from pipeline.optional import need

    matplotlib = need("matplotlib", "pipeline reproduce's figures")

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = {}
    methods = list(stage.corrections)
    rows = stage.trajectory_rows
    fig, axes = plt.subplots(1, 2, figsize=(13, 4.2), sharey=True)
    width = 0.8 / len(methods)
    x = np.arange(len(LANDMARKS))
    for ax, tibia_input in zip(axes, ("stored", "uncorrected"), strict=True):
        for k, method in enumerate(methods):
            vals = [rms_values(rows, tibia_input=tibia_input, positions="regression",
                               correction=method, landmark=n) for n in LANDMARKS]
            mean = [np.nanmean(v) for v in vals]
            sd = [np.nanstd(v, ddof=1) if np.isfinite(v).sum() > 1 else 0.0 for v in vals]
            ax.bar(x + (k - (len(methods) - 1) / 2) * width, mean, width, yerr=sd, capsize=2,
                   label=method)
        if tibia_input == "stored":
            for k, method in enumerate(methods):
                for sex, marker in (("m", "v"), ("f", "^")):
                    paper = PAPER_TABLE_IV.get(("regression", method, sex))
                    if paper is None:
                        continue
                    means = [paper_mean(c) for c in paper]
                    ax.plot(x + (k - (len(methods) - 1) / 2) * width, means, marker, color="k",
                            ms=4, label=f"paper ({sex})" if k == 0 else None)
        ax.set_xticks(x, LANDMARKS)
        ax.set_title(f"tibia input: {tibia_input} (regression positions)")
        ax.grid(axis="y", alpha=0.3)
    axes[0].set_ylabel("RMS error (mm), mean ± SD over subjects")
    axes[0].legend(fontsize=7, ncol=2, title="correction; black: paper's means", title_fontsize=7)
    out["fig_table4.png"] = _png(fig)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(9, 4.2))
    subjects = sorted({r["subject_id"] for r in stage.trajectory_rows})
    for method in methods:
        per = []
        for sid in subjects:
            v = np.concatenate([rms_values(rows, tibia_input="uncorrected", positions="regression",
                                           correction=method, landmark=n, subject_id=sid)
                                for n in ("MM", "LM")])
            per.append(np.nanmean(v) if v.size else np.nan)
        ax.plot(range(len(subjects)), per, "o-", ms=4, lw=1, label=method)
    ax.set_xticks(range(len(subjects)), [str(s) for s in subjects])
    ax.set_xlabel("subject")
    ax.set_ylabel("malleolus RMS error (mm, mean of MM and LM)")
    ax.set_title("per subject, uncorrected tibia input, regression positions")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8, ncol=3)
    out["fig_malleoli_per_subject.png"] = _png(fig)
    plt.close(fig)
    ex = stage.example
    if ex and {"none", "average"} <= set(ex.get("imc", {})):
        out.update(_example_figures(plt, ex))
    return out


def _example_figures(plt, ex: dict) -> dict[str, bytes]:
    out = {}
    omc, imc = ex["omc"], ex["imc"]
    t = np.arange(len(omc["LM"])) / ex["rate_hz"]
    fig, axes = plt.subplots(3, 1, figsize=(10, 6.5), sharex=True)
    for k, (ax, axis) in enumerate(zip(axes, "xyz", strict=True)):
        ax.plot(t, omc["LM"][:, k], "k", lw=1.6, label="optical")
        ax.plot(t, imc["none"]["LM"][:, k], lw=1, label="IMU, no correction")
        ax.plot(t, imc["average"]["LM"][:, k], lw=1, label="IMU, closed-form AoR correction")
        ax.set_ylabel(f"LM {axis} (mm)")
        ax.grid(alpha=0.3)
    axes[0].set_title(f"subject {ex['subject_id']}: lateral malleolus, hip-centred, optical frame "
                      "(uncorrected tibia, regression positions)")
    axes[0].legend(fontsize=8, ncol=3)
    axes[-1].set_xlabel("time (s)")
    out["fig_trajectories.png"] = _png(fig)
    plt.close(fig)
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    for ax, method, title in zip(axes, ("none", "average"), ("no correction",
                                 "closed-form AoR correction"), strict=True):
        a = np.concatenate([imc[method][n] for n in ("MM", "LM")]).ravel()
        b = np.concatenate([omc[n] for n in ("MM", "LM")]).ravel()
        ok = np.isfinite(a) & np.isfinite(b)
        mean, diff = 0.5 * (a[ok] + b[ok]), a[ok] - b[ok]
        bias, sd = float(np.mean(diff)), float(np.std(diff, ddof=1))
        ax.scatter(mean, diff, s=2, alpha=0.25)
        for y, style in ((bias, "-"), (bias + 1.96 * sd, "--"), (bias - 1.96 * sd, "--")):
            ax.axhline(y, color="k", ls=style, lw=1)
        ax.set_title(f"{title}: bias {bias:.1f} mm, 95 % limits {bias - 1.96 * sd:.1f} to "
                     f"{bias + 1.96 * sd:.1f} mm", fontsize=9)
        ax.set_xlabel("mean of IMU and optical (mm; MM, LM coordinates, all samples)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("IMU minus optical (mm)")
    out["fig_bland_altman.png"] = _png(fig)
    plt.close(fig)
    return out
