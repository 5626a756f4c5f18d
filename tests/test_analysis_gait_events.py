"""pipeline.analysis.gait_events: rests, swings and contacts of a simulated foot with known events
(pipeline.simulate.foot_walk), a shank, standing still, and the real S02 walk against Vicon."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.analysis.gait_events import gait_events, rest_periods
from pipeline.simulate.foot_walk import foot_walk

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
                                  ("left", "tibia_l_imu", "shank")):  # fmt: skip
        s = rec.sensors[sensor]
        ev = gait_events(s.gyr, s.acc, rec.rate_hz, segment)
        ic = truth[side]["ic"]
        errors = [abs(k / 100.0 - ic[np.argmin(np.abs(ic - k / 100.0))]) for k in ev.ic]
        errors = [e for e in errors if e < 0.15]
        assert len(errors) >= 5 and np.median(errors) < 0.030, (side, errors)
