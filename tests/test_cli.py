"""The command line: help with examples, one-line errors, exit codes, no partial outputs."""

import contextlib
from pathlib import Path

import numpy as np
import pytest

from pipeline.cli import EXAMPLES, build_parser, main

OPENSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opensim"


def test_every_command_has_help_with_an_example(capsys):
    parser = build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert set(sub.choices) == set(EXAMPLES) == {
        "scale", "ik", "orientations", "calibrate", "simulate", "reproduce", "demo",
        "view", "batch", "live"}
    for name in EXAMPLES:
        with pytest.raises(SystemExit) as exc:
            main([name, "--help"])
        assert exc.value.code == 0
        out = capsys.readouterr().out
        assert "example" in out and f"pipeline {name}" in out


HEADER = "DataRate=100.000000\nDataType=Quaternion\nversion=3\nendheader\n"
COLUMNS = ["pelvis_imu", "femur_r_imu", "tibia_r_imu"]


def _sto(rows, columns=COLUMNS, header=HEADER):
    lines = ["time\t" + "\t".join(columns)]
    for t, quats in rows:
        lines.append(f"{t:g}\t" + "\t".join(",".join(f"{v:.9g}" for v in q) for q in quats))
    return header + "\n".join(lines) + "\n"


def _rows(n=50, dt=0.01):
    q = [1.0, 0.0, 0.0, 0.0]
    return [(k * dt, [q] * len(COLUMNS)) for k in range(n)]


def _bad_files():
    rows = _rows()
    unsorted = list(rows)
    unsorted[10], unsorted[11] = unsorted[11], unsorted[10]
    repeated = list(rows)
    repeated[20] = (rows[19][0], rows[20][1])
    zero_q = [(t, [[0, 0, 0, 0]] + q[1:]) if k == 5 else (t, q) for k, (t, q) in enumerate(rows)]
    big_q = [(t, [[3, 0, 0, 0]] + q[1:]) if k == 5 else (t, q) for k, (t, q) in enumerate(rows)]
    full = _sto(rows)
    return {
        "empty": ("", "empty"),
        "header only": (HEADER, "column"),
        "truncated": (full[: len(full) - 20], "truncated"),  # cut mid-row
        "unsorted time": (_sto(unsorted), "time"),
        "repeated time": (_sto(repeated), "time"),
        "zero quaternion": (_sto(zero_q), "quaternion"),
        "non-unit quaternion": (_sto(big_q), "unit"),
        "rate mismatch": (_sto(_rows(dt=0.02)), "rate"),
    }


@pytest.mark.parametrize("case", list(_bad_files()))
def test_bad_sto_refused_with_one_line(tmp_path, capsys, case):
    text, expected = _bad_files()[case]
    path = tmp_path / "bad.sto"
    path.write_text(text)
    out = tmp_path / "out"
    code = main(["ik", "--orientations", str(path), "--sex", "m", "--height-m", "1.75",
                 "--out", str(out)])
    err = capsys.readouterr().err.strip()
    assert code == 2, err
    assert len(err.splitlines()) == 1 and "Traceback" not in err
    assert expected.lower() in err.lower(), err
    assert not out.exists() or not any(out.iterdir())  # nothing half-written


@pytest.mark.parametrize("columns", [COLUMNS, COLUMNS[1:]])
def test_a_still_recording_runs_and_says_what_it_could_not_observe(tmp_path, capsys, columns):
    """Half a second of one pose (with the pelvis, or a knee alone): no heading to find from a
    motion, none needed; the pose read in its still window, unchecked (no walk), no flag."""
    rows = [(t, q[-len(columns):]) for t, q in _rows()]
    path = tmp_path / "still.sto"
    path.write_text(_sto(rows, columns))
    code = main(["ik", "--orientations", str(path), "--sex", "m", "--height-m", "1.75",
                 "--out", str(tmp_path / "out")])
    assert code == 0
    summary = (tmp_path / "out" / "still_summary.md").read_text()
    assert "the subject's heading is not observed" in summary
    assert "read in the still window 0.00-0.49 s (not checked: no walk to check it by)" in summary
    assert "warning" not in capsys.readouterr().err


def test_units_hint_for_height_in_cm(tmp_path, capsys):
    code = main(["ik", "--orientations", str(tmp_path / "x.sto"), "--sex", "m",
                 "--height-m", "175", "--out", str(tmp_path)])
    assert code == 2
    assert "centimetres" in capsys.readouterr().err


def test_missing_file(tmp_path, capsys):
    code = main(["ik", "--orientations", str(tmp_path / "nope.sto"), "--sex", "m",
                 "--height-m", "1.75", "--out", str(tmp_path / "o")])
    assert code == 2
    assert "nope.sto" in capsys.readouterr().err


def test_debug_shows_the_traceback(tmp_path):
    from pipeline.errors import InputError

    with pytest.raises(InputError):
        main(["--debug", "ik", "--orientations", str(tmp_path / "nope.sto"), "--sex", "m",
              "--height-m", "1.75", "--out", str(tmp_path / "o")])


def test_cli_defaults_are_the_librarys():
    """The CLI's defaults were once their own (``--knee free`` vs ``build_urdf``'s hinge,
    ``--method ipopt`` vs ``calibrate``'s gn): now both read one constant."""
    import inspect

    from pipeline.calibration.calibrate import calibrate
    from pipeline.calibration.conventions import DEFAULT_METHOD
    from pipeline.cli import build_parser
    from pipeline.model.builder import build_urdf, urdf_text
    from pipeline.model.conventions import DEFAULT_KNEE
    from pipeline.model.skeleton import Skeleton
    from pipeline.process import IKOptions

    parser = build_parser()
    scale = parser.parse_args(["scale", "--sex", "f", "--height-m", "1.6", "--out", "a.urdf"])
    ik = parser.parse_args(["ik", "--orientations", "x.sto", "--sex", "f", "--height-m", "1.6",
                            "--out", "o"])
    cal = parser.parse_args(["calibrate", "hinge", "--imu1", "a.csv", "--imu2", "b.csv"])
    assert ik.knee is None  # not given: the configuration file's or IKOptions' value applies
    assert scale.knee == IKOptions().knee == DEFAULT_KNEE
    for f in (build_urdf, urdf_text, Skeleton.build):
        assert inspect.signature(f).parameters["knee"].default == DEFAULT_KNEE, f
    assert cal.method == DEFAULT_METHOD == inspect.signature(calibrate).parameters["method"].default


def test_sensor_to_model_refuses_nan_and_degrees(capsys, tmp_path):
    sto = Path(__file__).resolve().parents[2] / "shared/data/opensim/quaternions_4_ik.sto"
    if not sto.is_file():
        pytest.skip("needs ../shared/data/opensim")
    base = ["ik", "--orientations", str(sto), "--sex", "m", "--height-m", "1.8", "--out"]
    for bad, needle in ((["nan", "0", "0"], "finite"), (["-90", "0", "0"], "-1.5708")):
        out = tmp_path / bad[0]
        assert main([*base, str(out), "--sensor-to-model", *bad]) == 2
        err = capsys.readouterr().err
        assert "sensor_to_model" in err and needle in err and "Traceback" not in err
        assert not out.exists() or not any(out.iterdir())  # nothing written


def _no_traceback_one_line(capsys, *needles):
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    for n in needles:
        assert n in err, err


def test_output_path_faults_are_one_line_errors(capsys, tmp_path):
    a_file = tmp_path / "a_file"
    a_file.write_text("x")
    for argv, needle in (
        (["simulate", "--out", str(a_file)], "found a file"),
        (["simulate", "--out", str(a_file / "sub")], "is a file, not a folder"),
        (["demo", "--out", str(a_file / "sub")], "is a file, not a folder"),
    ):
        assert main(argv) == 2
        _no_traceback_one_line(capsys, needle, str(a_file))
    assert a_file.read_text() == "x"


@contextlib.contextmanager
def _tmpfs(path: Path, options: str):
    """A real tmpfs mounted at ``path`` for the test (needs root, as in CI; skipped otherwise)."""
    import subprocess

    path.mkdir()
    mount = ["mount", "-t", "tmpfs", "-o", options, "tmpfs", str(path)]
    if subprocess.run(mount, capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    try:
        yield path
    finally:
        subprocess.run(["umount", str(path)], check=True)


def test_full_disk_leaves_nothing_half_written(capsys, tmp_path):
    """A real 300 kB filesystem: the demo's outputs do not fit."""
    with _tmpfs(tmp_path / "tiny", "size=300k") as tiny:
        assert main(["demo", "--out", str(tiny / "demo")]) == 2
        _no_traceback_one_line(capsys, "No space left on device")
        assert not any(p.is_file() for p in tiny.rglob("*"))  # nothing half-written


def test_read_only_output_folder_is_a_one_line_error(capsys, tmp_path):
    """A real read-only filesystem (root ignores permission bits, not a read-only mount)."""
    with _tmpfs(tmp_path / "ro", "ro,size=1m") as ro:
        assert main(["simulate", "--out", str(ro / "sim"), "--duration-s", "1"]) == 2
        _no_traceback_one_line(capsys, str(ro / "sim"), "not writable")
        assert not any(ro.iterdir())


def test_every_option_states_its_default_or_that_it_is_required():
    import argparse

    from pipeline.cli import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    missing = [
        (name, a.option_strings)
        for name, sp in sub.choices.items()
        for a in sp._actions
        if a.option_strings and a.dest != "help" and a.help != argparse.SUPPRESS
        and not any(w in (a.help or "") for w in ("default", "required"))
    ]
    assert missing == []


@pytest.mark.slow
def test_sigterm_during_ik_leaves_all_or_nothing(tmp_path, processes_with):
    """A real SIGTERM at several moments of `pipeline ik`: either every output exists (the run
    finished) or none does (exit 143), never a half-written set."""
    import signal
    import subprocess
    import sys
    import time

    sto = Path(__file__).resolve().parents[2] / "shared/data/opensim/xsens_walking_orientations.sto"
    if not sto.is_file():
        pytest.skip("needs ../shared/data/opensim")
    outcomes = set()
    for k, delay in enumerate((0.3, 0.5, 0.8, 1.4, 2.0, 2.6, 3.2)):
        out = tmp_path / f"run{k}"
        cmd = [sys.executable, "-m", "pipeline", "ik", "--orientations", str(sto), "--sex", "m",
               "--height-m", "1.8", "--sensor-to-model", "-1.5708", "0", "0", "--out", str(out)]
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        time.sleep(delay)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        files = sorted(p.name for p in out.glob("*")) if out.exists() else []
        # the recording's forked child (pipeline.viz.background, same command line) is gone
        assert processes_with(str(out)) == [], (delay, proc.returncode)
        # all or nothing: the seven outputs (.mot, .csv, .urdf, .rrd, summary, configuration,
        # figures) or none. A signal after the outputs were committed (while Python exits) still
        # leaves the complete set.
        assert len(files) in (0, 8), (proc.returncode, files, err)
        if proc.returncode == 143 and files:  # after the commit, while the command ended
            assert "the outputs were complete before it (8 files" in err, err
            outcomes.add("finished")
        elif proc.returncode == 143:
            assert "no output was written" in err
            outcomes.add("interrupted")
        elif proc.returncode == 0:
            assert len(files) == 8
            outcomes.add("finished")
    assert "interrupted" in outcomes


def test_every_ik_flag_reaches_the_options(monkeypatch, tmp_path):
    """``--calibration-method`` was once parsed and then dropped on its way to IKOptions."""
    import pipeline.commands.ik as ik

    seen = {}

    def fake_run(settings, recorder=None):
        seen["settings"] = settings
        raise SystemExit(0)

    monkeypatch.setattr(ik, "run_settings", fake_run)
    with pytest.raises(SystemExit):
        main(["ik", "--orientations", str(tmp_path / "x.sto"), "--sex", "f", "--height-m", "1.6",
              "--out", str(tmp_path / "o"), "--calibration-method", "gn", "--drift", "none",
              "--filter", "pi", "--correction", "none", "--no-rerun"])
    o = seen["settings"].options
    assert (o.calibration_method, o.drift, o.filter, o.correction) == ("gn", "none", "pi", "none")
    assert seen["settings"].outputs.rerun is False


def test_view_refuses_what_is_not_a_whole_recording(tmp_path, capsys):
    (tmp_path / "notes.rrd").write_text("hello")
    assert main(["view", str(tmp_path / "notes.rrd")]) == 2
    assert "notes.rrd: not a rerun recording" in capsys.readouterr().err


@pytest.mark.parametrize("argv, message", [
    (["view", "x.rrd", "--port", "99999"], "--port: expected 1-65535, got 99999"),
    (["simulate", "--out", "o", "--seed", "-1"], "--seed: expected 0 or more, got -1"),
    (["calibrate", "hinge", "--imu1", "a", "--imu2", "b", "--population", "0"],
     "--population: expected 2 or more, got 0"),
    (["calibrate", "hinge", "--imu1", "a", "--imu2", "b", "--iterations", "-1"],
     "--iterations: expected 1 or more, got -1"),
    (["batch", "m.csv", "--out", "o", "--workers", "x"], "--workers: expected an integer"),
])
def test_counts_and_ports_out_of_range_are_one_line_errors(argv, message, capsys):
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2 and message in capsys.readouterr().err


def test_simulate_then_ik_the_helps_own_chain(tmp_path, capsys):
    """`pipeline simulate` (gait: a standing start by default) then `pipeline ik` on its output
    with no other flag: the knee of the simulation, no hint about the knee model."""
    assert main(["simulate", "--out", str(tmp_path / "sim"), "--duration-s", "8"]) == 0
    assert main(["ik", "--orientations", str(tmp_path / "sim" / "imu"), "--sex", "m",
                 "--height-m", "1.75", "--no-rerun", "--out", str(tmp_path / "ik")]) == 0
    from pipeline.io.mot import read_mot

    knee = read_mot(tmp_path / "ik" / "sim_ik.mot").columns["knee_angle_r"]
    assert np.nanmax(knee) - np.nanmin(knee) > np.radians(40)  # gait's knee swings ~60 deg
    assert "try --knee" not in capsys.readouterr().err


def test_demo_standing_time_is_used_and_checked(capsys):
    from pipeline.commands.demo import demo
    from pipeline.errors import InputError

    with pytest.raises(InputError, match="field standing_s: expected 0.5-10 s"):
        demo("unused", standing_s=0.0)


@pytest.fixture
def full_disk(tmp_path):
    """A 64 KiB tmpfs (where this machine lets the tests mount one): every output overflows."""
    import subprocess

    mnt = tmp_path / "full"
    mnt.mkdir()
    done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", str(mnt)],
                          capture_output=True)
    if done.returncode != 0:
        pytest.skip("cannot mount a tmpfs here")
    yield mnt
    subprocess.run(["umount", str(mnt)], check=False)


def test_a_full_disk_is_one_line_and_exit_2_never_a_hang(full_disk):
    """`pipeline ik` as a program (its recording written by a forked child) into a full disk,
    repeated: exit 2 within seconds, one line, nothing left."""
    import subprocess
    import sys
    import time

    for _ in range(3):
        t0 = time.monotonic()
        done = subprocess.run([sys.executable, "-m", "pipeline", "ik", "--orientations",
                               "example:ximu3_lower_body", "--sex", "m", "--height-m", "1.8",
                               "--out", str(full_disk / "out")], capture_output=True, text=True,
                              timeout=60)
        assert done.returncode == 2, done.stderr
        assert done.stderr.strip().splitlines()[-1] == (
            "error: cannot write the outputs: No space left on device")
        assert time.monotonic() - t0 < 30 and list(full_disk.iterdir()) == []


def test_debug_after_the_command_shows_the_traceback(tmp_path):
    """``--debug`` works after the command as before it (refused there before)."""
    args = ["scale", "--sex", "m", "--height-m", "1.75", "--knee-axis-femur", "0", "0", "0",
            "--out", str(tmp_path / "m.urdf")]
    assert main(args) == 2
    for where in (["--debug", *args], [*args, "--debug"]):
        with pytest.raises(Exception, match="knee"):
            main(where)


@pytest.mark.skipif(not Path("/dev/full").exists(), reason="needs /dev/full")
def test_a_report_that_cannot_be_printed_after_the_outputs_is_not_an_error(tmp_path):
    """``> /dev/full`` and ``| head -0`` after the model is written: exit 0 (an error before,
    'cannot write the outputs', with every output written); the full device said on stderr,
    the closed pipe not."""
    import subprocess
    import sys

    args = [sys.executable, "-m", "pipeline", "scale", "--sex", "m", "--height-m", "1.7"]
    with open("/dev/full", "w") as full:
        r = subprocess.run([*args, "--out", str(tmp_path / "a.urdf")], stdout=full,
                           stderr=subprocess.PIPE, text=True)
    assert r.returncode == 0 and (tmp_path / "a.urdf").exists()
    assert r.stderr.strip() == ("warning: could not print to standard output (No space left on "
                                "device); the outputs are written")
    p = subprocess.Popen([*args, "--out", str(tmp_path / "b.urdf")], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True)
    p.stdout.close()  # the reader gone before the report
    assert p.wait() == 0 and p.stderr.read() == "" and (tmp_path / "b.urdf").exists()
