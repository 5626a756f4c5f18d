"""Every example that ``pipeline --help`` and each command's ``--help`` show runs as written from
any folder (here an empty temporary one: the tests never write into the repository), without
``../shared``: each reads the shipped ``example:`` recordings, but ``reproduce``, whose published
dataset we may not ship (its repository states no licence), run where ``../shared`` has it."""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest

from pipeline.cli import EXAMPLES, build_parser, main

ROOT = Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"
# in the order a new user would run them: calibrate reads what simulate wrote
ORDER = ("scale", "simulate", "orientations", "calibrate", "ik", "batch", "demo", "reproduce",
         "live")
NEEDS_DATA = {"reproduce": SHARED / "wang2023"}


def test_every_command_has_an_example_in_its_help():
    parser = build_parser()
    text = parser.format_help()
    for name, example in EXAMPLES.items():
        assert example in text, name
    assert set(ORDER) | {"view"} == set(EXAMPLES)


@pytest.mark.slow
def test_examples_run_as_written(monkeypatch, capsys, tmp_path):
    root = tmp_path / "anywhere"
    root.mkdir()
    if SHARED.parent.is_dir():
        (tmp_path / "shared").symlink_to(SHARED.parent)
    monkeypatch.chdir(root)
    for name in ORDER:
        if name in NEEDS_DATA and not NEEDS_DATA[name].is_dir():
            continue
        argv = shlex.split(EXAMPLES[name])
        assert argv[0] == "pipeline"
        assert main(argv[1:]) == 0, name
    out = capsys.readouterr().out
    assert '"axis_1"' in out  # the calibrate example printed its JSON
    assert (root / "out" / "subject.urdf").is_file()
    assert (root / "out" / "demo" / "demo.rrd").is_file()
    assert (root / "out" / "batch" / "batch_report.html").is_file()
    # `pipeline view out/demo/demo.rrd --web` serves until stopped: its file exists (above) and the
    # command line it runs is checked in test_viz_viewer.py


def test_version(capsys):
    from pipeline import __version__

    with pytest.raises(SystemExit) as done:
        main(["--version"])
    assert done.value.code == 0 and capsys.readouterr().out.strip() == f"pipeline {__version__}"
