"""`pipeline demo`: the whole product on a simulated subject, checked against the truth."""

import pytest

from pipeline.cli import main
from pipeline.commands.demo import demo


@pytest.fixture(scope="module")
def result(tmp_path_factory):
    return demo(tmp_path_factory.mktemp("demo"), seed=0)


def test_writes_every_output(result):
    for path in result.files:
        assert path.exists() and path.stat().st_size > 0, path


def test_calibration_recovers_the_knee_axis(result):
    assert max(result.axis_error_deg) < 0.5


def test_ik_recovers_the_simulated_kinematics(result):
    for key in ("right_hip_flexion", "right_hip_adduction", "right_knee_flexion",
                "left_hip_flexion", "left_knee_flexion"):  # fmt: skip
        assert result.angle_rms_deg[key] < 1.0, key
    # the remaining knee rotation/adduction error is the simulated hinge's neutral offset
    _, adduction, rotation = result.knee_neutral_offset_deg
    assert abs(result.angle_rms_deg["right_knee_rotation"] - abs(rotation)) < 1.0
    assert abs(result.angle_rms_deg["right_knee_adduction"] - abs(adduction)) < 1.0
    for name in ("right_EFM", "right_EFL", "right_KJC"):
        assert result.landmark_rms_m[name] < 0.005, name
    assert result.landmark_rms_m["right_MM"] < 0.03


def test_recording_shows_the_moving_model(result):
    from pipeline.viz.recording import entity_row_counts

    counts = entity_row_counts(next(p for p in result.files if p.suffix == ".rrd"))
    names = {e.lstrip("/") for e in counts}
    assert "world/model/right_tibia" in names and "world/model/right_tibia/mesh" in names
    assert any(n.startswith("plots/right_knee") for n in names)
    assert counts["/world/model/right_tibia"] == 1700


def test_cli_demo_runs(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path / "d")]) == 0
    assert "pipeline view" in capsys.readouterr().out
