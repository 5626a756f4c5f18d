"""pipeline.analysis.gait_events: rests, swings and contacts of a simulated foot with known events
(pipeline.simulate.foot_walk), a shank, standing still, and the real S02 walk against Vicon."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.analysis.gait_events import gait_events, rest_periods
from pipeline.simulate.foot_walk import Pace, foot_walk

S02 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "gaittoolbox_s02"


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_contacts_of_a_simulated_foot(seed):
    """Every swing found; IC within 10 ms and FC within 10 ms of the truth (the first IC, from
    standing, has no swing before it)."""
    w = foot_walk(strides=6, seed=seed, turns_deg=(0, 60, 0, -90))
    ev = gait_events(w.gyr, w.acc, w.rate_hz)
    assert len(ev.ic) == len(ev.fc) == len(ev.swing) == 6
    assert np.abs(ev.ic / w.rate_hz - w.ic[1:]).max() < 0.010
    assert np.abs(ev.fc / w.rate_hz - w.fc).max() < 0.010
    assert np.all(ev.fc < ev.swing) and np.all(ev.swing < ev.ic)
    assert ev.trajectory is None  # every swing strong: the foot's path was not needed


@pytest.mark.parametrize("speed", [0.6, 1.0, 1.4, 1.8, 2.2])
@pytest.mark.parametrize("rate_hz", [100.0, 200.0])
def test_every_stride_at_every_speed(speed, rate_hz):
    """From a slow walk to a fast one whose foot never rests by the fixed thresholds (at 1.8-2.2
    m/s its stillest 50 ms in stance turn at up to 0.8 rad/s, :meth:`Pace.at`): every swing found,
    IC within 10 ms (measured: 0.6-5.2), stride lengths within 1 % (0.04-0.42 %)."""
    from pipeline.analysis.foot_trajectory import foot_trajectory
    from pipeline.analysis.strides import foot_strides

    pace = Pace.at(speed)
    w = foot_walk(strides=10, pace=pace, rate_hz=rate_hz, seed=0, turns_deg=(0, 0, 90))
    ev = gait_events(w.gyr, w.acc, rate_hz)
    assert len(ev.ic) == 10
    assert np.abs(ev.ic / rate_hz - w.ic[1:]).max() < 0.010
    path = ev.trajectory or foot_trajectory(w.gyr, w.acc, rate_hz, ev.rests)
    lengths = [s.stride_length_m for s in foot_strides("right", w.time, ev, path)]
    assert len(lengths) == 9
    assert np.abs(np.array(lengths) / pace.length_m - 1).max() < 0.01


def test_the_swings_sign_is_the_walks_not_the_shuffles():
    """Ten small shuffles (a lift and a set-down, the larger turn backwards) before four strides:
    counted by sign the shuffles outvoted the strides and flipped both feet; by their turns the
    strides' swings (60 deg each) decide."""
    from pipeline.analysis.gait_events import sagittal_rate

    shuffle = [-np.radians(8.0) / 0.2] * 20 + [np.radians(5.0) / 0.2] * 20 + [0.0] * 30
    stride = [-np.radians(40.0) / 0.3] * 30 + [np.radians(60.0) / 0.25] * 25 + [0.0] * 40
    w = shuffle * 10 + stride * 4  # shuffles -8 deg then +5; strides' push-off -40, swing +60
    w = np.array(w)
    rests = np.array([(a, b) for a, b in _zero_runs(w) if b - a >= 10])
    axis = np.array([0.0, 1.0, 0.0])
    signed, found = sagittal_rate(np.outer(w, axis), rests, np.array([0.0, 0.0, 1.0]))
    assert found @ axis > 0.99 and signed.max() > 4.0  # the swings positive


def _zero_runs(w: np.ndarray) -> list[tuple[int, int]]:
    from pipeline.io.gaps import true_runs

    return true_runs(w == 0.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_turns_on_the_spot_do_not_take_the_sagittal_axis(seed):
    """Short steps turning 120 deg one way, then the other: the turns about the vertical outweigh
    the flexion (the plain principal axis of the gyroscope found 3 of the 6 swings, each turn
    the other way signed as a swing's opposite); the horizontal part's finds all six."""
    w = foot_walk(strides=6, seed=seed, turns_deg=(120, -120) * 3, pace=Pace(length_m=0.4))
    ev = gait_events(w.gyr, w.acc, w.rate_hz)
    assert len(ev.ic) == 6
    assert np.abs(ev.ic / w.rate_hz - w.ic[1:]).max() < 0.010
    vertical = w.acc[:100].mean(axis=0) / np.linalg.norm(w.acc[:100].mean(axis=0))
    assert abs(ev.axis @ vertical) < np.sin(np.radians(1.0))  # horizontal


@pytest.mark.parametrize("length_m, steps", [(0.4, 6), (0.05, 0)])
def test_a_step_that_barely_pitches_the_foot_counts_when_the_foot_moved(monkeypatch, length_m,
                                                                        steps):
    """Feet pitched a quarter as much as in walking (swing peak 1.9 rad/s, below MIN_SWING_RATE,
    as in a pivot turn): steps of 0.4 m are found, IC within 10 ms; shuffles of 5 cm are not."""
    import pipeline.simulate.foot_walk as fw

    monkeypatch.setattr(fw, "LOBES", tuple((a, b, turn / 4) for a, b, turn in fw.LOBES))
    w = foot_walk(strides=6, seed=1, pace=Pace(length_m=length_m), clearance_m=0.02)
    ev = gait_events(w.gyr, w.acc, w.rate_hz)
    assert len(ev.ic) == steps
    if steps:
        assert np.abs(ev.ic / w.rate_hz - w.ic[1:]).max() < 0.010
    # the path computed for the weak swings is the one the gait analysis would compute, kept
    from pipeline.analysis.foot_trajectory import foot_trajectory

    again = foot_trajectory(w.gyr, w.acc, w.rate_hz, ev.rests)
    np.testing.assert_array_equal(ev.trajectory.position, again.position)


def test_the_sign_does_not_depend_on_the_mounting():
    """The same walk with the sensor upside down (its axes negated in pairs: a half turn)."""
    w = foot_walk(strides=4, seed=3)
    flip = np.diag([1.0, -1.0, -1.0])
    a = gait_events(w.gyr, w.acc, w.rate_hz)
    b = gait_events(w.gyr @ flip, w.acc @ flip, w.rate_hz)
    np.testing.assert_allclose(a.ic, b.ic)
    np.testing.assert_allclose(a.axis @ flip, b.axis, atol=1e-9)


def test_standing_still_has_rests_and_no_event():
    rng = np.random.default_rng(0)
    gyr = rng.normal(0, 0.01, (1000, 3))
    acc = np.array([0.0, 0.0, 9.81]) + rng.normal(0, 0.05, (1000, 3))
    assert rest_periods(gyr, acc, 100.0).tolist() == [[0, 1000]]
    ev = gait_events(gyr, acc, 100.0)
    assert len(ev.ic) == len(ev.fc) == 0


def test_a_shank_gives_one_ic_per_swing_peak():
    """A shank-like signal: forward rotation through stance and a swing peak each stride."""
    t = np.arange(0, 10, 0.01)
    w = 1.0 + 4.0 * np.exp(-(((t % 1.1) - 0.8) / 0.08) ** 2) - 1.5 * np.exp(
        -(((t % 1.1) - 1.0) / 0.03) ** 2) - 1.5 * np.exp(-(((t % 1.1) - 0.6) / 0.03) ** 2)
    gyr = np.column_stack([0.1 * w, w, 0.05 * w])
    acc = np.tile([0.0, 0.0, 9.81], (len(t), 1))
    ev = gait_events(gyr, acc, 100.0, "shank")
    assert len(ev.ic) >= 8
    phase = (ev.ic / 100.0 - 1.0) % 1.1  # the IC dip at 1.0 s into each 1.1 s cycle
    assert np.minimum(phase, 1.1 - phase).max() < 0.02
    with pytest.raises(ValueError, match="segment 'hand'"):
        gait_events(gyr, acc, 100.0, "hand")


def test_the_ximu3_walk_feet_and_shanks_agree():
    """The shipped x-IMU3 recording (no truth): two short walks and turns on the spot. Three or
    more of each foot's initial contacts are its shank sensor's, found independently, within
    60 ms (measured: 0-70 ms on the right, 3 of 5 within 50 ms on the left; the right foot's
    plain principal axis was 5 deg from the vertical and found no swing), and the feet
    alternate."""
    from pipeline.io.formats import read_recording

    rec = read_recording("example:ximu3_lower_body")
    ics = {}
    for side in ("r", "l"):
        foot, shank = rec.sensors[f"calcn_{side}_imu"], rec.sensors[f"tibia_{side}_imu"]
        ic = gait_events(foot.gyr, foot.acc, rec.rate_hz).ic / rec.rate_hz
        by_shank = gait_events(shank.gyr, shank.acc, rec.rate_hz, "shank").ic / rec.rate_hz
        assert len(ic) >= 4, side
        agree = [np.abs(by_shank - t).min() < 0.060 for t in ic]
        assert sum(agree) >= 3, (side, ic, by_shank)
        ics[side] = ic
    sides = [s for _, s in sorted([(t, s) for s in ics for t in ics[s]])]
    assert sum(a == b for a, b in zip(sides[:-1], sides[1:], strict=True)) <= 1, sides


@pytest.mark.dataset
def test_s02_initial_contacts_against_the_heel_markers():
    """The real walk: each foot's and each shank's ICs within 30 ms (median) of Zeni et al.
    2008's heel strikes from the Vicon heel and sacrum (the issue's target; 7-20 ms measured,
    bench_gait)."""
    if not S02.exists():
        pytest.skip("../shared/data/gaittoolbox_s02 not present")
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_gait import S02_MAP, vicon_events

    from pipeline.io.formats import read_recording

    rec = read_recording(S02 / "imu", S02_MAP)
    truth = vicon_events(S02)
    for side, sensor, segment in (("right", "calcn_r_imu", "foot"), ("left", "calcn_l_imu", "foot"),
                                  ("right", "tibia_r_imu", "shank"),
                                  ("left", "tibia_l_imu", "shank")):
        s = rec.sensors[sensor]
        ev = gait_events(s.gyr, s.acc, rec.rate_hz, segment)
        ic = truth[side]["ic"]
        errors = [abs(k / 100.0 - ic[np.argmin(np.abs(ic - k / 100.0))]) for k in ev.ic]
        errors = [e for e in errors if e < 0.15]
        assert len(errors) >= 5 and np.median(errors) < 0.030, (side, errors)
        if (side, segment) == ("right", "foot"):  # its pivot in the turn: peak 1.3 rad/s, 30 cm
            assert np.abs(ev.ic / 100.0 - 15.48).min() < 0.020
