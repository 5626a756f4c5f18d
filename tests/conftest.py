"""Shared fixtures: a simulated trial written by ``pipeline simulate`` (one per test session) and
a finder of the processes a command may leave behind."""

from __future__ import annotations

from pathlib import Path

import pytest

from pipeline.cli import main


@pytest.fixture(scope="session")
def sim(tmp_path_factory):
    """The folder ``pipeline simulate --out`` wrote (default motion, seed 0)."""
    out = tmp_path_factory.mktemp("sim") / "gait"
    assert main(["simulate", "--out", str(out)]) == 0
    return out


@pytest.fixture
def processes_with():
    """``f(arg)``: pids of the running (not zombie) processes whose command line holds ``arg``
    (Linux /proc): what a command that forked may have left behind."""

    def find(arg: str) -> list[int]:
        pids = []
        for d in Path("/proc").glob("[0-9]*"):
            try:
                cmd = (d / "cmdline").read_bytes().split(b"\0")
                state = (d / "stat").read_text().rsplit(")", 1)[1].split()[0]
            except OSError:
                continue
            if arg.encode() in cmd and state != "Z":
                pids.append(int(d.name))
        return pids

    return find
