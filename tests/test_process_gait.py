"""pipeline.process.gait: which sensor gives each leg's strides, and what is said when none does
(the simulated foot walk placed on both feet and shanks; the S02 walk through pipeline ik)."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.gait import BLEND_S, gait_of, with_pelvis_path
from pipeline.simulate.foot_walk import foot_walk

S02 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "gaittoolbox_s02"


def _rec(names):
    w = foot_walk(strides=5, seed=0)
    return Recording(w.time, w.rate_hz, {n: SensorSignals(gyr=w.gyr, acc=w.acc) for n in names})


def test_feet_give_strides_with_lengths():
    notes = []
    gait = gait_of(_rec(["calcn_r_imu", "calcn_l_imu"]), notes)
    assert gait.sources == {"right": "foot sensor calcn_r_imu", "left": "foot sensor calcn_l_imu"}
    assert len(gait.strides) == 8 and notes == []
    assert [s.start_s for s in gait.strides] == sorted(s.start_s for s in gait.strides)
    assert all(abs(s.stride_length_m - 1.3) < 0.02 for s in gait.strides)


def test_without_a_foot_sensor_the_shank_gives_times_only():
    """The foot walk's signal on a shank: times without a path, and the note says so."""
    notes = []
    gait = gait_of(_rec(["tibia_r_imu"]), notes)
    assert gait.sources == {"right": "shank sensor tibia_r_imu"} and "right" not in gait.paths
    assert any("right strides from the shank sensor tibia_r_imu" in n for n in notes)
    assert all(np.isnan(s.stride_length_m) for s in gait.strides)


def test_no_walking_and_no_raw_signals_are_said():
    rng = np.random.default_rng(0)
    still = SensorSignals(gyr=rng.normal(0, 0.01, (800, 3)),
                          acc=[0, 0, 9.81] + rng.normal(0, 0.05, (800, 3)))
    notes = []
    assert gait_of(Recording(np.arange(800) / 100.0, 100.0, {"calcn_r_imu": still}),
                   notes).strides == []
    assert notes == ["no strides: no walking found (no swing of a foot or shank)"]
    notes = []
    quats = SensorSignals(quat=np.tile([1.0, 0, 0, 0], (800, 1)))
    gait_of(Recording(np.arange(800) / 100.0, 100.0, {"calcn_r_imu": quats}), notes)
    assert notes == ["no strides: no foot or shank sensor with raw signals"]


@pytest.mark.dataset
def test_pipeline_ik_writes_the_s02_strides(tmp_path):
    if not S02.exists():
        pytest.skip("../shared/data/gaittoolbox_s02 not present")
    import csv
    import json
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_gait import S02_MAP

    from pipeline.cli import main

    pairs = [f"{k}={v}" for k, v in S02_MAP.items()]
    assert main(["ik", "--orientations", str(S02 / "imu"), "--sensor-map", *pairs, "--sex", "m",
                 "--height-m", "1.72", "--no-rerun", "--out", str(tmp_path)]) == 0
    rows = list(csv.DictReader((tmp_path / "gaittoolbox_s02_strides.csv").open()))
    straight = [float(r["stride_length_m"]) for r in rows if r["straight"] == "true"]
    assert len(rows) >= 8 and 1.3 < np.median(straight) < 1.6  # Vicon: 1.17-1.56 m
    fig = json.loads((tmp_path / "gaittoolbox_s02_figures.json").read_text())
    assert fig["strides"] == len(rows) and 1.2 < fig["stride_time_s"] < 1.6
    assert "Strides (`<name>_strides.csv`" in (tmp_path / "gaittoolbox_s02_summary.md").read_text()


def test_the_stance_weight_and_a_path_needs_both_feet():
    from pipeline.process.gait import _stance_weight

    w = foot_walk(strides=3, seed=0)
    rec = Recording(w.time, w.rate_hz, {"calcn_r_imu": SensorSignals(gyr=w.gyr, acc=w.acc)})
    notes = []
    gait = gait_of(rec, notes)
    weight = _stance_weight(gait.events["right"], len(w.time), w.rate_hz)
    assert weight[: int(w.fc[0] * 100) - 10].min() > 1 - 1e-9  # standing until the first toe-off
    swing = (w.time > w.fc[1] + BLEND_S) & (w.time < w.ic[2] - BLEND_S)
    assert weight[swing].max() < 1e-9
    assert with_pelvis_path(gait, rec, None, None, notes).pelvis_path is None
    assert notes[-1] == "the pelvis's path needs a foot sensor on each foot: not written"


def test_a_foot_outside_the_ik_model_writes_no_path():
    """The simulated walk without its pelvis and right shank sensors: the right leg's joints are
    not observed, the model has no right foot, and the path is not written (this crashed)."""
    from pipeline.model.measures import Measures
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.process import process_recording
    from pipeline.simulate.model import simulate_trial

    m = Measures("m", 1.75)
    sk = Skeleton.build(geometry_from_measures(m)[0], knee="hinge", root="freeflyer")
    rec = simulate_trial(sk, "walk", duration_s=12.0, seed=0, standing_s=2.0).raw_recording()
    rec = rec.with_sensors({n: s for n, s in rec.sensors.items()
                            if n not in ("pelvis_imu", "tibia_r_imu")})
    run = process_recording(rec, m, filter="vqf")
    assert run.gait.pelvis_path is None and len(run.gait.strides) > 4
    assert "the pelvis's path needs both feet's orientations from the IK, and the model has no "\
           "right foot (its leg's joints are not observed): not written" in run.notes


@pytest.mark.dataset
def test_s02_the_body_walks_the_room(tmp_path):
    """pipeline ik --landmarks world: pelvis_tx/ty/tz in the .mot, within 2.5 % of the distance
    walked from the Vicon pelvis (1.9 % measured, bench_gait), the landmarks in the room."""
    if not S02.exists():
        pytest.skip("../shared/data/gaittoolbox_s02 not present")
    import sys

    import scipy.io as sio

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_gait import S02_MAP, path_error

    from pipeline.cli import main
    from pipeline.io.mot import read_mot

    pairs = [f"{k}={v}" for k, v in S02_MAP.items()]
    assert main(["ik", "--orientations", str(S02 / "imu"), "--sensor-map", *pairs, "--sex", "m",
                 "--height-m", "1.72", "--no-rerun", "--landmarks", "world", "--out",
                 str(tmp_path)]) == 0
    mot = read_mot(tmp_path / "gaittoolbox_s02_ik.mot").columns
    path = np.column_stack([mot[f"pelvis_t{a}"] for a in "xyz"])
    assert 0.8 < np.median(path[:, 1]) < 1.05  # the pelvis's height above the floor (m)
    m = sio.loadmat(S02 / "vicon" / "S02-Trial-Walk-1.mat", squeeze_me=True,
                    struct_as_record=False)
    err, walked = path_error(path[1000:2200], m["Root"][1000:2200, 3:] / 1000.0)
    assert walked > 7.0 and err.mean() < 0.025 * walked
    import csv

    rows = list(csv.DictReader((tmp_path / "gaittoolbox_s02_landmarks.csv").open()))
    hjc = np.array([[float(r[f"right_HJC_{a}"]) for a in "xz"] for r in rows])
    assert np.ptp(hjc, axis=0).max() > 2.0  # in the room, not relative to the pelvis


def test_a_walk_is_min_strides_on_each_leg():
    from pipeline.analysis.strides import Stride
    from pipeline.process.gait import MIN_STRIDES, walked

    def stride(side: str) -> Stride:
        return Stride(side, *([0.0] * (len(Stride.__dataclass_fields__) - 1)))

    both = [stride(s) for s in ("right", "left") for _ in range(MIN_STRIDES)]
    assert walked(both)
    assert not walked(both[1:])  # one leg a stride short
    assert not walked([])


@pytest.mark.dataset
def test_s02_without_its_feet_the_shanks_find_every_stride():
    """S02 with the foot sensors left out: every stride the feet give found from the shanks
    (the right shank's pivot step at the turn swings at 1.6 rad/s, a third of a straight
    stride's), each initial contact within 30 ms of the foot's but the last one, the stopping
    step's (measured: 1-21 ms, 61 at the turn, 73 at the stop)."""
    from _helpers import s02_cut

    rec = s02_cut(0)
    if rec is None:
        pytest.skip("no S02 data")
    feet = gait_of(rec, [])
    shanks = gait_of(rec.with_sensors({n: s for n, s in rec.sensors.items()
                                       if not n.startswith("calcn")}), [])
    for side in ("right", "left"):
        by_foot = [s for s in feet.strides if s.side == side]
        by_shank = [s for s in shanks.strides if s.side == side]
        assert len(by_shank) == len(by_foot), side
        for f, s in zip(by_foot, by_shank, strict=True):
            if f.straight:
                assert abs(f.start_s - s.start_s) < 0.03, (side, f, s)


def test_a_short_walk_says_what_it_could_not_check():
    from pipeline.analysis.strides import Stride
    from pipeline.process.gait import too_short

    def stride(side):
        return Stride(side, 0.0, 1.0, 1.0, 0.6, 1.3, 1.3, 120.0, 0.02, 0.0, True)

    assert too_short([]) is None
    assert too_short([stride("right")] * 3 + [stride("left")] * 3) is None
    said = too_short([stride("right")] * 2 + [stride("left")] * 3)
    assert said.startswith("a short walk (right 2, left 3 strides, 3 a leg needed)")
    assert "was not checked" in said


def test_swings_without_a_stride_are_not_called_no_walking():
    """One swing of each foot (a step each): no stride, and the notes say the swings were found."""
    w = foot_walk(strides=1, seed=0)
    s = SensorSignals(gyr=w.gyr, acc=w.acc)
    notes: list[str] = []
    gait = gait_of(Recording(w.time, w.rate_hz, {"calcn_r_imu": s, "calcn_l_imu": s}), notes)
    assert gait.strides == []
    assert notes[-1].startswith("no strides: swings found (right 1, left 1) but no two contacts")


@pytest.mark.dataset
def test_s02_after_shuffling_in_place_keeps_its_strides():
    """Ten shuffles before the walk (a heel lifted and set down, its larger turn backwards): the
    swing's sign is the walk's, not the shuffles' (by sign they outvoted it: both feet flipped,
    no stride found), every stride found again, none invented."""
    import sys

    from _helpers import s02_cut

    rec = s02_cut(0)
    if rec is None:
        pytest.skip("no S02 data")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from gait_speeds import shuffling

    lines = shuffling(rec)
    assert "- right: 5 strides as recorded, 5 after the shuffling: 5 the same" in "\n".join(lines)
    assert "- left: 6 strides as recorded, 6 after the shuffling: 6 the same" in "\n".join(lines)
    assert all(" 0 invented" in line for line in lines if line.startswith("- "))
