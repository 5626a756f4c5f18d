"""pipeline.process.swap: a leg's thigh and shank sensors swapped, told apart by the foot (eq 1),
on the simulator and on the real recordings, and read back by the sensor check."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.io.recording import Recording
from pipeline.model.measures import Measures
from pipeline.process.sensor_checks import SWAPPED_BACK, check_sensors
from pipeline.process.swap import MIN_RESIDUAL, SWAP_RATIO, swap_evidence

SUBJECT = Measures("m", 1.75)
DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"


def _trial(motion: str, standing_s: float, knee: str = "free"):
    from pipeline.model.scaling import geometry_from_measures
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.artefacts import Artefacts
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee=knee, root="freeflyer",
                        ankle="free" if motion == "walk" else "universal")  # fmt: skip
    artefacts = Artefacts() if motion in ("walk", "gait") else None
    return simulate_trial(sk, motion, duration_s=12.0, seed=0, standing_s=standing_s,
                          artefacts=artefacts).raw_recording()  # fmt: skip


def _swapped(rec: Recording, side: str) -> Recording:
    thigh, shank = f"femur_{side}_imu", f"tibia_{side}_imu"
    return rec.with_sensors({**rec.sensors, thigh: rec.sensors[shank],
                             shank: rec.sensors[thigh]})  # fmt: skip


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
    for name, s in walk.sensors.items():
        assert np.array_equal(fixed.sensors[name].gyr, s.gyr), name
    assert not [f for f in check_sensors(walk)[1] if f.check == "swapped"]


@pytest.mark.parametrize("motion, standing_s", [("static", 3.0), ("supine_hip_flexion", 0.0)])
def test_a_still_leg_decides_nothing(motion, standing_s):
    """Standing or lying, both fits leave noise (eq 1's MIN_RESIDUAL): not read as swapped even
    when the sensors are."""
    rec = _swapped(_trial(motion, standing_s, knee="hinge"), "r")
    ev = swap_evidence("right", rec)
    assert max(ev.shank_residual, ev.thigh_residual) < MIN_RESIDUAL and not ev.swapped


def test_without_a_foot_sensor_there_is_no_evidence(walk):
    rec = walk.with_sensors({n: s for n, s in walk.sensors.items() if n != "calcn_r_imu"})
    assert swap_evidence("right", rec) is None and swap_evidence("left", rec) is not None


@pytest.mark.dataset
def test_the_real_walks():
    """S02 (Xsens MTw) and the x-IMU3 walk as recorded: no leg swapped; each leg with its thigh
    and shank swapped: found (module docstring's residuals)."""
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
