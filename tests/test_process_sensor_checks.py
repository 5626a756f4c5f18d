"""pipeline.process.sensor_checks: every fault of a sensor's raw signals found, named and handled
(on the simulator with one injected fault at a time, and on the real recordings)."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.model.measures import Measures
from pipeline.process.recording_checks import check_units
from pipeline.process.sensor_checks import CHECKS, check_sensors

SUBJECT = Measures("m", 1.75)
NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items() if seg != "torso"}
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


@pytest.fixture(scope="module")
def walk() -> Recording:
    """A simulated walk with soft tissue, wandering biases and the floor's field."""
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.artefacts import Artefacts
    from pipeline.simulate.model import simulate_trial

    geometry, _ = geometry_from_measures(SUBJECT)
    sk = Skeleton.build(geometry, knee="free", root="freeflyer")
    trial = simulate_trial(sk, "gait", duration_s=12.0, seed=3, standing_s=2.0,
                           artefacts=Artefacts())
    return Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(
        gyr=i.recording.gyr, acc=i.recording.acc, mag=i.recording.mag)
        for f, i in trial.imus.items()})


def _with(rec: Recording, name: str, **signals) -> Recording:
    return rec.with_sensors({**rec.sensors, name: rec.sensors[name].replace(**signals)})


def test_a_clean_walk_has_no_findings(walk):
    out, findings = check_sensors(walk)
    assert findings == [] and set(out.sensors) == set(walk.sensors)


def test_a_dead_gyroscope_axis_excludes_the_sensor(walk):
    gyr = walk.sensors["tibia_r_imu"].gyr.copy()
    gyr[:, 1] = 0.0
    out, (f,) = check_sensors(_with(walk, "tibia_r_imu", gyr=gyr))
    assert (f.sensor, f.check, f.action) == ("tibia_r_imu", "dead", "excluded")
    assert "gyroscope axes y never change" in f.evidence and "tibia_r_imu" not in out.sensors


def test_a_dead_magnetometer_is_not_used_and_the_sensor_stays(walk):
    out, (f,) = check_sensors(_with(walk, "femur_l_imu", mag=np.zeros_like(
        walk.sensors["femur_l_imu"].mag)))
    assert (f.check, f.action) == ("dead", "magnetometer not used")
    assert out.sensors["femur_l_imu"].mag is None and out.sensors["femur_l_imu"].gyr is not None


def test_a_gyroscope_clipped_at_its_range_is_excluded(walk):
    """A +-250 deg/s range (the smallest MEMS gyroscopes have) on a foot swinging at up to
    ~540 deg/s (the simulated foot's rates tripled: real feet reach 500-700 deg/s, S02 and
    x-IMU3)."""
    gyr = 3.0 * walk.sensors["calcn_r_imu"].gyr
    limit = np.radians(250.0)
    out, (f,) = check_sensors(_with(walk, "calcn_r_imu", gyr=np.clip(gyr, -limit, limit)))
    assert (f.check, f.action) == ("saturation", "excluded")
    assert "held at 250 deg/s" in f.evidence
    assert "calcn_r_imu" not in out.sensors


def test_a_gyroscope_beyond_a_human_segments_speed_is_excluded(walk):
    """The real DOT foot of issue 24: +-1,700-1,950 deg/s in a 2,000 deg/s range."""
    gyr = walk.sensors["calcn_l_imu"].gyr.copy()
    rng = np.random.default_rng(0)
    burst = rng.uniform(1700, 1950, size=300) * rng.choice([-1, 1], size=300)
    gyr[500:800, 2] = np.radians(burst)
    _, findings = check_sensors(_with(walk, "calcn_l_imu", gyr=gyr))
    assert [(f.sensor, f.check, f.action) for f in findings] == [
        ("calcn_l_imu", "saturation", "excluded")]
    assert "beyond a human segment's speed" in findings[0].evidence


def test_a_gyroscope_in_degrees_is_refused_even_on_a_slow_trial(walk):
    """deg/s as rad/s on a slow motion: the magnitude test (90th percentile) would pass it; the
    accelerometer's turn of gravity does not."""
    from pipeline.io.checks import check_gyro_units
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee="free", root="freeflyer")
    seated = simulate_trial(sk, "still_thigh", duration_s=12.0, seed=3)
    rec = Recording(seated.time, 100.0, {NAMES[f]: SensorSignals(
        gyr=np.degrees(i.recording.gyr), acc=i.recording.acc) for f, i in seated.imus.items()})
    check_gyro_units(rec.sensors["pelvis_imu"].gyr)  # 90th percentile 1.5 "rad/s": passes
    check_units(walk)  # rad/s: passes
    with pytest.raises(InputError, match=r"field gyr: .*look like deg/s read as rad/s"):
        check_sensors(rec)
    with pytest.raises(InputError, match=r"look like rad/s read as deg/s"):
        check_units(walk.with_sensors({n: s.replace(gyr=np.radians(s.gyr))
                                       for n, s in walk.sensors.items()}))


def test_a_sensor_that_fell_off_is_excluded(walk):
    n = walk.time.size
    rng = np.random.default_rng(1)
    lying = SensorSignals(gyr=rng.normal(0, 0.005, (n, 3)),
                          acc=np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0, 0.02, (n, 3)),
                          mag=walk.sensors["tibia_l_imu"].mag)
    out, (f,) = check_sensors(walk.with_sensors({**walk.sensors, "tibia_l_imu": lying}))
    assert (f.sensor, f.check, f.action) == ("tibia_l_imu", "moves with its segment", "excluded")


def test_a_still_thigh_or_a_foot_on_the_floor_is_not_a_fallen_sensor(walk):
    """Seated knee extension (the thigh still while the shank swings) gives no finding; a foot
    still while its shank turns (a squat's foot, or a fallen one: one neighbour cannot tell) is
    noted, not excluded."""
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee="free", root="freeflyer")
    seated = simulate_trial(sk, "still_thigh", duration_s=12.0, seed=3)
    rec = Recording(seated.time, 100.0, {NAMES[f]: SensorSignals(
        gyr=i.recording.gyr, acc=i.recording.acc) for f, i in seated.imus.items()})
    assert [f for f in check_sensors(rec)[1] if f.check == "moves with its segment"] == []
    n = walk.time.size
    rng = np.random.default_rng(2)
    lying = SensorSignals(gyr=rng.normal(0, 0.005, (n, 3)),
                          acc=np.tile([0.0, 0.0, 9.81], (n, 1)) + rng.normal(0, 0.02, (n, 3)))
    out, (f,) = check_sensors(walk.with_sensors({**walk.sensors, "calcn_r_imu": lying}))
    assert (f.sensor, f.check, f.action) == ("calcn_r_imu", "moves with its segment", "noted")
    assert "calcn_r_imu" in out.sensors


def test_feet_that_rest_through_mid_stance_are_not_taken_for_fallen_sensors():
    """The simulated walk's feet rest flat through every mid-stance and through the standing
    start (their median speed below 0.15 of the shanks'): no finding."""
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee="free", root="freeflyer")
    rec = simulate_trial(sk, "walk", duration_s=10.0, seed=0, standing_s=2.0).raw_recording()
    feet = rec.sensors["calcn_r_imu"].gyr, rec.sensors["tibia_r_imu"].gyr
    assert np.median(np.linalg.norm(feet[0], axis=1)) < 0.15 * np.median(
        np.linalg.norm(feet[1], axis=1))  # the median alone would call it fallen
    assert [f for f in check_sensors(rec)[1] if f.check == "moves with its segment"] == []


def test_the_run_names_the_excluded_sensor_and_writes_none_of_its_joints(walk):
    from pipeline.commands.ik import summary_text
    from pipeline.process import process_recording

    gyr = walk.sensors["tibia_r_imu"].gyr.copy()
    gyr[:, 0] = 0.0
    run = process_recording(_with(walk, "tibia_r_imu", gyr=gyr), SUBJECT, filter="vqf")
    assert not any(k.startswith(("right_knee", "right_ankle")) for k in run.joint_angles)
    assert "left_knee_flexion" in run.joint_angles
    assert any("sensor tibia_r_imu: dead" in f for f in run.flags)
    assert "| tibia_r_imu | dead: gyroscope axes x never change (excluded) |" in summary_text(run)



def test_quaternions_in_x_y_z_w_order_are_refused(walk):
    """The simulator's orientations written x, y, z, w and read as w, x, y, z: refused, named;
    the same in the right order pass."""
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.process.recording_checks import check_quaternion_order
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee="free", root="freeflyer")
    trial = simulate_trial(sk, "gait", duration_s=8.0, seed=2, standing_s=2.0)
    right = Recording(trial.time, 100.0, {NAMES[f]: SensorSignals(
        gyr=i.recording.gyr, acc=i.recording.acc, quat=i.recording.quat)
        for f, i in trial.imus.items()})
    check_quaternion_order(right)
    wrong = right.with_sensors({n: s.replace(quat=s.quat[:, [1, 2, 3, 0]])
                                for n, s in right.sensors.items()})
    with pytest.raises(InputError, match=r"field quat: .*read as x, y, z, w"):
        check_sensors(wrong)

def test_a_dropout_is_named_and_kept_unless_nearly_all_is_missing(walk):
    """5 s of missing samples (a radio dropout): named with its time and kept (what needs it is
    blank there, :mod:`pipeline.process.missing`); a sensor missing 90 % of the recording is
    excluded."""
    gyr, acc = walk.sensors["femur_l_imu"].gyr.copy(), walk.sensors["femur_l_imu"].acc.copy()
    gyr[500:1000], acc[500:1000] = np.nan, np.nan
    out, (f,) = check_sensors(_with(walk, "femur_l_imu", gyr=gyr, acc=acc))
    assert (f.sensor, f.check, f.action) == ("femur_l_imu", "dropout", "noted")
    assert f"missing at 5.00-9.99 s ({100 * 500 / walk.n_samples:.1f}% of" in f.evidence
    assert "femur_l_imu" in out.sensors and np.isfinite(out.sensors["femur_l_imu"].gyr).all()
    n = walk.n_samples
    gyr[: int(0.95 * n)] = np.nan
    out, (f,) = check_sensors(_with(walk, "femur_l_imu", gyr=gyr, acc=acc))
    assert (f.check, f.action) == ("dropout", "excluded") and "femur_l_imu" not in out.sensors


def test_a_repair_of_one_sensors_file_is_named_on_that_sensor(tmp_path):
    """A folder of Xsens files, one with dropped packets (filled by the reader): the finding is
    that sensor's, listed (not a flag), with the reader's words."""
    import dataclasses

    from pipeline.io.formats import read_recording

    folder = tmp_path / "imu"
    folder.mkdir()
    rows = [f"{k}\t0\t0\t9.81\t0.1\t0.2\t0.3" for k in range(200) if k not in (50, 51)]
    for name in ("femur_r_imu", "tibia_r_imu"):
        lines = ["// Update Rate: 100.0Hz", "PacketCounter\tAcc_X\tAcc_Y\tAcc_Z\tGyr_X\tGyr_Y"
                 "\tGyr_Z"]
        body = rows if name == "tibia_r_imu" else [r for k, r in enumerate(
            f"{k}\t0\t0\t9.81\t0.1\t0.2\t0.3" for k in range(200))]
        (folder / f"{name}.txt").write_text("\n".join(lines + body) + "\n")
    rec = read_recording(folder)
    assert set(rec.sensor_notes) == {"tibia_r_imu"}
    _, found = check_sensors(dataclasses.replace(rec, time=rec.time))
    (f,) = [f for f in found if f.check == "read"]
    assert (f.sensor, f.action, f.flagged) == ("tibia_r_imu", "listed", False)
    assert f.evidence.startswith("its file's reader: 2 dropped packet(s) (PacketCounter jumps)")


def test_the_registry_names_every_check_with_its_scope():
    from pipeline.process.sensor_checks import SCOPES

    assert {n: c.scope for n, c in CHECKS.items()} == {
        "units": "recording", "quaternion order": "recording", "read": "sensor",
        "dead": "sensor", "dropout": "sensor", "saturation": "sensor", "orientations": "sensor",
        "moves with its segment": "sensor", "slipped": "sensor", "crossed": "legs",
        "swapped": "legs"}
    assert {c.scope for c in CHECKS.values()} == set(SCOPES)


def test_an_unchanged_recording_keeps_its_context_the_strides_computed_once():
    from pipeline.process.check_context import CheckContext
    from pipeline.process.sensor_checks import run_checks

    t = np.arange(300) / 100.0
    rng = np.random.default_rng(3)
    s = SensorSignals(gyr=rng.normal(0, 0.01, (300, 3)), acc=np.tile([0, 0, 9.81], (300, 1))
                      + rng.normal(0, 0.01, (300, 3)))
    ctx = CheckContext(Recording(t, 100.0, {"calcn_r_imu": s}))
    checked, findings = run_checks(ctx)
    assert findings == [] and checked is ctx and checked.rec is ctx.rec
    assert ctx.gait is checked.gait  # computed once, shared


@pytest.mark.dataset
def test_the_real_recordings():
    """S02 (Xsens MTw) and x-IMU3: nothing flagged (S02's shank gyroscopes peak at ~300 deg/s on
    one axis with rounded tops, 0.6 % over 40 ms: a smooth peak, not a range's limit)."""
    from pipeline.io.formats import read_recording

    s02, ximu3 = DATA / "gaittoolbox_s02" / "imu", DATA / "ximu3_lower_body"
    if not (s02.exists() and ximu3.exists()):
        pytest.skip("../shared/data/gaittoolbox_s02 or ximu3_lower_body not present")
    ids = {"pelvis_imu": "00B40B91", "femur_l_imu": "00B40C45", "femur_r_imu": "00B40C3C",
           "tibia_l_imu": "00B40C44", "tibia_r_imu": "00B40C47", "calcn_l_imu": "00B40C55",
           "calcn_r_imu": "00B40C48"}
    _, findings = check_sensors(read_recording(s02, ids))
    assert findings == []
    found = check_sensors(read_recording(ximu3))[1]
    assert [f for f in found if f.flagged] == []
    # two short walks, turns on the spot and shuffles: the leg sensors' views step 20-86 deg
    # with the leg's others and the other leg's, so each is listed as not checked (a slip would
    # not be told from the movement's change), none flagged; so is the pelvis (its gravity steps
    # 4 deg, the axis it rocks about 19 deg with the leg's others at 36); the right shank, its
    # turning steps found too, steps less than the limit
    listed = [f for f in found if f.check == "slipped"]
    assert {f.sensor for f in listed} >= set(read_recording(ximu3).sensors) - {"tibia_r_imu"}
    assert all("the movement itself changed" in f.evidence or "across a pause" in f.evidence
               for f in listed)


@pytest.mark.dataset
def test_one_sensors_quaternion_order_is_named_and_its_orientation_filtered():
    """S02 with the right thigh's quaternions written x, y, z, w (the others right): named for
    that sensor (its orientations turn unlike its gyroscope), its orientation from its raw signals
    (6-D, aligned by the joints): every joint within 2 deg RMS of the faultless run (measured:
    0.1-1.8, the right hip's rotation most)."""
    from _helpers import s02_cut

    from pipeline.process import mot_columns, process_recording

    rec = s02_cut(0)
    if rec is None:
        pytest.skip("no S02 data")
    s = rec.sensors["femur_r_imu"]
    bad = rec.with_sensors({**rec.sensors, "femur_r_imu": s.replace(quat=s.quat[:, [1, 2, 3, 0]])})
    z_up = {"sensor_to_model": (-np.pi / 2, 0.0, 0.0)}
    base, run = (process_recording(r, Measures("m", 1.72), **z_up) for r in (rec, bad))
    (f,) = run.sensor_findings
    assert (f.sensor, f.check, f.action) == ("femur_r_imu", "orientations",
                                             "orientation from its raw signals")
    assert any("orientations of ['femur_r_imu'] estimated from their raw signals" in n
               for n in run.notes)
    a, b = mot_columns(base), mot_columns(run)
    moved = {k: np.degrees(np.sqrt(np.nanmean((a[k] - b[k]) ** 2))) for k in a
             if not k.startswith("pelvis_t")}
    assert max(moved.values()) < 2.0, moved
