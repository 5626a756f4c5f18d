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
