"""pipeline.simulate.subtalar: the free ankle's third angle follows the foot's inversion (eq 1),
one coefficient per leg in the bone-pin range; the model's ankle gets none and draws nothing."""

from __future__ import annotations

import numpy as np

from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.simulate.subtalar import ANKLE_TURN_PER_INVERSION, ankle_turns

GEOMETRY = geometry_from_measures(Measures("f", 1.62))[0]


def test_each_leg_turns_by_its_own_coefficient_times_its_inversion():
    sk = Skeleton.build(GEOMETRY, ankle="free")
    inversion = {"right": np.radians(np.linspace(-3.0, 8.0, 50)),
                 "left": np.radians(np.linspace(5.0, -2.0, 50))}
    turns = ankle_turns(sk, inversion, np.random.default_rng(7))
    assert [i for i, _ in turns] == [sk.q_index(f"{x}_ankle_Y") for x in ("right", "left")]
    ks = []
    for (_, c), side in zip(turns, ("right", "left"), strict=True):
        moved = inversion[side] != 0.0
        k = c[moved] / inversion[side][moved]
        assert np.all(c[~moved] == 0.0)
        np.testing.assert_allclose(k, k[0], rtol=1e-12)  # one coefficient over the walk
        assert ANKLE_TURN_PER_INVERSION[0] <= k[0] <= ANKLE_TURN_PER_INVERSION[1]
        ks.append(k[0])
    assert ks[0] != ks[1]  # drawn per leg


def test_the_models_two_axis_ankle_gets_no_turn_and_draws_nothing():
    rng = np.random.default_rng(7)
    assert ankle_turns(Skeleton.build(GEOMETRY), {"right": np.ones(3), "left": np.ones(3)},
                       rng) == []
    assert rng.uniform() == np.random.default_rng(7).uniform()
