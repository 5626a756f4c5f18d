"""pipeline.reproduce.wang2023.evidence: per-subject malleolus errors and the paired test."""

import numpy as np
import pytest

from pipeline.reproduce.wang2023.evidence import evidence_rows, evidence_section
from pipeline.reproduce.wang2023.imc import ImcStage


def _stage(errors: dict[str, list[tuple[float, float]]]) -> ImcStage:
    rows = []
    for correction, per_subject in errors.items():
        for sid, (mm, lm) in enumerate(per_subject, start=1):
            for name, v in (("MM", mm), ("LM", lm)):
                for tibia_input in ("uncorrected", "stored"):
                    rows.append(dict(subject_id=sid, sex="m", tibia_input=tibia_input,
                                     positions="regression", correction=correction,
                                     landmark=name, rms_mm=v))
    return ImcStage(rows, [], [], tuple(errors), 0.0)


def test_rows_and_the_test_by_hand():
    base = [(60.0, 62.0), (70.0, 66.0), (50.0, 54.0), (80.0, 78.0), (55.0, 57.0), (65.0, 61.0)]
    better = [(m - 5 - k, lm - 5 - k) for k, (m, lm) in enumerate(base)]  # every subject better
    stage = _stage({"average": base, "new": better, "none": base})
    rows = [r for r in evidence_rows(stage) if r["tibia_input"] == "uncorrected"]
    new = [r for r in rows if r["correction"] == "new"]
    assert [r["minus_closed_form_mm"] for r in new] == pytest.approx([-5.0 - k for k in range(6)])
    assert new[0]["malleoli_mm"] == pytest.approx(0.5 * (55 + 57))
    text = evidence_section(stage)
    # six subjects all better: the exact two-sided signed-rank p is 2 / 2^6 = 0.031
    assert "| uncorrected | new | 6 |" in text and "| 0.031 | 6/6 |" in text
    from scipy.stats import wilcoxon

    assert wilcoxon(np.array([r["minus_closed_form_mm"] for r in new])).pvalue == pytest.approx(
        2 / 2**6)
    assert "| uncorrected | none | 6 |" in text and "n/a | 0/6 |" in text  # identical: no test
    assert "the 42 mm goal" in text and "not reached" in text
