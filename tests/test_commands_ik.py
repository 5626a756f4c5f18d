"""pipeline.commands.ik: the configuration file, its flags layer, and the reproducible run."""

from pathlib import Path

import pytest
import tomllib

from pipeline.cli import main
from pipeline.process.options import resolve_settings

OPENSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opensim"
WALK = OPENSIM / "xsens_walking_orientations.sto"


@pytest.mark.dataset
def test_the_written_configuration_reproduces_the_mot_byte_for_byte(tmp_path):
    if not WALK.exists():
        pytest.skip("../shared/data/opensim not present")
    first = tmp_path / "first"
    assert main(["ik", "--orientations", str(WALK), "--sex", "f", "--height-m", "1.68",
                 "--knee-width-m", "0.1", "--sensor-to-model", "-1.5708", "0", "0",
                 "--correction", "aor", "--knee", "hinge", "--no-rerun",
                 "--out", str(first)]) == 0
    config = first / "xsens_walking_orientations_config.toml"
    doc = tomllib.loads(config.read_text())
    assert doc["subject"] == {"sex": "f", "height_m": 1.68, "knee_width_m": 0.1}
    assert doc["ik"]["orientations"] == str(WALK.resolve())
    assert doc["ik"]["knee"] == "hinge" and doc["ik"]["correction"] == "aor"
    assert doc["ik"]["calibration_pose"] == "standing" and doc["ik"]["rerun"] is False
    second = tmp_path / "second"
    assert main(["ik", "--config", str(config), "--out", str(second)]) == 0
    name = "xsens_walking_orientations_ik.mot"
    assert (second / name).read_bytes() == (first / name).read_bytes()
    assert (second / config.name).read_text() == config.read_text()
    # a flag overrides the file
    third = tmp_path / "third"
    assert main(["ik", "--config", str(config), "--knee", "free", "--out", str(third)]) == 0
    assert tomllib.loads((third / config.name).read_text())["ik"]["knee"] == "free"
    assert (third / name).read_bytes() != (first / name).read_bytes()


def test_flags_override_the_file_and_required_values_are_named(tmp_path):
    cfg = tmp_path / "s.toml"
    cfg.write_text('[subject]\nsex = "m"\nheight_m = 1.8\n[ik]\norientations = "w.sto"\n'
                   'knee = "hinge"\nout = "res"\n[sensors]\npelvis_imu = "P"\n')
    s = resolve_settings(cfg, {"knee": "free", "height_m": 1.7, "sensor_map": {"femur_r_imu": "T"}})
    assert Path(s.inputs.orientations) == tmp_path / "w.sto"
    assert Path(s.outputs.out) == tmp_path / "res"
    assert s.subject.height_m == 1.7 and s.options.knee == "free"
    assert s.inputs.sensor_map == {"pelvis_imu": "P", "femur_r_imu": "T"}
    cfg.write_text('[ik]\norientations = "w.sto"\nout = "o"\n')
    with pytest.raises(Exception, match="--sex is required"):
        resolve_settings(cfg, {})
    with pytest.raises(Exception, match="--orientations is required"):
        resolve_settings(None, {"sex": "m", "height_m": 1.8, "out": "o"})


def test_bad_configuration_exits_2_naming_the_file_and_key(tmp_path, capsys):
    cfg = tmp_path / "s.toml"
    cfg.write_text('[subject]\nsex = "m"\nheight_m = 1.8\n[ik]\norientations = "w.sto"\n'
                   'correction = "wang"\n')
    assert main(["ik", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert str(cfg) in err and "field correction" in err and "'aor'" in err
    cfg.write_text('[subject]\nsex = "m"\nheight_m = 1.8\n[ik]\norientations = "w.sto"\n'
                   'heading_axis = "x"\n')
    assert main(["ik", "--config", str(cfg), "--out", str(tmp_path / "o")]) == 2
    assert "field ik.heading_axis: unknown key" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


@pytest.mark.dataset
def test_an_unmatched_sensor_name_is_refused_before_anything_is_written(tmp_path, capsys):
    if not WALK.exists():
        pytest.skip("../shared/data/opensim not present")
    out = tmp_path / "o"
    code = main(["ik", "--orientations", str(WALK), "--sex", "m", "--height-m", "1.8",
                 "--sensor-map", "pelvis_imu=hip_sensor", "--out", str(out)])
    assert code == 2
    err = capsys.readouterr().err
    assert "field sensors.pelvis_imu" in err and "hip_sensor" in err and WALK.name in err
    assert not any(out.glob("*")) if out.exists() else True


def _chunk_columns(path: Path) -> dict[str, list]:
    """Per entity, each chunk's columns (the row ids, new on every run, left out)."""
    from rerun.chunk import RrdReader

    out: dict[str, list] = {}
    for c in RrdReader(path).stream().to_chunks():
        if c.entity_path.startswith("/__"):
            continue
        rb = c.to_record_batch()
        out.setdefault(c.entity_path, []).append(
            {n: rb.column(n) for n in rb.schema.names if "RowId" not in n})
    return out


CHILD_RUN = """
import os, sys
import pipeline.commands.ik as ik
from pipeline.model.measures import Measures
from pipeline.viz.background import BackgroundRecording
pids = []
start = BackgroundRecording.start
def spy(**kw):
    worker = start(**kw)
    pids.append(worker.pid)
    return worker
BackgroundRecording.start = staticmethod(spy)
ik.run_ik(sys.argv[1], Measures("m", 1.8), sys.argv[2])
try:
    os.waitpid(pids[0], os.WNOHANG)
    print(len(pids), "not reaped")
except ChildProcessError:
    print(len(pids), "reaped")
"""


@pytest.mark.dataset
def test_the_recording_written_by_the_child_is_the_one_written_in_process(tmp_path, monkeypatch):
    """A short recording is logged by a forked child (pipeline.viz.background) while the other
    files are written (in a new process: alone, as the program is); the .rrd holds exactly what
    logging in the process writes, and the child is reaped when run_ik returns."""
    import os
    import subprocess
    import sys

    import pipeline.commands.ik as ik
    from pipeline.model.measures import Measures

    sto = OPENSIM / "quaternions_4_ik.sto"
    if not sto.exists():
        pytest.skip("../shared/data/opensim not present")
    if not hasattr(os, "fork") or sys.platform == "darwin":
        pytest.skip("forks only where fork is safe")
    out = subprocess.run([sys.executable, "-c", CHILD_RUN, str(sto), str(tmp_path / "child")],
                         check=True, capture_output=True, text=True).stdout
    assert out.split() == ["1", "reaped"]
    monkeypatch.setattr(ik, "BACKGROUND_FRAMES", 0)
    ik.run_ik(sto, Measures("m", 1.8), tmp_path / "process")
    a = _chunk_columns(tmp_path / "child" / "quaternions_4_ik.rrd")
    b = _chunk_columns(tmp_path / "process" / "quaternions_4_ik.rrd")
    assert sorted(a) == sorted(b) and len(a) > 20
    for entity, chunks in a.items():
        assert len(chunks) == len(b[entity])
        for ca, cb in zip(chunks, b[entity], strict=True):
            assert ca.keys() == cb.keys()
            assert all(ca[n].equals(cb[n]) for n in ca), entity


def _broken_recording(*args) -> None:
    raise ValueError("the viewer's format changed")


def test_a_failing_recording_leaves_no_output(tmp_path, monkeypatch):
    """The child's error reaches the caller and no file (nor temporary) is left."""
    import pipeline.commands.ik as ik
    from pipeline.model.measures import Measures

    sto = OPENSIM / "quaternions_4_ik.sto"
    if not sto.exists():
        pytest.skip("../shared/data/opensim not present")

    monkeypatch.setattr(ik, "_record_and_report", _broken_recording)
    out = tmp_path / "out"
    with pytest.raises((RuntimeError, ValueError), match="format changed"):
        ik.run_ik(sto, Measures("m", 1.8), out)
    assert list(out.glob("*")) == []


@pytest.mark.dataset
def test_the_program_writes_its_recording_through_the_early_child(tmp_path, processes_with):
    """`pipeline ik` run as the program forks the recording's writer before its imports
    (pipeline.cli): the .rrd it leaves holds the model, landmarks and angles, and the command
    leaves no process behind."""
    import subprocess
    import sys

    from pipeline.viz.recording import read_entities

    sto = OPENSIM / "quaternions_4_ik.sto"
    if not sto.exists():
        pytest.skip("../shared/data/opensim not present")
    out = tmp_path / "out"
    subprocess.run([sys.executable, "-m", "pipeline", "ik", "--orientations", str(sto), "--sex",
                    "m", "--height-m", "1.8", "--out", str(out)], check=True,
                   capture_output=True)
    entities = read_entities(out / "quaternions_4_ik.rrd")
    assert {"/world/model/pelvis", "/world/model/right_tibia/mesh", "/world/landmarks/right_MM",
            "/plots/right_knee/flexion"} <= entities
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no temporary left
    assert processes_with(str(out)) == []


def test_a_second_run_into_the_same_folder_is_refused_or_replaces_the_first(tmp_path, capsys):
    """Refused naming the files; with --overwrite the first run's extra files (its .osim) go."""
    assert main(["simulate", "--out", str(tmp_path / "sim"), "--duration-s", "6",
                 "--standing-s", "2"]) == 0
    imu, out = tmp_path / "sim" / "imu", tmp_path / "out"
    args = ["ik", "--orientations", str(imu), "--sex", "m", "--height-m", "1.75", "--no-rerun",
            "--out", str(out)]
    assert main([*args, "--osim"]) == 0
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert "sim.osim" in before
    assert main(args) == 2
    err = capsys.readouterr().err
    assert "a previous run's outputs are there (" in err and "sim_ik.mot" in err
    assert "--overwrite" in err
    assert {p.name: p.stat().st_mtime_ns for p in out.iterdir()} == before  # untouched
    (out / "notes.txt").write_text("mine")
    assert main([*args, "--overwrite"]) == 0
    assert "sim.osim" not in {p.name for p in out.iterdir()}  # the first run's, not rewritten
    assert (out / "notes.txt").read_text() == "mine"  # not an output of this recording
    assert "overwrite" not in (out / "sim_config.toml").read_text()


@pytest.mark.dataset
def test_a_dropout_is_blank_named_and_the_rest_kept(tmp_path, capsys):
    """OpenSense's walk with 1 s of the right shank's cells empty (a radio dropout): the run
    completes, one warning names the sensor and the span, the right knee and ankle are blank
    over it in the .mot, every other joint is as in the faultless run."""
    import numpy as np

    from pipeline.io.mot import read_mot

    if not WALK.exists():
        pytest.skip("../shared/data/opensim not present")
    lines = WALK.read_text().splitlines()
    head = next(i for i, line in enumerate(lines) if line.startswith("time"))
    col = lines[head].split("\t").index("tibia_r_imu")
    for i in range(head + 1 + 1000, head + 1 + 1100):
        cells = lines[i].split("\t")
        cells[col] = ""
        lines[i] = "\t".join(cells)
    holed = tmp_path / "holed.sto"
    holed.write_text("\n".join(lines) + "\n")
    args = ["--sex", "f", "--height-m", "1.68", "--sensor-to-model", "-1.5708", "0", "0",
            "--no-rerun"]
    assert main(["ik", "--orientations", str(WALK), *args, "--out", str(tmp_path / "a")]) == 0
    capsys.readouterr()
    assert main(["ik", "--orientations", str(holed), *args, "--out", str(tmp_path / "b")]) == 0
    err = capsys.readouterr().err
    said = [line for line in err.splitlines() if "dropout" in line]
    assert len(said) == 1 and "tibia_r_imu" in said[0] and "10.00-10.99 s" in said[0], err
    a = read_mot(tmp_path / "a" / "xsens_walking_orientations_ik.mot").columns
    b = read_mot(tmp_path / "b" / "holed_ik.mot").columns
    gap = slice(1000, 1100)
    for name in ("knee_angle_r", "ankle_angle_r"):
        assert np.isnan(b[name][gap]).all()
        assert np.isfinite(np.delete(b[name], range(1000, 1100))).all()
    for name in ("knee_angle_l", "ankle_angle_l", "hip_flexion_r", "hip_flexion_l"):
        assert np.isfinite(b[name]).all()
        assert np.max(np.abs(np.asarray(b[name]) - np.asarray(a[name]))) < 0.5, name


def test_name_gives_the_outputs_name_and_a_path_is_refused():
    from pipeline.commands.ik import output_name
    from pipeline.errors import InputError

    assert output_name("subject01", "any/imu") == "subject01"
    assert output_name(None, "example:ximu3_lower_body") == "ximu3_lower_body"
    for bad in ("a/b", "..", ""):
        with pytest.raises(InputError, match="expected a name, not a path"):
            output_name(bad, "walk.sto")
