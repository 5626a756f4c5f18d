"""pipeline.io.lock: one run per output folder; a second refused naming the first, a stale lock
taken over, the lock gone on any exit; and through ``pipeline ik``."""

import json
import os
import socket
import subprocess
import sys

import pytest

from pipeline.errors import InputError
from pipeline.io.lock import LOCK_NAME, output_lock


def test_a_second_run_is_refused_naming_the_first(tmp_path):
    out = tmp_path / "out"
    with output_lock(out, "pipeline ik of a.sto") as lock:
        held = json.loads(lock.read_text())
        assert held["pid"] == os.getpid() and held["what"] == "pipeline ik of a.sto"
        with pytest.raises(InputError, match=r"another run \(pid \d+ on .*pipeline ik of a\.sto\)"
                                              r" is writing into this folder"):
            with output_lock(out, "pipeline ik of b.sto"):
                pass
    assert not (out / LOCK_NAME).exists()  # released
    with output_lock(out, "again"):
        pass


def test_a_stale_lock_is_taken_over_and_a_failure_leaves_nothing(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    (out / LOCK_NAME).write_text(json.dumps({"pid": int(dead), "host": socket.gethostname(),
                                             "started": "then", "what": "a run killed"}))
    notes: list[str] = []
    with output_lock(out, "mine", notes) as lock:
        assert json.loads(lock.read_text())["what"] == "mine"
    assert notes and "a stale lock of a run that no longer runs" in notes[0]
    fresh = tmp_path / "fresh"
    with pytest.raises(KeyboardInterrupt), output_lock(fresh, "interrupted"):
        raise KeyboardInterrupt
    assert not fresh.exists()  # created for the lock, empty: removed again


def test_pipeline_ik_refuses_a_folder_in_use_and_the_recording_folder(tmp_path, capsys):
    from pipeline.cli import main

    args = ["ik", "--orientations", "example:opensense_imu_ik_test", "--sex", "m", "--height-m",
            "1.75", "--no-rerun"]
    out = tmp_path / "out"
    with output_lock(out, "pipeline ik of another recording"):
        assert main([*args, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "pipeline ik of another recording" in err and "is writing into this folder" in err
    assert not any(p.name != LOCK_NAME for p in out.iterdir())
    folder = tmp_path / "recording"
    folder.mkdir()
    (folder / "pelvis_imu.csv").write_text("time,gyr_x\n")
    code = main(["ik", "--orientations", str(folder), "--sex", "m", "--height-m", "1.75",
                 "--out", str(folder / "out")])
    assert code == 2 and "--out is in the recording's own folder" in capsys.readouterr().err
