"""pipeline.process.sides: the legs' sensors named left for right, told by the hip centres (eq 1),
on the simulator and on the real walk, and read back by the pipeline."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.io.recording import Recording, SensorSignals
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.process.run import process_recording
from pipeline.process.sensor_checks import SWAPPED_BACK
from pipeline.process.sides import MIN_MARGIN, in_one_heading, mirrored, side_evidence

SUBJECT = Measures("m", 1.75)
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


@pytest.fixture(scope="module")
def walk() -> Recording:
    """The simulated walk (free knee and ankle, soft tissue, wandering biases; 9-D)."""
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.artefacts import Artefacts
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee="free", root="freeflyer",
                        ankle="free")
    return simulate_trial(sk, "walk", duration_s=12.0, seed=0, standing_s=3.0,
                          artefacts=Artefacts()).raw_recording()


def _margin(rec: Recording, **options) -> float:
    """Eq (1) on ``rec`` as the pipeline reads it (its own run's subject's right)."""
    import pipeline.process.run as run_module

    seen = []
    real = run_module.side_evidence

    def spy(*args):
        seen.append(real(*args))
        return seen[-1]

    run_module.side_evidence = spy
    try:
        process_recording(rec, SUBJECT, **options)
    finally:
        run_module.side_evidence = real
    return seen[0].margin


def test_mirrored_gives_each_leg_sensor_the_other_legs_name():
    s = {n: SensorSignals(gyr=np.full((3, 3), k)) for k, n in
         enumerate(["pelvis_imu", "femur_r_imu", "femur_l_imu", "calcn_r_imu", "torso_imu"])}
    rec = Recording(np.arange(3.0), 100.0, s, sensor_notes={"femur_r_imu": ("a gap",)})
    out = mirrored(rec)
    assert out.sensors["femur_l_imu"] is s["femur_r_imu"]
    assert out.sensors["femur_r_imu"] is s["femur_l_imu"]
    assert out.sensors["calcn_l_imu"] is s["calcn_r_imu"] and "calcn_r_imu" not in out.sensors
    assert out.sensors["pelvis_imu"] is s["pelvis_imu"]
    assert out.sensors["torso_imu"] is s["torso_imu"]
    assert out.sensor_notes == {"femur_l_imu": ("a gap",)}
    assert mirrored(None) is None
    thighs = mirrored(rec, ("femur",))
    assert thighs.sensors["femur_l_imu"] is s["femur_r_imu"]
    assert thighs.sensors["calcn_r_imu"] is s["calcn_r_imu"]


def test_the_hip_centres_say_which_leg_is_which(walk):
    """Named right: eq (1) near +1; mirrored: the same fits, the sign turned (the subject's right
    comes from both legs' flexion alike, within 0.01)."""
    m = _margin(walk)
    assert m > 2 * MIN_MARGIN
    assert _margin(mirrored(walk)) == pytest.approx(-m, abs=0.01)


def test_a_mirrored_recording_is_read_back_and_flagged(walk):
    run = process_recording(walk, SUBJECT)
    back = process_recording(mirrored(walk), SUBJECT)
    (f,) = [f for f in back.sensor_findings if f.check == "sides"]
    assert (f.sensor, f.action) == ("femur_r_imu", SWAPPED_BACK)
    assert "named left for right" in f.evidence and f.line() in back.flags
    assert not [f for f in run.sensor_findings if f.check == "sides"]
    for name, x in run.joint_angles.items():
        np.testing.assert_allclose(back.joint_angles[name], x, atol=1e-9, err_msg=name)


def test_thighs_named_for_the_other_leg_alone_are_read_back_alone(walk):
    """The hips find the thighs mirrored; the stride's rhythm (swap eq 4) puts each thigh with
    the other leg's shank and foot: the thighs alone are exchanged back."""
    crossed = walk.with_sensors({**walk.sensors, "femur_r_imu": walk.sensors["femur_l_imu"],
                                 "femur_l_imu": walk.sensors["femur_r_imu"]})
    run, back = process_recording(walk, SUBJECT), process_recording(crossed, SUBJECT)
    (f,) = [f for f in back.sensor_findings if f.check == "sides"]
    assert "the thighs' sensors are named left for right" in f.evidence
    for name, x in run.joint_angles.items():
        np.testing.assert_allclose(back.joint_angles[name], x, atol=1e-9, err_msg=name)


def test_where_the_rhythm_does_not_tell_the_run_is_refused(monkeypatch):
    """Eq (4) between the limits: which sensors to read back is not guessed (one-line error)."""
    import pipeline.process.swap as swap
    from pipeline.errors import InputError
    from pipeline.process.sides import Sides, exchange_of

    monkeypatch.setattr(swap, "crossing_evidence",
                        lambda rec: swap.Crossing(-3.0, 0.0, swap.MIN_THIGH_GAIN / 2))
    rec = Recording(np.arange(3.0), 100.0, {})
    with pytest.raises(InputError, match="does not tell whether the shanks and feet go"):
        exchange_of(Sides(-1.0, 0.18, 0.18), rec)


def test_without_the_thighs_signals_there_is_no_evidence(walk):
    orientations_only = walk.with_sensors({n: s.replace(gyr=None, acc=None, mag=None)
                                           for n, s in walk.sensors.items()})
    rotations = {s: np.tile(np.eye(3), (len(walk.time), 1, 1))
                 for s in ("pelvis", "right_femur", "left_femur")}
    geometry = geometry_from_measures(SUBJECT)[0]
    assert side_evidence(orientations_only, rotations, np.array([0, 0, 1.0]), "ipopt", geometry,
                         []) is None


def test_one_heading_down_each_leg():
    """Shared headings or aligned joints, down both legs (the feet do not count)."""
    names = ["pelvis_imu", "femur_r_imu", "femur_l_imu", "tibia_r_imu", "tibia_l_imu"]
    assert in_one_heading(names, [])
    assert in_one_heading([], ["right_hip", "left_hip", "right_knee", "left_knee"])
    assert in_one_heading(names[:3], ["right_knee", "left_knee"])  # S02's shanks distrusted
    assert not in_one_heading(names[:3], ["right_knee"])
    assert not in_one_heading(names[1:], [])  # the pelvis's own heading


def test_only_a_walk_decides():
    """Lying with one hip flexing, the still hip's centre is free (eq 1 read -0.77 on this trial,
    module docstring): no strides, no evidence, nothing read back."""
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee="hinge", root="freeflyer")
    rec = simulate_trial(sk, "supine_hip_flexion", duration_s=12.0, seed=0).raw_recording()
    run = process_recording(rec, SUBJECT, calibration_pose="supine")
    assert not run.gait.strides
    assert not [f for f in run.sensor_findings if f.check == "sides"]


@pytest.mark.dataset
def test_the_real_walk_named_left_for_right():
    """S02 (Xsens MTw): eq (1) +0.99 as named, its sensor map mirrored read back to the same
    angles, with the vendor's orientations and without magnetometers; without magnetometers
    and the headings left apart (``drift='none'``), not decided."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_gait import S02_MAP

    from pipeline.io.formats import read_recording

    s02 = DATA / "gaittoolbox_s02" / "imu"
    if not s02.exists():
        pytest.skip("../shared/data/gaittoolbox_s02 not present")
    rec = read_recording(s02, S02_MAP)
    six_d = rec.with_sensors({n: s.replace(quat=None, mag=None) for n, s in rec.sensors.items()})
    apart = process_recording(six_d, SUBJECT, drift="none")  # read mirrored before: -1.00
    assert not [f for f in apart.sensor_findings if f.check == "sides"]
    for r in (rec, six_d):
        assert _margin(r) > 0.9
        run, back = process_recording(r, SUBJECT), process_recording(mirrored(r), SUBJECT)
        assert [f.check for f in back.sensor_findings if f.check == "sides"] == ["sides"]
        for name, x in run.joint_angles.items():
            np.testing.assert_allclose(back.joint_angles[name], x, atol=1e-9, err_msg=name)
