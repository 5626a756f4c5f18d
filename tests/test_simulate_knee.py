"""The simulated walk's knee (pipeline.simulate.knee): a free knee that is not a hinge (its
adduction and rotation follow flexion and the stride, eq 1), the flexion that reaches a given
hip-to-ankle distance exactly, and a hinge that stays a hinge."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analysis.joint_angles import joint_angles
from pipeline.errors import InputError
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.simulate.knee import KNEE_COUPLING, draw_knee, flexion_reaching, hip_ankle_distance_sq
from pipeline.simulate.model import simulate_trial

GEOMETRY = geometry_from_measures(Measures("m", 1.75))[0]


@pytest.fixture(scope="module")
def free():
    return Skeleton.build(GEOMETRY, knee="free", root="freeflyer")


def test_a_hinge_draws_nothing_and_has_no_stride_terms():
    sk = Skeleton.build(GEOMETRY, knee="hinge", root="freeflyer")
    rng = np.random.default_rng(0)
    knee = draw_knee(sk, "right", rng)
    assert knee.coupled == () and knee.coupling == ()
    assert rng.uniform() == np.random.default_rng(0).uniform()  # the stream is untouched
    assert not np.any(knee.stride_angles(np.linspace(0, 7, 50), np.ones(50)))


def test_a_free_knee_draws_its_sizes_within_the_ranges(free):
    for seed in range(5):
        knee = draw_knee(free, "left", np.random.default_rng(seed))
        c_x, c_y, screw = knee.coupling
        lo, hi = KNEE_COUPLING["adduction"]
        assert lo <= abs(c_x) <= hi
        assert KNEE_COUPLING["rotation"][0] <= c_y <= KNEE_COUPLING["rotation"][1]
        lo, hi = np.deg2rad(KNEE_COUPLING["screw_home_deg"])
        assert lo <= screw <= hi


@pytest.mark.parametrize("extra", [(0.0, 0.0), (0.03, -0.05), (-0.035, 0.07)])
def test_the_flexion_reaches_the_distance_exactly(free, extra):
    knee = draw_knee(free, "right", np.random.default_rng(1))
    q = free.neutral()
    knee.set(q, 0.6, np.array(extra))
    d2 = hip_ankle_distance_sq(free, q, "right")
    q[knee.flexion] = 0.3  # the last sample's flexion, on the same (flexed) side
    flexion_reaching(free, knee, q, d2, np.array(extra), "right")
    assert q[knee.flexion] == pytest.approx(0.6, abs=1e-9)
    assert hip_ankle_distance_sq(free, q, "right") == pytest.approx(d2, abs=1e-13)
    c_x = knee.coupling[0]
    assert q[knee.coupled[0]] == pytest.approx(c_x * 0.6 + extra[0], abs=1e-9)


def test_a_leg_too_short_for_the_distance_is_refused(free):
    knee = draw_knee(free, "right", np.random.default_rng(1))
    q = free.neutral()
    with pytest.raises(InputError, match="cannot reach"):
        flexion_reaching(free, knee, q, 1.1 * knee.sides[0][3], np.zeros(2), "right")


def test_the_walks_knee_is_not_a_hinge(free, monkeypatch):
    import pipeline.simulate.walk as walk
    from pipeline.simulate.knee import SCREW_HOME_RAD
    from pipeline.simulate.motions import ramp

    knees = {}

    def drawn(skeleton, side, rng):
        knees[side] = draw_knee(skeleton, side, rng)
        return knees[side]

    monkeypatch.setattr(walk, "draw_knee", drawn)
    trial = simulate_trial(free, "walk", duration_s=8.0, seed=2, standing_s=1.0)
    angles = joint_angles(trial.skeleton, trial.q)
    s, _, _, tau = ramp(trial.time, 1.0)
    standing, walking = slice(0, 90), slice(300, None)
    for side in ("right", "left"):
        k = angles[f"{side}_knee_flexion"]
        r, b = angles[f"{side}_knee_rotation"], angles[f"{side}_knee_adduction"]
        # standing: no rotation or adduction beyond the (zero) flexion's
        assert np.abs(r[standing]).max() < 1e-6 and np.abs(b[standing]).max() < 1e-6
        # eq (1) in the ISB angles: internal rotation and adduction (both legs alike)
        c_x, c_y, screw = knees[side].coupling
        extra = knees[side].stride_angles(2 * np.pi * tau / trial.walk.T, s)
        np.testing.assert_allclose(b, c_x * k + extra[:, 0], atol=1e-6)
        np.testing.assert_allclose(r, c_y * k + screw * (1 - np.exp(-k / SCREW_HOME_RAD))
                                   + extra[:, 1], atol=1e-6)
        # sizes as the biplane study's (module docstring), over the walk
        r, b, k = np.degrees(r[walking]), np.degrees(b[walking]), np.degrees(k[walking])
        assert 4.0 < np.ptp(r) < 20.0 and 1.0 < np.ptp(b) < 8.0
        # not a function of flexion alone: at one flexion, different rotations
        bins = np.digitize(k, np.arange(0, 70, 5))
        spread = [np.ptp(r[bins == i]) for i in np.unique(bins) if np.sum(bins == i) > 20]
        assert np.median(spread) > 1.0
