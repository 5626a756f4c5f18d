"""``pipeline reproduce``: a paper's results on its published data (only this command loads
:mod:`pipeline.reproduce`)."""

from __future__ import annotations

from pathlib import Path

from pipeline.errors import InputError

__all__ = ["PAPERS", "run_reproduce"]

PAPERS = ("wang2023",)


def run_reproduce(paper: str, data: str | Path, out: str | Path,
                  rerun_dir: str | Path | None = None) -> str:
    """Run the reproduction of ``paper`` (one of :data:`PAPERS`); return its summary line."""
    if paper not in PAPERS:
        raise InputError(f"expected a paper in {PAPERS}, got {paper!r}", field="paper")
    from pipeline.reproduce.wang2023 import reproduce_wang2023  # the paper code, only here

    return reproduce_wang2023(data, out, rerun_dir=None if rerun_dir is None else Path(rerun_dir))
