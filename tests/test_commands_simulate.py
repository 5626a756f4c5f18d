"""pipeline.commands.simulate: the files ``pipeline simulate`` writes and their truth."""

from __future__ import annotations

import json

import numpy as np
import pytest
from _helpers import knee_truth

from pipeline.commands import simulate
from pipeline.io.imu_csv import read_imu_csv
from pipeline.model import Skeleton
from pipeline.rotations import angle_between

HEADER = "time,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z,mag_x,mag_y,mag_z,quat_w,quat_x,quat_y,quat_z"


def test_simulate_writes_every_file(sim):
    assert {p.name for p in sim.iterdir()} == {"imu", "truth"}
    imus = ["pelvis_imu"] + [f"{s}_{g}_imu" for s in ("right", "left") for g in ("femur", "tibia")]
    imus += ["right_foot_imu", "left_foot_imu"]
    assert {p.name for p in (sim / "imu").iterdir()} == {f"{n}.csv" for n in imus}
    assert {p.name for p in (sim / "truth").iterdir()} == {"truth.json", "model.urdf",
                                                          "landmarks.csv", "configuration.csv"}
    assert (sim / "imu" / "right_femur_imu.csv").read_text().splitlines()[0] == HEADER
    rec = read_imu_csv(sim / "imu" / "right_femur_imu.csv")
    assert rec.time.size == 1500 and abs(rec.rate_hz - 100.0) < 1e-6
    truth = json.loads((sim / "truth" / "truth.json").read_text())
    assert truth["motion"] == "gait" and truth["seed"] == 0
    assert set(truth["sensors"]) == set(imus)
    assert truth["sensors"]["right_tibia_imu"]["misalignment_deg"] > 5.0
    lm = (sim / "truth" / "landmarks.csv").read_text().splitlines()
    assert lm[0].startswith("time,right_HJC_x,right_HJC_y,right_HJC_z") and len(lm) == 1501
    Skeleton.from_urdf(sim / "truth" / "model.urdf", root="freeflyer")  # the URDF used loads


def test_truth_json_matches_the_files(sim):
    """The truth is consistent with the written signals: the axis the two sensors' orientations
    map to the world is one physical axis at every sample."""
    truth, j1, j2, _, _ = knee_truth(sim)
    from pipeline.rotations import matrix_from_quat

    q1 = read_imu_csv(sim / "imu" / "right_femur_imu.csv").quat
    q2 = read_imu_csv(sim / "imu" / "right_tibia_imu.csv").quat
    w1, w2 = matrix_from_quat(q1) @ j1, matrix_from_quat(q2) @ j2
    assert np.degrees(angle_between(w1, w2)).max() < 1e-6


def test_simulation_outputs_are_all_or_nothing(tmp_path, monkeypatch):
    def boom(*args, **kwargs):
        raise RuntimeError("disk full")

    monkeypatch.setattr(simulate, "write_array_csv", boom)
    out = tmp_path / "sim"
    with pytest.raises(RuntimeError, match="disk full"):
        simulate.run_simulation(out, "gait", 1.0, 0)
    assert not out.exists() or not any(out.iterdir())
