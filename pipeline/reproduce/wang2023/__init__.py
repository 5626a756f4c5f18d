"""Wang et al. 2023 on its published dataset (``pipeline reproduce wang2023``).

Paper-only code lives here, apart from the product: the dataset reader (:mod:`.dataset`), optical
processing (:mod:`.omc`: sphere-fit hip centre, ISB frames), Table I fitting (:mod:`.regression`),
the validation statistics (:mod:`.evaluation`: eq 18-20, RMS, r, ICC, Euler errors), the IMC
stage (:mod:`.imc`: Tables IV-V), the Xsens MVN comparison (:mod:`.xsens_mvn`, :mod:`.xsens`:
Tables II, VI, VII) and the report (:mod:`.report`). Its user-facing steps call the product's
domain code (model, calibration, IK, analysis).
"""

from pipeline.reproduce.wang2023.run import reproduce_wang2023

__all__ = ["reproduce_wang2023"]
