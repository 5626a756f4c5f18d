"""pipeline.process.swap: a leg's thigh and shank sensors swapped, told apart by the foot (eq 1),
and sensors exchanged between the legs, told by the stride's rhythm (eq 2), on the simulator and
on the real recordings, and read back by the sensor check."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.io.recording import Recording
from pipeline.model.measures import Measures
from pipeline.process.check_context import CheckContext
from pipeline.process.sensor_checks import SWAPPED_BACK, check_sensors
from pipeline.process.swap import (
    MIN_GAIN,
    MIN_RESIDUAL,
    MIN_THIGH_GAIN,
    SWAP_RATIO,
    Crossing,
    crossing_evidence,
    swap_evidence,
)

SUBJECT = Measures("m", 1.75)
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _trial(motion: str, standing_s: float, knee: str = "free"):
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.artefacts import Artefacts
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee=knee, root="freeflyer",
                        ankle="free" if motion == "walk" else "universal")
    artefacts = Artefacts() if motion in ("walk", "gait") else None
    return simulate_trial(sk, motion, duration_s=12.0, seed=0, standing_s=standing_s,
                          artefacts=artefacts).raw_recording()


def _swapped(rec: Recording, side: str) -> Recording:
    thigh, shank = f"femur_{side}_imu", f"tibia_{side}_imu"
    return rec.with_sensors({**rec.sensors, thigh: rec.sensors[shank],
                             shank: rec.sensors[thigh]})


def _crossed(rec: Recording, segment: str) -> Recording:
    """The right and left ``segment`` (``femur``, ``tibia``, ``calcn``) sensors exchanged."""
    right, left = f"{segment}_r_imu", f"{segment}_l_imu"
    return rec.with_sensors({**rec.sensors, right: rec.sensors[left], left: rec.sensors[right]})


def _assert_as_named(fixed: Recording, named: Recording) -> None:
    for name, s in named.sensors.items():
        assert np.array_equal(fixed.sensors[name].gyr, s.gyr), name


#: What eq (2)-(3) read exchanged for each exchange injected.
EXCHANGED = {"tibia": "tibia", "calcn": "foot"}


@pytest.fixture(scope="module")
def walk() -> Recording:
    """The simulated walk (free knee and ankle, soft tissue, wandering biases)."""
    return _trial("walk", 3.0)


def test_the_foot_fits_its_shank_not_its_thigh(walk):
    for side in ("right", "left"):
        ev = swap_evidence(side, walk)
        assert ev.thigh_residual > SWAP_RATIO * ev.shank_residual and not ev.swapped, ev
        assert swap_evidence(side, _swapped(walk, side[0])).swapped


def test_the_check_reads_a_swapped_leg_back_and_says_so(walk):
    fixed, found = check_sensors(_swapped(walk, "r"))
    (f,) = [f for f in found if f.check == "swapped"]
    assert (f.sensor, f.action, f.flagged) == ("tibia_r_imu", SWAPPED_BACK, True)
    assert "fits an ankle with femur_r_imu" in f.evidence
    _assert_as_named(fixed, walk)
    assert not [f for f in check_sensors(walk)[1] if f.check == "swapped"]


@pytest.mark.parametrize("motion, standing_s", [("static", 3.0), ("supine_hip_flexion", 0.0)])
def test_a_still_leg_decides_nothing(motion, standing_s):
    """Standing or lying, both fits leave noise (eq 1's MIN_RESIDUAL): not read as swapped even
    when the sensors are; not a walk, eq (2) does not decide."""
    named = _trial(motion, standing_s, knee="hinge")
    ev = swap_evidence("right", _swapped(named, "r"))
    assert max(ev.shank_residual, ev.thigh_residual) < MIN_RESIDUAL and not ev.swapped
    assert crossing_evidence(CheckContext(named)) is None  # no strides: not a walk


def test_the_legs_take_turns(walk):
    """Eq (2)-(3): as named each leg's shank and foot pair (P < 0); each exchange injected is
    found and told (module docstring's figures)."""
    c = crossing_evidence(CheckContext(walk))
    assert c.pairing < -2 * MIN_GAIN and not c.crossed and c.exchanged is None
    for segment, exchanged in EXCHANGED.items():
        c = crossing_evidence(CheckContext(_crossed(walk, segment)))
        assert c.crossed and c.exchanged == exchanged, (segment, c)
        assert abs(c.thighs) > MIN_THIGH_GAIN * 1.5, (segment, c)


def test_the_check_reads_crossed_sensors_back(walk):
    fixed, found = check_sensors(_crossed(walk, "calcn"))
    (f,) = [f for f in found if f.check == "crossed"]
    assert (f.sensor, f.action, f.flagged) == ("calcn_r_imu", SWAPPED_BACK, True)
    assert "feet's sensors are swapped" in f.evidence
    _assert_as_named(fixed, walk)
    from pipeline.process.run import process_recording

    run, back = (process_recording(r, SUBJECT) for r in (walk, _crossed(walk, "tibia")))
    for name, x in run.joint_angles.items():
        np.testing.assert_allclose(back.joint_angles[name], x, atol=1e-9, err_msg=name)


def test_where_the_thighs_do_not_tell_the_four_are_excluded(walk):
    """Eq (3) between the limits: the shanks' and feet's sensors excluded, named, not guessed."""
    c = Crossing(pairing=2 * MIN_GAIN, thighs=MIN_THIGH_GAIN / 2, with_legs=3.0)
    assert c.crossed and c.exchanged is None
    assert sorted(c.sensors) == ["calcn_l_imu", "calcn_r_imu", "tibia_l_imu", "tibia_r_imu"]
    assert "do not tell whether" in c.evidence()
    assert set(c.read_back(walk).sensors) == {"pelvis_imu", "femur_r_imu", "femur_l_imu"}


@pytest.mark.dataset
def test_the_real_walks():
    """S02 (Xsens MTw) and the x-IMU3 walk as recorded: no leg swapped, no exchange between the
    legs; each leg with its thigh and shank swapped and each exchange injected: found (module
    docstring's figures)."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_gait import S02_MAP

    from pipeline.io.formats import read_recording

    s02, ximu3 = DATA / "gaittoolbox_s02" / "imu", DATA / "ximu3_lower_body"
    if not (s02.exists() and ximu3.exists()):
        pytest.skip("../shared/data/gaittoolbox_s02 or ximu3_lower_body not present")
    for rec in (read_recording(s02, S02_MAP), read_recording(ximu3)):
        for side in ("right", "left"):
            ev = swap_evidence(side, rec)
            assert ev.thigh_residual > 2.0 * ev.shank_residual, ev
            assert swap_evidence(side, _swapped(rec, side[0])).swapped
        c = crossing_evidence(CheckContext(rec))
        assert c.pairing < -2 * MIN_GAIN and not c.crossed, c
        for segment, exchanged in EXCHANGED.items():
            c = crossing_evidence(CheckContext(_crossed(rec, segment)))
            assert c.crossed and c.exchanged == exchanged, (segment, c)


def test_a_faulty_sensor_keeps_its_leg_from_deciding_a_dead_magnetometer_does_not(walk):
    """A leg sensor excluded or noted (here the foot's gyroscope axis dead) could make either fit
    the worse: that leg is not decided; a magnetometer left out (all zero) changes no fit."""
    swapped = _swapped(walk, "r")
    foot = swapped.sensors["calcn_r_imu"]
    dead = swapped.with_sensors({**swapped.sensors, "calcn_r_imu": foot.replace(
        gyr=np.column_stack([foot.gyr[:, 0], np.zeros(len(foot.gyr)), foot.gyr[:, 2]]))})
    assert not [f for f in check_sensors(dead)[1] if f.check == "swapped"]
    shank = swapped.sensors["tibia_r_imu"]
    no_mag = swapped.with_sensors({**swapped.sensors,
                                   "tibia_r_imu": shank.replace(mag=np.zeros_like(shank.mag))})
    found = check_sensors(no_mag)[1]
    assert any(f.action == "magnetometer not used" for f in found)
    assert [f.action for f in found if f.check == "swapped"] == [SWAPPED_BACK]


@pytest.mark.dataset
def test_running_thighs_do_not_guess():
    """qmt_full_body (16 IMUs, no truth; strides of 1 s at 5-7 rad/s): its shanks' sensors
    exchanged are found (eq 2), but its thighs swing the wrong way round for eq (3): the four
    sensors would be excluded, not read back wrongly."""
    from _helpers import qmt_recording

    rec = qmt_recording(DATA)
    if rec is None:
        pytest.skip("../shared/data/qmt_full_body not present")
    assert not crossing_evidence(CheckContext(rec)).crossed
    c = crossing_evidence(CheckContext(_crossed(rec, "tibia")))
    assert c.crossed and c.thighs < 0 and c.exchanged is None, c
    assert set(c.read_back(rec).sensors) == {"pelvis_imu", "femur_r_imu", "femur_l_imu"}
    # the sensor check itself does not decide here: four of qmt's gyroscopes pass a human
    # segment's speed (noted), and a noted sensor keeps its legs from eq (2)
    found = check_sensors(_crossed(rec, "tibia"))[1]
    assert any(f.check == "saturation" and f.action == "noted" for f in found)
    assert not [f for f in found if f.check == "crossed"]
