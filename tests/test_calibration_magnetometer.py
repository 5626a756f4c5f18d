"""pipeline.calibration.magnetometer: a sensor's field against the others' and over time."""

import numpy as np

from pipeline.calibration.magnetometer import MAX_DISTURBED, field_trust

N = 1000
UP = np.tile([0.0, 0.0, 1.0], (N, 1))
FIELD = np.array([20.0, 0.0, -40.0])  # dip -63 deg


def test_sensors_in_the_common_field_are_trusted_one_bent_by_a_magnet_is_not():
    rng = np.random.default_rng(0)
    ok = {f"s{k}": (FIELD + rng.normal(0, 0.3, (N, 3)), UP) for k in range(4)}
    bent = np.tile(FIELD, (N, 1))
    bent[:, :2] *= np.linspace(1.0, 3.0, N)[:, None]  # strength and dip both leave the field's
    out = field_trust({**ok, "near_magnet": (bent, UP)})
    assert all(out[k].trusted for k in ok)
    assert not out["near_magnet"].trusted and out["near_magnet"].disturbed > MAX_DISTURBED
    assert "disturbed" in out["near_magnet"].evidence
    assert abs(out["s0"].reference_dip_deg - np.degrees(np.arcsin(-40 / np.hypot(20, 40)))) < 1


def test_a_dead_magnetometer_is_not_trusted_and_a_short_disturbance_is_tolerated():
    field = np.tile(FIELD, (N, 1))
    brief = field.copy()
    brief[:50] *= 2.0  # 5 % of the samples
    out = field_trust({"a": (field, UP), "b": (field, UP), "dead": (np.zeros((N, 3)), UP),
                       "brief": (brief, UP)})
    assert not out["dead"].trusted and "no field" in out["dead"].evidence
    assert out["brief"].trusted and 0.04 < out["brief"].disturbed < 0.06
