"""pipeline.process.joint_headings: which rows a joint's heading may jump across, and which rows
its fits take (the joints' heading estimators themselves: test_process_heading_alignment)."""

import dataclasses

import numpy as np

from pipeline.io.gaps import Missing
from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.joint_headings import breaks_of, own_rows


def _rec(missing: Missing) -> Recording:
    n = 100
    names = ("pelvis_imu", "femur_r_imu", "tibia_r_imu", "calcn_r_imu", "tibia_l_imu")
    rec = Recording(np.arange(n) / 100.0, 100.0,
                    {k: SensorSignals(gyr=np.zeros((n, 3))) for k in names})
    return dataclasses.replace(rec, missing=missing)


def test_a_restarted_filter_breaks_the_joints_at_and_below_it_on_its_chain():
    spans = {"femur_r_imu": ((10, 20),), "tibia_l_imu": ((50, 60),), "calcn_r_imu": ((70, 80),)}
    rec = _rec(Missing(spans, restarted=frozenset({"femur_r_imu", "tibia_l_imu"})))
    assert breaks_of(rec, "pelvis") is None  # nothing above the pelvis restarted
    for seg in ("right_femur", "right_tibia", "right_foot"):  # the right thigh's filter restarted
        rows = np.flatnonzero(breaks_of(rec, seg))
        assert rows.tolist() == list(range(10, 20)), seg  # the foot's gap: not a restart
    assert np.flatnonzero(breaks_of(rec, "left_tibia")).tolist() == list(range(50, 60))
    assert breaks_of(rec, "left_femur") is None  # the left shank is below it
    assert breaks_of(_rec(Missing(spans)), "right_foot") is None  # the vendor's: no restart


def test_own_rows_are_the_samples_both_sensors_have():
    rec = _rec(Missing({"tibia_r_imu": ((30, 40),)}))
    assert own_rows(rec, "pelvis", "right_femur") == slice(None)
    rows = own_rows(rec, "right_femur", "right_tibia")
    assert len(rows) == 90 and not set(range(30, 40)) & set(rows.tolist())
