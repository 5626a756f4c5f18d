"""pipeline live: the shipped walk replayed through the command (every output written, all or
nothing), stopped by SIGTERM mid-capture (the capture so far written), and its refusals."""

import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import main
from pipeline.io.formats import read_recording
from pipeline.io.mot import read_mot

ARGS = ["--sex", "m", "--height-m", "1.8", "--viewer", "none"]


def test_the_shipped_walk_replayed_writes_the_capture_and_pipeline_iks_outputs(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["live", "--replay", "example:ximu3_lower_body", "--speed", "max", *ARGS,
                 "--no-rerun", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "live: stand still" in err and "live: calibrated" in err
    name = "ximu3_lower_body"
    names = {p.name for p in out.iterdir()}
    assert {f"{name}_capture", f"{name}_ik.mot", f"{name}_live.mot", f"{name}_summary.md",
            f"{name}_config.toml", f"{name}.urdf"} <= names
    capture = read_recording(out / f"{name}_capture")  # pipeline ik reads it back
    assert capture.n_samples == 929 and len(capture.sensor_names) == 7
    live, offline = read_mot(out / f"{name}_live.mot"), read_mot(out / f"{name}_ik.mot")
    assert set(offline.columns) - {"pelvis_tx", "pelvis_ty", "pelvis_tz"} <= set(live.columns)
    late = live.time > 12.0  # after the final calibration
    d = np.degrees(live.columns["knee_angle_r"][late] - offline.columns["knee_angle_r"][late])
    assert np.sqrt(np.mean(d**2)) < 1.0
    assert "orientations" in (out / f"{name}_config.toml").read_text()


def test_sigterm_ends_the_capture_and_writes_it(tmp_path):
    """A real-time replay stopped by SIGTERM after 3 s: exit 0, the 3 s captured written."""
    out = tmp_path / "out"
    p = subprocess.Popen([sys.executable, "-m", "pipeline", "live", "--replay",
                          "example:ximu3_lower_body", *ARGS, "--no-rerun", "--out", str(out)],
                         stderr=subprocess.PIPE, text=True)
    time.sleep(4.0)  # the imports, then about 3 s of capture
    p.send_signal(signal.SIGTERM)
    assert p.wait(timeout=60) == 0, p.stderr.read()
    assert "live: stopped; writing the capture" in p.stderr.read()
    capture = read_recording(out / "ximu3_lower_body_capture")
    assert 1.0 < capture.time[-1] < 4.5


def test_a_source_is_needed_and_an_lsl_without_streams_is_one_line(tmp_path, capsys):
    assert main(["live", *ARGS, "--out", str(tmp_path / "a")]) == 2
    assert "give one source: --replay RECORDING or --lsl" in capsys.readouterr().err
    pytest.importorskip("pylsl")
    from pipeline.errors import InputError
    from pipeline.live.sources import LslSource

    with pytest.raises(InputError, match="no LSL stream of type IMU found within 0.2 s"):
        LslSource(resolve_s=0.2, prefix="nobody-streams-this/")


def test_a_slow_or_closed_viewer_never_holds_the_capture(tmp_path, monkeypatch):
    """The viewer logs from its own queue: a viewer that takes 0.5 s a frame (or has gone) gets
    frames dropped, and each ``log`` returns at once."""
    from pipeline.live.viewer import LiveViewer

    viewer = LiveViewer("test", "save", path=tmp_path / "v.rrd")
    monkeypatch.setattr(viewer, "_show", lambda item: time.sleep(0.5))
    t0 = time.perf_counter()
    for k in range(200):
        viewer.log(np.array([k / 10.0]), {"pelvis": (np.eye(3)[None], np.zeros((1, 3)))},
                   {"right_knee_flexion": np.array([0.3])}, None)
    assert time.perf_counter() - t0 < 0.5 and viewer.dropped > 150
    monkeypatch.setattr(viewer, "_show", lambda item: 1 / 0)  # a viewer gone: errors swallowed
    viewer.log(np.array([100.0]), {}, {}, None)
    viewer.close()
    assert Path(tmp_path / "v.rrd").exists()
