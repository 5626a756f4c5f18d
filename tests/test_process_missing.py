"""pipeline.process.missing: a sensor's missing samples bridged for the estimators and blank in
what the run gives (unit cases, the simulator, S02 and the x-IMU3 walk)."""

import shutil
from pathlib import Path

import numpy as np
import pytest

from pipeline.analysis.strides import Stride
from pipeline.io.gaps import Missing
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.model.measures import Measures
from pipeline.process.missing import (
    blank_after_restart,
    blank_angles,
    blank_landmarks,
    blank_path,
    blank_rotations,
    bridged,
    missing_of,
    unknown_in,
    without_strides_over,
)

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
S02_MAP = {"pelvis_imu": "00B40B91", "femur_l_imu": "00B40C45", "femur_r_imu": "00B40C3C",
           "tibia_l_imu": "00B40C44", "tibia_r_imu": "00B40C47", "calcn_l_imu": "00B40C55",
           "calcn_r_imu": "00B40C48"}


def _rec(n=200):
    t = np.arange(n) / 100.0
    gyr = np.stack([np.sin(t), np.cos(t), t], axis=1)
    quat = np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
    return Recording(t, 100.0, {"tibia_r_imu": SensorSignals(quat=quat, gyr=gyr.copy(),
                                                             acc=gyr.copy() + 9.81),
                                "pelvis_imu": SensorSignals(quat=quat.copy(), gyr=gyr.copy(),
                                                            acc=gyr.copy())})


def test_missing_spans_are_found_bridged_and_carried():
    rec = _rec()
    s = rec.sensors["tibia_r_imu"]
    gyr, quat = s.gyr.copy(), s.quat.copy()
    gyr[50:80] = np.nan
    quat[60:90] = np.nan
    holed = rec.with_sensors({**rec.sensors, "tibia_r_imu": s.replace(gyr=gyr, quat=quat)})
    missing = missing_of(holed)
    assert missing.spans == {"tibia_r_imu": ((50, 90),)}
    assert missing.describe("tibia_r_imu", rec.time) == "0.50-0.89 s"
    out = bridged(holed, missing)
    assert np.isfinite(out.sensors["tibia_r_imu"].gyr).all()
    np.testing.assert_allclose(out.sensors["tibia_r_imu"].gyr[50:80, 2], rec.time[50:80])  # linear
    assert out.missing == missing and out.present("pelvis_imu").all()
    assert out.present("tibia_r_imu").sum() == 160 and not out.present()[50:90].any()
    assert bridged(rec, missing_of(rec)) is rec  # nothing missing: the recording itself


def test_what_needs_a_missing_sensor_is_blank_and_nothing_else():
    n = 100
    missing = Missing({"tibia_r_imu": ((10, 20),), "pelvis_imu": ((50, 55),)})
    angles = {k: np.zeros(n) for k in ("right_hip_flexion", "right_knee_flexion",
                                       "right_ankle_flexion", "left_knee_flexion",
                                       "left_hip_flexion", "pelvis_tilt")}
    out = blank_angles(angles, missing)
    blank = {k for k, v in out.items() if np.isnan(v[10:20]).all()}
    assert blank == {"right_knee_flexion", "right_ankle_flexion"}
    blank = {k for k, v in out.items() if np.isnan(v[50:55]).all()}
    assert blank == {"right_hip_flexion", "left_hip_flexion", "pelvis_tilt"}
    assert all(np.isfinite(np.delete(v, np.r_[10:20, 50:55])).all() for v in out.values())
    marks = {k: np.zeros((n, 3)) for k in ("right_KJC", "right_AJC", "right_TOE", "left_AJC")}
    from pipeline.model.conventions import landmark_segment

    out = blank_landmarks(marks, missing, landmark_segment)
    # the tibia carries the ankle and the foot below it; the pelvis carries every landmark
    assert {k for k, v in out.items() if np.isnan(v[10:20]).all()} == {"right_AJC", "right_TOE"}
    assert all(np.isnan(v[50:55]).all() for v in out.values())
    assert np.isnan(blank_path(np.zeros((n, 3)), missing)[[10, 50]]).all()


def test_rotations_blank_over_gaps_and_the_spans_read_back():
    n = 50
    rotations = {seg: np.tile(np.eye(3), (n, 1, 1)) for seg in ("right_tibia", "pelvis")}
    missing = Missing({"tibia_r_imu": ((5, 9),)})
    out = blank_rotations(rotations, missing)
    assert np.isnan(out["right_tibia"][5:9]).all() and np.isfinite(out["pelvis"]).all()
    assert unknown_in(out) == missing


def test_strides_over_their_sensors_gap_are_left_out_and_said():
    time = np.arange(1000) / 100.0

    def stride(side, a, b):
        return Stride(side, a, b, b - a, *([np.nan] * 6), straight=True)

    strides = [stride("right", 1.0, 2.0), stride("right", 2.0, 3.0), stride("left", 2.0, 3.0)]
    sources = {"right": "foot sensor calcn_r_imu", "left": "foot sensor calcn_l_imu"}
    notes = []
    kept = without_strides_over(strides, sources, time, Missing({"calcn_r_imu": ((250, 260),)}),
                                notes)
    assert kept == [strides[0], strides[2]]
    assert notes == ["1 stride(s) over a sensor's missing samples left out"]


def test_a_6d_pelvis_restarted_blanks_its_angles_from_its_gap_on():
    angles = {"pelvis_tilt": np.zeros(10), "right_knee_flexion": np.zeros(10)}
    notes = []
    out = blank_after_restart(angles, ("pelvis_tilt",), "pelvis_imu",
                              Missing({"pelvis_imu": ((4, 6),)}), notes)
    assert np.isnan(out["pelvis_tilt"][4:]).all() and np.isfinite(out["pelvis_tilt"][:4]).all()
    assert np.isfinite(out["right_knee_flexion"]).all() and len(notes) == 1


def _with_dropout(rec: Recording, sensor: str, rows: slice) -> Recording:
    s = rec.sensors[sensor]
    cut = {}
    for k in ("quat", "gyr", "acc", "mag"):
        v = getattr(s, k)
        if v is not None:
            v = v.copy()
            v[rows] = np.nan
            cut[k] = v
    return rec.with_sensors({**rec.sensors, sensor: s.replace(**cut)})


def _compare(base, run, rows: slice):
    """(blank joints over ``rows``, RMS difference (deg) of every joint outside them, by
    joint)."""
    blank = {k for k, v in run.joint_angles.items() if np.isnan(v[rows]).all()}
    outside = np.ones(len(run.time), dtype=bool)
    outside[rows] = False
    rms = {}
    for k, a in base.joint_angles.items():
        d = np.angle(np.exp(1j * (run.joint_angles[k][outside] - a[outside])))
        rms[k] = float(np.degrees(np.sqrt(np.nanmean(d**2))))
    return blank, rms


def test_a_simulated_dropout_blanks_the_shanks_joints_and_keeps_the_rest():
    """A 2 s dropout of the right shank in a simulated walk (the vendor's orientations and raw
    signals): named, its knee and ankle blank over it, the other leg and the pelvis as in the
    faultless run, the right leg's joints outside it within 1 deg RMS."""
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.process import process_recording
    from pipeline.simulate.model import simulate_trial

    subject = Measures("m", 1.75)
    sk = Skeleton.build(geometry_from_measures(subject)[0], knee="free", root="freeflyer")
    trial = simulate_trial(sk, "gait", duration_s=12.0, seed=2, standing_s=2.0)
    names = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}
    rec = Recording(trial.time, 100.0, {names[f]: i.recording.sensor
                                        for f, i in trial.imus.items()})
    base = process_recording(rec, subject)
    rows = slice(600, 800)
    run = process_recording(_with_dropout(rec, "tibia_r_imu", rows), subject)
    (f,) = [f for f in run.sensor_findings if f.check == "dropout"]
    assert f.sensor == "tibia_r_imu" and "6.00-7.99 s" in f.evidence and f.action == "noted"
    blank, worst = _compare(base, run, rows)
    right = {k for k in run.joint_angles if k.startswith(("right_knee", "right_ankle"))}
    assert blank == right
    assert all(worst[k] < 0.1 for k in worst if k.startswith(("left_", "pelvis_"))), worst
    assert all(worst[k] < 1.0 for k in worst if k.startswith("right_")), worst


@pytest.mark.dataset
def test_s02_dropouts_of_each_kind_of_sensor():
    """S02 (Xsens' orientations) with 3 s of one sensor missing mid-walk, for a shank, a foot
    and the pelvis: named, the joints it takes part in blank over it, every joint outside it
    within 0.5 deg RMS of the faultless run but for the sensor's own leg's (its lean and its
    knee's and ankle's headings measured on less data: within 1.5 deg RMS)."""
    from pipeline.io.formats import read_recording
    from pipeline.process import process_recording

    if not (DATA / "gaittoolbox_s02").exists():
        pytest.skip("../shared/data/gaittoolbox_s02 not present")
    subject, world = Measures("m", 1.75), {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)}
    rec = read_recording(DATA / "gaittoolbox_s02" / "imu", S02_MAP)
    base = process_recording(rec, subject, **world)
    rows = slice(1400, 1700)
    expect = {"tibia_r_imu": ({"right_knee", "right_ankle"}, "right_"),
              "calcn_l_imu": ({"left_ankle"}, "left_"),
              "pelvis_imu": ({"right_hip", "left_hip", "pelvis"}, None)}
    for sensor, (joints, leg) in expect.items():
        run = process_recording(_with_dropout(rec, sensor, rows), subject, **world)
        assert [f.sensor for f in run.sensor_findings if f.check == "dropout"] == [sensor]
        blank, worst = _compare(base, run, rows)
        assert {k.rsplit("_", 1)[0] for k in blank} == joints, sensor
        for k, w in worst.items():
            assert w < (1.5 if leg and k.startswith(leg) else 0.5), (sensor, k, w)


@pytest.mark.dataset
def test_ximu3_rows_missing_from_one_devices_files(tmp_path):
    """3 s of rows cut from one x-IMU3 device's files, as a radio dropout leaves them (the
    issue: exit 0, no warning, a knee 179 deg off): named with its span, its joints blank,
    the other leg and the pelvis exactly as in the faultless run."""
    from pipeline.io.formats import read_recording
    from pipeline.process import process_recording

    src = DATA / "ximu3_lower_body"
    if not src.exists():
        pytest.skip("../shared/data/ximu3_lower_body not present")
    holed = tmp_path / "rec"
    shutil.copytree(src, holed)
    for f in (holed / "Right Lower Leg 64F61B2A (UDP)").glob("*.csv"):
        lines = f.read_text().splitlines()
        first = int(lines[1].split(",")[0])
        keep = [row for row in lines[1:] if not 8.0 <= (int(row.split(",")[0]) - first) / 1e6 < 11]
        f.write_text("\n".join([lines[0], *keep]) + "\n")
    subject = Measures("m", 1.75)
    base = process_recording(read_recording(src), subject)
    rec = read_recording(holed)
    assert "tibia_r_imu has no samples between t = 7.98 and 11.00 s: missing there, not " \
           "bridged" in rec.notes
    run = process_recording(rec, subject)
    (f,) = [f for f in run.sensor_findings if f.check == "dropout"]
    assert f.sensor == "tibia_r_imu" and "7.99-10.98 s" in f.evidence
    gap = np.isnan(run.joint_angles["right_knee_flexion"])
    assert 140 <= gap.sum() <= 160 and np.isnan(run.joint_angles["right_ankle_flexion"][gap]).all()
    # the subject's heading (both legs' flexion axes) and the magnetometers' common field are
    # measured on less data: every joint moves a little, the other leg's within 0.5 deg RMS
    blank, rms = _compare(base, run, gap)
    assert {k.rsplit("_", 1)[0] for k in blank} == {"right_knee", "right_ankle"}
    for k, w in rms.items():
        assert w < (1.5 if k.startswith("right_") else 0.5), (k, w)


@pytest.mark.dataset
def test_s02_a_foot_sensor_whose_battery_died_before_the_walk(tmp_path):
    """S02's right foot file ending at 12 s (the issue: 'no strides: no walking found'): the run
    spans every sensor's samples, names the foot with its span, blanks the right ankle from
    there, and finds the right strides from the shank instead (said why)."""
    from pipeline.io.formats import read_recording
    from pipeline.process import process_recording

    src = DATA / "gaittoolbox_s02" / "imu"
    if not src.exists():
        pytest.skip("../shared/data/gaittoolbox_s02 not present")
    for f in src.iterdir():
        if S02_MAP["calcn_r_imu"] in f.name:
            lines = f.read_text().splitlines()
            head = next(i for i, x in enumerate(lines) if x.startswith("PacketCounter")) + 1
            (tmp_path / f.name).write_text("\n".join(lines[: head + 1200]) + "\n")
        else:
            (tmp_path / f.name).symlink_to(f)
    rec = read_recording(tmp_path, S02_MAP)
    assert rec.n_samples == 2503 and "calcn_r_imu ends 13.03 s early: missing there, not " \
                                       "bridged" in rec.notes
    run = process_recording(rec, Measures("m", 1.72), sensor_to_model=(-np.pi / 2, 0.0, 0.0))
    (f,) = [f for f in run.sensor_findings if f.check == "dropout"]
    assert f.sensor == "calcn_r_imu" and "12.00-25.02 s" in f.evidence
    assert np.isnan(run.joint_angles["right_ankle_flexion"][1200:]).all()
    assert np.isfinite(run.joint_angles["right_knee_flexion"]).all()
    sides = [s.side for s in run.gait.strides]
    assert sides.count("right") >= 4 and sides.count("left") >= 5
    assert any("right strides from the shank sensor tibia_r_imu (the foot sensor calcn_r_imu "
               "has 48% of the recording's samples" in n for n in run.notes)
