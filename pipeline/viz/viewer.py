"""Open a recording in rerun's viewer: native, or the bundled web viewer served on 127.0.0.1."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
from pathlib import Path
from urllib.parse import quote

from pipeline.errors import InputError

__all__ = ["has_display", "port_in_use", "view", "viewer_command", "web_viewer_url"]


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


def port_in_use(port: int, host: str = "127.0.0.1") -> bool:
    """Whether a TCP ``port`` on ``host`` is taken (a bind attempt, closed at once). With
    ``SO_REUSEADDR``, as the viewer's server binds: a port a closed viewer left in TIME_WAIT
    is free to it (refused for a minute after each viewer before), one listened on is not."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as sock:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((host, int(port)))
        except OSError:
            return True
    return False


def has_display() -> bool:
    """Whether a native window can open: always on macOS and Windows, on Linux an X11 or
    Wayland display."""
    if sys.platform != "linux":
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def view(path: str | Path, web: bool = False, web_port: int = 9090, grpc_port: int = 9876) -> int:
    """Open a recording in the rerun viewer (blocks until it closes); returns its exit code.

    Refused before anything starts or is printed: a missing file, a native viewer without a
    display (hint: ``--web``), a web or gRPC port already in use (hint: ``--port`` or
    ``--grpc-port``). The viewer runs in its own process group, which is stopped with this
    command (Ctrl-C, SIGTERM, or an error), so no ``rerun --serve-web`` child outlives it.
    """
    path = Path(path)
    if not path.is_file():
        raise InputError("no such recording", file=path)
    if not web and not has_display():
        raise InputError("no display for the native viewer here; use --web to serve the web "
                         "viewer on 127.0.0.1", file=path)
    if web:
        for port, what, flag in ((web_port, "web viewer", "--port"),
                                 (grpc_port, "data (gRPC)", "--grpc-port")):
            if port_in_use(port):
                raise InputError(f"port {port} ({what}) is already in use on 127.0.0.1; choose "
                                 f"another with {flag}", field=flag[2:].replace("-", "_"))
    cmd = viewer_command(path, web=web, web_port=web_port, grpc_port=grpc_port)
    child = subprocess.Popen(cmd, start_new_session=True)
    # on SIGTERM only signal the group: the wait below then returns and `finally` reaps it
    previous = signal.signal(signal.SIGTERM, lambda *_: _signal_group(child, signal.SIGTERM))
    try:
        if web:
            print(f"web viewer: {web_viewer_url(web_port, grpc_port)} (Ctrl-C to stop)", flush=True)
        return child.wait()
    except KeyboardInterrupt:
        return 0
    finally:
        _stop(child)
        signal.signal(signal.SIGTERM, previous)


def _signal_group(child: subprocess.Popen, sig: int) -> None:
    try:
        os.killpg(child.pid, sig)
    except ProcessLookupError:
        pass


def _stop(child: subprocess.Popen) -> None:
    """Terminate the viewer's whole process group (then kill what is left after 5 s)."""
    if child.poll() is not None:
        return
    _signal_group(child, signal.SIGTERM)
    try:
        child.wait(timeout=5)
    except subprocess.TimeoutExpired:
        _signal_group(child, signal.SIGKILL)
        child.wait()
