"""``pipeline reproduce wang2023``: Wang et al. 2023 on its published dataset.

Stage 1 (optical data, all 38 subjects): see :mod:`pipeline.reproduce.wang2023.optical`.

Stage 2 (IMC subjects; Wang §II.B-C, §III.C): see :mod:`pipeline.reproduce.wang2023.imc`.

Stage 3 (Xsens MVN comparison; Tables II, VI, VII): see :mod:`pipeline.reproduce.wang2023.xsens`.

Outputs (mm and degrees, written all-or-nothing): ``subjects.csv``, ``landmarks_in_segments.csv``,
``knee_aor.csv``, ``regression.csv``, ``report.md`` and the IMC tables when stage 2 runs.
"""

from __future__ import annotations

from pathlib import Path

from pipeline.errors import InputError
from pipeline.io.atomic import output_dir, output_set
from pipeline.reproduce.wang2023.evidence import evidence_tables
from pipeline.reproduce.wang2023.factors import factor_rows, factors_tables
from pipeline.reproduce.wang2023.figures import imc_figures
from pipeline.reproduce.wang2023.imc import imc_tables, run_imc_stage
from pipeline.reproduce.wang2023.limits import limit_rows, limits_tables
from pipeline.reproduce.wang2023.optical import omc_tables, run_omc_stage
from pipeline.reproduce.wang2023.report import render_report
from pipeline.reproduce.wang2023.xsens import run_xsens_stage, xsens_tables

__all__ = ["reproduce_wang2023"]


def reproduce_wang2023(
    data_dir: str | Path,
    out_dir: str | Path,
    *,
    rerun_dir: str | Path | None = None,
    progress: bool = True,
    imc: bool = True,
) -> str:
    """Run the reproduction; write its files into ``out_dir`` (all or none); return a summary."""
    data_dir, out_dir = Path(data_dir), Path(out_dir)
    if not data_dir.exists():
        raise InputError("dataset directory not found: the published data (raw/, xsens/) are at "
                         "github.com/wangzhengtao1993/AnatomicalLandmarkTrajectoriesBasedonIMUData",
                         file=data_dir)
    stage = run_omc_stage(data_dir, progress=progress)
    files = omc_tables(stage)
    imc_stage = None
    if imc:
        imc_stage = run_imc_stage(stage, rerun_dir=rerun_dir, progress=progress)
        imc_stage.factors = factor_rows(stage, imc_stage)
        imc_stage.limits = limit_rows(stage, imc_stage)
        files.update(imc_tables(imc_stage))
        files.update(factors_tables(imc_stage.factors))
        files.update(evidence_tables(imc_stage))
        files.update(limits_tables(imc_stage.limits))
    xsens_stage = None
    if imc and (data_dir / "xsens").is_dir():
        xsens_stage = run_xsens_stage(data_dir, omc_stage=stage)
        files.update(xsens_tables(xsens_stage))
    figures = {} if imc_stage is None else imc_figures(imc_stage)
    files["report.md"] = render_report(stage, imc_stage, xsens_stage, figures=tuple(figures))
    output_dir(out_dir)
    with output_set() as out:
        for name, text in files.items():
            with out.open(out_dir / name) as fh:
                fh.write(text)
        for name, png in figures.items():
            with out.open(out_dir / name, "wb") as fh:
                fh.write(png)
    names = sorted([*files, *figures])
    return f"wrote {', '.join(names)} to {out_dir} ({len(stage.results)} subjects)"
