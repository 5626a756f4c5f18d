"""CLI library side: `pipeline simulate` -> `pipeline calibrate` recovers the truth; bad inputs;
all-or-nothing outputs; calibration -> IMU frames of the model."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pipeline.calibration.ipopt import calibrate_ipopt
from pipeline.calibration.joint_constraints import joint_data, project_hinge_positions
from pipeline.cli import main
from pipeline.commands import workflows
from pipeline.commands.workflows import CALIBRATION_KEYS, imu_placements_from_calibration
from pipeline.io.imu_csv import ImuRecording, read_imu_csv, write_imu_csv
from pipeline.model import Skeleton, SubjectGeometry, build_urdf
from pipeline.rotations import angle_between, exp3, log3, rotation_aligning_with_twist
from pipeline.simulate.model import simulate_trial

HEADER = "time,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,quat_w,quat_x,quat_y,quat_z"


@pytest.fixture(scope="module")
def sim(tmp_path_factory):
    out = tmp_path_factory.mktemp("sim") / "gait"
    assert main(["simulate", "--out", str(out)]) == 0
    return out


def _calibrate(capsys, sim, method, joint="hinge", as_json=True):
    argv = ["calibrate", joint, "--imu1", str(sim / "right_femur_imu.csv")]
    argv += ["--imu2", str(sim / "right_tibia_imu.csv"), "--method", method]
    capsys.readouterr()
    assert main(argv + (["--json"] if as_json else [])) == 0
    out = capsys.readouterr().out
    return json.loads(out) if as_json else out


def _knee_truth(sim):
    truth = json.loads((sim / "truth.json").read_text())
    k = truth["joints"]["right_knee"]
    j1, j2 = np.array(k["axis_1"]), np.array(k["axis_2"])
    o1, o2 = project_hinge_positions(
        np.array(k["position_1_m"]), np.array(k["position_2_m"]), j1, j2
    )
    return truth, j1, j2, o1, o2


def _errors(res, j1, j2, o1, o2):
    a1, a2 = np.array(res["axis_1"]), np.array(res["axis_2"])
    s = 1.0 if a1 @ j1 > 0 else -1.0  # the CLI knows no "right": both signs flip together
    e_axis = [np.degrees(angle_between(s * a1, j1)), np.degrees(angle_between(s * a2, j2))]
    e_pos = [
        np.linalg.norm(np.array(res["position_1_m"]) - o1),
        np.linalg.norm(np.array(res["position_2_m"]) - o2),
    ]
    return max(e_axis), max(e_pos)


def test_simulate_writes_every_file(sim):
    names = {p.name for p in sim.iterdir()}
    imus = ["pelvis_imu"] + [f"{s}_{g}_imu" for s in ("right", "left") for g in ("femur", "tibia")]
    imus += ["right_foot_imu", "left_foot_imu"]
    expected = {f"{n}.csv" for n in imus}
    expected |= {"truth.json", "model.urdf", "landmarks.csv", "configuration.csv"}
    assert names == expected
    assert (sim / "right_femur_imu.csv").read_text().splitlines()[0] == HEADER
    rec = read_imu_csv(sim / "right_femur_imu.csv")
    assert rec.time.size == 1500 and abs(rec.rate_hz - 100.0) < 1e-6
    truth = json.loads((sim / "truth.json").read_text())
    assert truth["motion"] == "gait" and truth["seed"] == 0
    assert set(truth["sensors"]) == set(imus)
    assert truth["sensors"]["right_tibia_imu"]["misalignment_deg"] > 5.0
    lm = (sim / "landmarks.csv").read_text().splitlines()
    assert lm[0].startswith("time,right_HJC_x,right_HJC_y,right_HJC_z") and len(lm) == 1501
    Skeleton.from_urdf(sim / "model.urdf", root="freeflyer")  # the URDF used loads


def test_truth_json_matches_the_files(sim):
    """The truth is consistent with the written signals: the axis the two sensors' orientations
    map to the world is one physical axis at every sample."""
    truth, j1, j2, _, _ = _knee_truth(sim)
    from pipeline.rotations import matrix_from_quat

    q1 = read_imu_csv(sim / "right_femur_imu.csv").quat
    q2 = read_imu_csv(sim / "right_tibia_imu.csv").quat
    w1, w2 = matrix_from_quat(q1) @ j1, matrix_from_quat(q2) @ j2
    assert np.degrees(angle_between(w1, w2)).max() < 1e-6


def test_cli_ipopt_recovers_the_simulated_knee(capsys, sim):
    res = _calibrate(capsys, sim, "ipopt")
    assert tuple(res) == CALIBRATION_KEYS
    _, j1, j2, o1, o2 = _knee_truth(sim)
    e_axis, e_pos = _errors(res, j1, j2, o1, o2)
    assert e_axis < 0.5  # deg
    assert e_pos < 0.003  # m, after eq 16 projection
    assert res["method"] == "ipopt" and res["observability"]["determined"] is True
    assert np.isclose(np.linalg.norm(res["axis_1"]), 1.0)


@pytest.mark.parametrize("method", ["gn", "dwpso", "gwo"])
def test_cli_each_method_runs(capsys, sim, method):
    res = _calibrate(capsys, sim, method)
    assert tuple(res) == CALIBRATION_KEYS and res["method"] == method
    _, j1, j2, o1, o2 = _knee_truth(sim)
    e_axis, e_pos = _errors(res, j1, j2, o1, o2)
    # GWO with the CLI's small swarm is the least accurate (tests/test_solvers.py: <= 2 deg)
    assert e_axis < (2.0 if method == "gwo" else 1.0)
    if method == "gn":
        assert e_pos < 0.003


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
    f1, f2 = sim / "right_femur_imu.csv", sim / "right_tibia_imu.csv"
    missing = tmp_path / "nope.csv"
    _fails(capsys, ["calibrate", "hinge", "--imu1", str(missing), "--imu2", str(f2)], "nope.csv")
    rec = read_imu_csv(f2)
    short = write_imu_csv(
        tmp_path / "short.csv",
        ImuRecording(rec.time[:1000], rec.gyr[:1000], rec.acc[:1000], rec.quat[:1000]),
    )
    argv = ["calibrate", "hinge", "--imu1", str(f1), "--imu2", str(short)]
    _fails(capsys, argv, "short.csv", "right_femur_imu.csv", "1500", "1000")
    slow = write_imu_csv(
        tmp_path / "slow.csv", ImuRecording(2 * rec.time, rec.gyr, rec.acc, rec.quat)
    )
    _fails(capsys, ["calibrate", "hinge", "--imu1", str(f1), "--imu2", str(slow)], "rate")
    late = write_imu_csv(
        tmp_path / "late.csv", ImuRecording(rec.time + 1.0, rec.gyr, rec.acc, rec.quat)
    )
    _fails(capsys, ["calibrate", "hinge", "--imu1", str(f1), "--imu2", str(late)], "time")
    _fails(capsys, ["simulate", "--out", str(f1)], "directory")
    _fails(capsys, ["simulate", "--out", str(tmp_path / "x"), "--duration-s", "-1"], "duration")


def test_simulation_outputs_are_all_or_nothing(tmp_path, monkeypatch):
    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(workflows, "_write_table", boom)
    out = tmp_path / "sim"
    with pytest.raises(RuntimeError, match="disk full"):
        workflows.run_simulation(out, "gait", 1.0, 0)
    assert not out.exists() or not any(out.iterdir())


# --------------------------------------------------------------------- calibration -> IMU frames


def test_rotation_aligning_with_twist_by_hand():
    x, y, z = np.eye(3)
    R = rotation_aligning_with_twist(x, y, z, x)  # x -> y exactly, then z -> x: a cyclic shift
    np.testing.assert_allclose(R, [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-12)
    rng = np.random.default_rng(0)
    R_true = exp3(rng.normal(size=3))
    a, c = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_allclose(rotation_aligning_with_twist(a, R_true @ a, c, R_true @ c), R_true)
    ref = exp3(np.array([0.1, -0.2, 0.05])) @ R_true  # nearest rotation with R a = R_true a
    R = rotation_aligning_with_twist(a, R_true @ a, np.eye(3), ref.T)
    np.testing.assert_allclose(R @ a, R_true @ a, atol=1e-12)
    for phi in (-0.01, 0.01):  # a local optimum of |R - ref| among rotations about the axis
        Rp = exp3(phi * (R_true @ a) / np.linalg.norm(a)) @ R
        assert np.linalg.norm(Rp - ref) > np.linalg.norm(R - ref)


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    geometry = SubjectGeometry.default(1.75, "m", "right")
    folder = tmp_path_factory.mktemp("placement")
    sk = Skeleton.build(geometry, knee="hinge", root="freeflyer")
    gait = simulate_trial(sk, "gait", seed=11)
    static = simulate_trial(sk, "static", duration_s=2.0, seed=11)  # same seed: same placements
    a, b = gait.imus["right_femur_imu"].recording, gait.imus["right_tibia_imu"].recording
    res = calibrate_ipopt(
        joint_data(gait.time, a.gyr, a.acc, b.gyr, b.acc), "hinge", quat_1=a.quat, quat_2=b.quat
    )
    acc = tuple(
        static.imus[f"right_{s}_imu"].recording.acc.mean(axis=0) for s in ("femur", "tibia")
    )
    return geometry, gait, res, acc, folder


def _placement_errors(est, gait, seg):
    s = gait.imus[f"right_{seg}_imu"]
    T = est.placements[f"right_{seg}_imu"]
    a_f, a_t = gait.skeleton.knee_axis("right")
    axis = a_f if seg == "femur" else a_t
    rot_err = log3(T[:3, :3] @ s.R_segment.T)  # segment frame
    dp = T[:3, 3] - s.p_segment
    return rot_err, dp, axis


def test_placements_from_calibration_with_a_static_pose(calibrated):
    geometry, gait, res, acc, folder = calibrated
    est = imu_placements_from_calibration(
        gait.skeleton, res.axis_1, res.axis_2, res.position_1_m, res.position_2_m, static_acc=acc
    )
    assert est.twist_from == "static pose"
    axial = []
    for seg in ("femur", "tibia"):
        rot_err, dp, axis = _placement_errors(est, gait, seg)
        default_err = np.linalg.norm(log3(gait.imus[f"right_{seg}_imu"].misalignment))
        assert np.degrees(np.linalg.norm(rot_err)) < 1.0 < np.degrees(default_err)
        assert np.linalg.norm(dp - (dp @ axis) * axis) < 0.004  # across the axis: observable
        axial.append(dp @ axis)
    # along the axis only one common shift is undetermined: the relative position is recovered
    assert abs(axial[0] - axial[1]) < 0.004
    # and the result is written into the model as IMU frames
    path = build_urdf(geometry, folder / "calibrated.urdf", imu_placements=est.placements)
    sk = Skeleton.from_urdf(path)
    for name, T in est.placements.items():
        seg = name.removesuffix("_imu")
        np.testing.assert_allclose(sk.relative_pose(name, seg, sk.neutral()), T, atol=1e-9)


def test_placements_without_static_pose_recover_the_observable_part(calibrated):
    _, gait, res, _, _ = calibrated
    est = imu_placements_from_calibration(
        gait.skeleton, -res.axis_1, -res.axis_2, res.position_1_m, res.position_2_m
    )  # flipped signs are fixed from the model's IMU frames
    assert est.twist_from == "default" and any("undetermined" in n for n in est.notes)
    for seg in ("femur", "tibia"):
        rot_err, _, axis = _placement_errors(est, gait, seg)
        tilt = np.linalg.norm(rot_err - (rot_err @ axis) * axis)  # the part off the knee axis
        assert np.degrees(tilt) < 0.6
        mis = log3(gait.imus[f"right_{seg}_imu"].misalignment)
        assert np.degrees(np.linalg.norm(mis - (mis @ axis) * axis)) > 2.0  # it was misaligned
