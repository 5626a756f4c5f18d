"""pipeline.commands.calibrate: ``pipeline calibrate`` on simulated sensors, every method."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _helpers import imu_recording, knee_truth

from pipeline.cli import main
from pipeline.commands.calibrate import CALIBRATION_KEYS
from pipeline.io.imu_csv import read_imu_csv, write_imu_csv
from pipeline.rotations import angle_between


def _calibrate(capsys, sim, method, joint="hinge", as_json=True):
    argv = ["calibrate", joint, "--imu1", str(sim / "imu" / "right_femur_imu.csv")]
    argv += ["--imu2", str(sim / "imu" / "right_tibia_imu.csv"), "--method", method]
    capsys.readouterr()
    assert main(argv + (["--json"] if as_json else [])) == 0
    out = capsys.readouterr().out
    return json.loads(out) if as_json else out


def _errors(res, j1, j2, o1, o2):
    a1, a2 = np.array(res["axis_1"]), np.array(res["axis_2"])
    s = 1.0 if a1 @ j1 > 0 else -1.0  # the CLI knows no "right": both signs flip together
    e_axis = [np.degrees(angle_between(s * a1, j1)), np.degrees(angle_between(s * a2, j2))]
    e_pos = [
        np.linalg.norm(np.array(res["position_1_m"]) - o1),
        np.linalg.norm(np.array(res["position_2_m"]) - o2),
    ]
    return max(e_axis), max(e_pos)


def test_cli_ipopt_recovers_the_simulated_knee(capsys, sim):
    res = _calibrate(capsys, sim, "ipopt")
    assert tuple(res) == CALIBRATION_KEYS
    _, j1, j2, o1, o2 = knee_truth(sim)
    e_axis, e_pos = _errors(res, j1, j2, o1, o2)
    assert e_axis < 0.5  # deg
    assert e_pos < 0.003  # m, after eq 16 projection
    assert res["method"] == "ipopt" and res["observability"]["determined"] is True
    assert np.isclose(np.linalg.norm(res["axis_1"]), 1.0)


@pytest.mark.parametrize("method", ["gn", "dwpso", "gwo"])
def test_cli_each_method_runs(capsys, sim, method):
    res = _calibrate(capsys, sim, method)
    assert tuple(res) == CALIBRATION_KEYS and res["method"] == method
    _, j1, j2, o1, o2 = knee_truth(sim)
    e_axis, e_pos = _errors(res, j1, j2, o1, o2)
    # GWO with the CLI's small swarm is the least accurate (tests/test_solvers.py: <= 2 deg)
    assert e_axis < (2.0 if method == "gwo" else 1.0)
    if method == "gn":
        assert e_pos < 0.003
    # 'determined' is earned: a result far from the truth must not claim it (the swarms at their
    # default sizes stop before converging, and two independent starts disagree)
    obs = res["observability"]
    if obs["determined"]:
        assert e_axis < 1.0 and e_pos < 0.005, (method, e_axis, e_pos)
    else:
        assert "independent starts" in obs["warning"] and "did not converge" in obs["warning"]
    if e_pos > 0.01:
        assert not obs["determined"]


def test_cli_spherical_and_text_output(capsys, sim):
    res = _calibrate(capsys, sim, "gn", joint="spherical")
    assert res["axis_1"] is None and res["axis_2"] is None and len(res["position_1_m"]) == 3
    text = _calibrate(capsys, sim, "ipopt", as_json=False)
    assert "axis_1" in text and "position_2_m" in text and "WARNING" not in text
    assert text.splitlines()[0].startswith("hinge calibration: ipopt")


def test_poor_excitation_is_reported_in_both_outputs(capsys, tmp_path):
    out = tmp_path / "still"
    argv = ["simulate", "--out", str(out), "--motion", "still_thigh", "--duration-s", "10"]
    assert main(argv) == 0
    res = _calibrate(capsys, out, "ipopt")
    obs = res["observability"]
    assert obs["determined"] is False and "axis_1 (sensor 1)" in obs["undetermined"]
    assert "UNDETERMINED" in obs["warning"]
    text = _calibrate(capsys, out, "ipopt", as_json=False)
    assert "WARNING: UNDETERMINED" in text and "axis_1 (sensor 1)" in text


def _fails(capsys, argv, *needles):
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    for n in needles:
        assert n in err, err
    return err


def test_bad_inputs_exit_2_with_one_line(capsys, sim, tmp_path):
    f1, f2 = sim / "imu" / "right_femur_imu.csv", sim / "imu" / "right_tibia_imu.csv"
    missing = tmp_path / "nope.csv"
    _fails(capsys, ["calibrate", "hinge", "--imu1", str(missing), "--imu2", str(f2)], "nope.csv")
    rec = read_imu_csv(f2)
    short = write_imu_csv(
        tmp_path / "short.csv",
        imu_recording(rec.time[:1000], rec.gyr[:1000], rec.acc[:1000], rec.quat[:1000]),
    )
    argv = ["calibrate", "hinge", "--imu1", str(f1), "--imu2", str(short)]
    _fails(capsys, argv, "short.csv", "right_femur_imu.csv", "1500", "1000")
    slow = write_imu_csv(
        tmp_path / "slow.csv", imu_recording(2 * rec.time, rec.gyr, rec.acc, rec.quat)
    )
    _fails(capsys, ["calibrate", "hinge", "--imu1", str(f1), "--imu2", str(slow)], "rate")
    late = write_imu_csv(
        tmp_path / "late.csv", imu_recording(rec.time + 1.0, rec.gyr, rec.acc, rec.quat)
    )
    _fails(capsys, ["calibrate", "hinge", "--imu1", str(f1), "--imu2", str(late)], "time")
    _fails(capsys, ["simulate", "--out", str(f1)], "directory")
    _fails(capsys, ["simulate", "--out", str(tmp_path / "x"), "--duration-s", "-1"], "duration")


def test_degenerate_inputs_are_refused_not_returned(capsys, sim, tmp_path):
    from pipeline.commands.simulate import run_simulation

    thigh = sim / "imu" / "right_femur_imu.csv"
    # the same file twice, and the same signals under two names
    assert main(["calibrate", "hinge", "--imu1", str(thigh), "--imu2", str(thigh)]) == 2
    assert "same file" in capsys.readouterr().err
    copy = tmp_path / "copy.csv"
    copy.write_text(thigh.read_text())
    assert main(["calibrate", "hinge", "--imu1", str(thigh), "--imu2", str(copy)]) == 2
    assert "identical" in capsys.readouterr().err
    # a trial with no motion (the simulator's standing pose)
    still = tmp_path / "still"
    run_simulation(still, "static", 2.0, 0)
    argv = ["calibrate", "hinge", "--imu1", str(still / "imu" / "right_femur_imu.csv"),
            "--imu2", str(still / "imu" / "right_tibia_imu.csv")]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert "barely move" in err and "Traceback" not in err
