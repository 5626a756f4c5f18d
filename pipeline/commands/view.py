"""``pipeline view``: open a recording in the rerun viewer."""

from __future__ import annotations

from pathlib import Path

from pipeline.errors import InputError
from pipeline.viz.rrd import rrd_problem
from pipeline.viz.viewer import view

__all__ = ["run_view"]


def run_view(rrd: str | Path, web: bool = False, port: int = 9090, grpc_port: int = 9876) -> int:
    """Open ``rrd`` (native viewer, or the web viewer on 127.0.0.1:``port``, its data served on
    ``grpc_port``); returns the exit code."""
    rrd = Path(rrd)
    if not rrd.exists():
        raise InputError("no such recording", file=rrd)
    problem = rrd_problem(rrd)
    if problem:
        raise InputError(f"{problem}: expected a whole rerun recording (.rrd)", file=rrd)
    return int(view(rrd, web=web, web_port=port, grpc_port=grpc_port) or 0)
