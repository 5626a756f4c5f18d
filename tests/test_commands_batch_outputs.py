"""pipeline.commands.batch_outputs: the batch's summary and group report, read from each trial's
_figures.json; a trial without one is listed, never a crash."""

import csv
import json

import pytest

from pipeline.commands.batch_outputs import SUMMARY_COLUMNS, trial_figures, write_summary


def test_a_trials_figures_or_empty_cells(tmp_path):
    path = tmp_path / "walk_figures.json"
    path.write_text(json.dumps({"frames": 900, "residual_median_deg": 1.234, "flags": ["x"],
                                "strides": 8, "stride_time_s": 1.1, "stance_share": None}))
    fig = trial_figures(path)
    assert fig["frames"] == "900" and fig["residual_median_deg"] == "1.23"
    assert fig["flags"] == "1" and fig["stride_time_s"] == "1.1" and fig["stance_share"] == ""
    (tmp_path / "bad_figures.json").write_text("{not json")
    assert set(trial_figures(tmp_path / "bad_figures.json").values()) == {""}
    assert set(trial_figures(tmp_path / "missing_figures.json").values()) == {""}


def test_the_summary_and_the_group_report(tmp_path):
    pytest.importorskip("matplotlib")
    trial = tmp_path / "s1" / "walk"
    trial.mkdir(parents=True)
    curve = {"n": 2, "mean_deg": [5.0] * 101, "sd_deg": [1.0] * 101}
    (trial / "walk_figures.json").write_text(json.dumps(
        {"strides": 6, "flags": [], "cycles": {"right": {"knee_angle": curve}}}))
    rows = [{c: "" for c in SUMMARY_COLUMNS} | {"row": 1, "subject": "s1", "status": "ok",
             "orientations": "walk.sto", "out_dir": str(trial)},
            {c: "" for c in SUMMARY_COLUMNS} | {"row": 2, "subject": "s2", "status": "failed",
             "orientations": "run.sto", "out_dir": str(tmp_path / "s2" / "run")}]
    write_summary(tmp_path, rows, report=True)
    listed = list(csv.DictReader((tmp_path / "batch_summary.csv").open()))
    assert [r["status"] for r in listed] == ["ok", "failed"]
    page = (tmp_path / "batch_report.html").read_text()
    assert "<td>s1</td><td>walk</td><td>6</td>" in page
    assert "<td>s2</td><td>run</td>" in page and "no figures (failed or not run)" in page
    write_summary(tmp_path / "again", rows, report=False)
    assert not (tmp_path / "again" / "batch_report.html").exists()
