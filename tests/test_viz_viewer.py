"""Tests of pipeline.viz.viewer: the viewer command lines and addresses."""

from __future__ import annotations

from pathlib import Path

import pytest

from pipeline.errors import InputError
from pipeline.viz.viewer import view, viewer_command, web_viewer_url


def test_viewer_commands(tmp_path):
    rrd = tmp_path / "x.rrd"
    native = viewer_command(rrd)
    assert native[-1] == str(rrd) and "--serve-web" not in native
    assert Path(native[0]).name.startswith("rerun") or native[1:3] == ["-m", "rerun"]
    web = viewer_command(rrd, web=True, web_port=9191, grpc_port=9877)
    assert web[-1] == str(rrd)
    i = web.index("--bind")
    assert web[i + 1] == "127.0.0.1"
    assert web[web.index("--web-viewer-port") + 1] == "9191"
    assert web[web.index("--port") + 1] == "9877"
    assert "--serve-web" in web
    assert web_viewer_url(9191, 9877) == (
        "http://127.0.0.1:9191/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A9877%2Fproxy"
    )
    with pytest.raises(InputError):
        view(tmp_path / "missing.rrd")


def _free_port() -> int:
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture
def rrd(tmp_path):
    import numpy as np

    from pipeline.viz.recording import log_trial

    path = tmp_path / "t.rrd"
    log_trial(path, np.arange(5) / 10.0, {"EFM": np.zeros((5, 3))})
    return path


def test_busy_port_refused_before_anything_is_printed(rrd, capsys):
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        busy = s.getsockname()[1]
        with pytest.raises(InputError, match=f"port {busy}.*another with --port$"):
            view(rrd, web=True, web_port=busy, grpc_port=_free_port())
        with pytest.raises(InputError, match=f"port {busy} \\(data.*another with --grpc-port"):
            view(rrd, web=True, web_port=_free_port(), grpc_port=busy)
    assert capsys.readouterr().out == ""


def test_a_port_a_closed_server_left_in_time_wait_is_free():
    """A viewer just closed leaves its port in TIME_WAIT (the server closed first): free to the
    next viewer, which binds with SO_REUSEADDR (refused for a minute before)."""
    import socket

    from pipeline.viz.viewer import port_in_use

    server = socket.socket()
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind(("127.0.0.1", 0))
    server.listen()
    port = server.getsockname()[1]
    client = socket.create_connection(("127.0.0.1", port))
    conn, _ = server.accept()
    conn.close()  # the server's side closes first: its port goes to TIME_WAIT
    server.close()
    client.close()
    assert not port_in_use(port)


def test_native_viewer_without_display_hints_web(rrd, monkeypatch):
    from pipeline.viz import viewer

    monkeypatch.setattr(viewer, "has_display", lambda: False)
    with pytest.raises(InputError, match="--web"):
        view(rrd)


@pytest.mark.slow
def test_sigterm_stops_the_served_viewer_and_its_children(rrd):
    """`pipeline view --web` stopped with a real SIGTERM leaves no rerun server behind."""
    import signal
    import subprocess
    import sys
    import time

    from pipeline.viz.viewer import port_in_use

    web, grpc = _free_port(), _free_port()
    cmd = [sys.executable, "-m", "pipeline", "view", str(rrd), "--web", "--port", str(web),
           "--grpc-port", str(grpc)]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    try:
        assert f"127.0.0.1:{web}" in proc.stdout.readline()
        deadline = time.monotonic() + 30
        while not port_in_use(grpc) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert port_in_use(grpc), "the viewer's server did not start"
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=15)
        deadline = time.monotonic() + 10
        while (port_in_use(web) or port_in_use(grpc)) and time.monotonic() < deadline:
            time.sleep(0.2)
        assert not port_in_use(web) and not port_in_use(grpc)  # the children are gone
    finally:
        if proc.poll() is None:
            proc.kill()
