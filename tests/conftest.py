"""Shared fixtures: a simulated trial written by ``pipeline simulate`` (one per test session)."""

from __future__ import annotations

import pytest

from pipeline.cli import main


@pytest.fixture(scope="session")
def sim(tmp_path_factory):
    """The folder ``pipeline simulate --out`` wrote (default motion, seed 0)."""
    out = tmp_path_factory.mktemp("sim") / "gait"
    assert main(["simulate", "--out", str(out)]) == 0
    return out
