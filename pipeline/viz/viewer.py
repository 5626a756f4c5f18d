"""Open a recording in rerun's viewer: native, or the bundled web viewer served on 127.0.0.1."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path
from urllib.parse import quote

from pipeline.errors import InputError

__all__ = ["view", "viewer_command", "web_viewer_url"]


def _rerun_executable() -> list[str]:
    exe = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    return [exe] if Path(exe).exists() else [sys.executable, "-m", "rerun"]


def viewer_command(
    path: str | Path, web: bool = False, web_port: int = 9090, grpc_port: int = 9876
) -> list[str]:
    """Command line that opens ``path``: native viewer, or the web viewer served on 127.0.0.1."""
    cmd = _rerun_executable()
    if web:
        cmd += [
            "--serve-web",
            "--bind",
            "127.0.0.1",
            "--web-viewer-port",
            str(web_port),
            "--port",
            str(grpc_port),
        ]
    return [*cmd, str(Path(path))]


def web_viewer_url(web_port: int = 9090, grpc_port: int = 9876) -> str:
    """Address of the served web viewer, connected to the local gRPC proxy holding the data."""
    proxy = quote(f"rerun+http://127.0.0.1:{grpc_port}/proxy", safe="")
    return f"http://127.0.0.1:{web_port}/?url={proxy}"


def view(path: str | Path, web: bool = False, web_port: int = 9090, grpc_port: int = 9876) -> int:
    """Open a recording in the rerun viewer (blocks until it closes); returns its exit code."""
    path = Path(path)
    if not path.is_file():
        raise InputError("no such recording", file=path)
    cmd = viewer_command(path, web=web, web_port=web_port, grpc_port=grpc_port)
    if web:
        print(f"web viewer: {web_viewer_url(web_port, grpc_port)} (Ctrl-C to stop)", flush=True)
    try:
        return subprocess.call(cmd)
    except KeyboardInterrupt:
        return 0
