"""pipeline.reproduce.wang2023.verdict: the report's verdict counts Table IV cells by hand."""

from __future__ import annotations

from types import SimpleNamespace

from pipeline.reproduce.wang2023.imc_report import PAPER_TABLE_IV
from pipeline.reproduce.wang2023.verdict import table4_agreement, verdict_section


def _rows(offset_mm: float, landmark: str) -> list[dict]:
    """Two subjects per sex whose stored-input RMS equals the paper's mean (+ offset for one
    landmark), so that the group mean is known by hand."""
    rows = []
    for (positions, correction, sex), cells in PAPER_TABLE_IV.items():
        for name, cell in zip(("EFM", "EFL", "MM", "LM"), cells, strict=True):
            mean = float(cell.split("±")[0]) + (offset_mm if name == landmark else 0.0)
            for sid, d in ((1, -1.0), (2, 1.0)):
                rows.append(dict(subject_id=sid if sex == "m" else sid + 10, sex=sex,
                                 tibia_input="stored", positions=positions, correction=correction,
                                 landmark=name, rms_mm=mean + d))
    return rows


def test_cells_counted_against_the_papers_means():
    stage = SimpleNamespace(corrections=("none", "average", "individual"),
                            trajectory_rows=_rows(8.0, "LM"), orientation_rows=[],
                            factors=[])
    cells = table4_agreement(stage)
    assert len(cells) == 4 * len(PAPER_TABLE_IV)
    far = [c for c in cells if abs(c[4] - c[5]) > 5.0]
    assert len(far) == len(PAPER_TABLE_IV) and all(c[3] == "LM" for c in far)
    assert all(abs(c[4] - c[5] - 8.0) < 1e-9 for c in far)
    omc = SimpleNamespace(results=[0] * 38, fits=[0] * 60)
    text = verdict_section(omc, stage)
    assert f"{3 * len(PAPER_TABLE_IV)} of {4 * len(PAPER_TABLE_IV)} cells" in text
    assert "4 IMC subjects" in text
    assert "one at a time" not in text  # no factor study given, none reported


def test_verdict_names_the_factor_closest_to_the_papers_male_lm():
    factors = [dict(subject_id=i, sex="m", factor=f, MM_mm=50.0, LM_mm=lm)
               for i in (1, 2) for f, lm in (("ours", 61.7), ("a", 64.0), ("b", 58.5))]
    stage = SimpleNamespace(corrections=("none", "average", "individual"),
                            trajectory_rows=_rows(8.0, "LM"), orientation_rows=[],
                            factors=factors)
    text = verdict_section(SimpleNamespace(results=[0] * 38, fits=[0] * 60), stage)
    assert "our male LM is 61.7 mm against 55.1 mm" in text
    assert "the closest is 'b' at 58.5 mm" in text
