"""Hand checks of pipeline.reproduce.wang2023.factors (the data-driven table is tested with the
reproduction in test_reproduce_wang2023.py)."""

from pipeline.model.anthropometry import load_table1
from pipeline.model.measures import Measures
from pipeline.reproduce.wang2023.factors import lm_y_quirk


def test_malleolus_y_quirk_feeds_the_lateral_length_to_the_medial_equation():
    table = load_table1()
    m = Measures("m", 1.80, shank_lateral_m=0.42, shank_medial_m=0.38, knee_width_m=0.10,
                 ankle_width_m=0.07)
    eq = next(e for e in table.candidates("m", "LM", "y") if e.equation == "h+sM")
    by_hand = eq.evaluate_mm({"h": 1800.0, "s_M": 420.0}) / 1000.0  # s_M := s_L = 420 mm
    assert lm_y_quirk(m, table) == by_hand
    honest = eq.evaluate_mm({"h": 1800.0, "s_M": 380.0}) / 1000.0
    assert abs(by_hand - honest) > 1e-3  # 40 mm more shank moves the malleolus by > 1 mm
