"""pipeline.process.knee_correction: the correction registry and the decisions taken for every
method alike."""

import numpy as np
import pytest

from pipeline.calibration.correction import KneeCorrection
from pipeline.process.functional import KneeCalibration
from pipeline.process.knee_correction import (
    CORRECTIONS,
    KneeInputs,
    apply_correction,
    choose_correction,
)
from pipeline.rotations import exp3, rot_z

A_F = np.array([-0.148, -0.182, 0.972]) / np.linalg.norm([-0.148, -0.182, 0.972])
A_T = np.array([0.004, -0.036, 0.999]) / np.linalg.norm([0.004, -0.036, 0.999])


def _knee(n=600, tibia_turn=(0.0, 0.0, 0.0), **kw) -> KneeInputs:
    """A knee flexing 0-60 deg about the reference axis; the tibia's frame as its sensor sees
    it, turned in itself by ``tibia_turn`` (a misplaced sensor: ``e_T M``)."""
    from pipeline.rotations import rotation_aligning

    flex = np.radians(30.0) * (1 - np.cos(np.linspace(0, 6 * np.pi, n)))
    F = np.tile(np.eye(3), (n, 1, 1))
    T = np.stack([exp3(-a * A_F) for a in flex]) @ rotation_aligning(A_T, A_F)
    T = T @ exp3(np.asarray(tibia_turn))
    return KneeInputs("right", F, T, A_F, A_T, rotation_aligning(A_T, A_F), np.eye(3), np.eye(3),
                      100.0, **kw)


def test_the_registry_names_the_options_methods():
    from pipeline.calibration.conventions import CORRECTIONS as NAMES

    assert set(CORRECTIONS) == set(NAMES) - {"none"}


def test_a_knee_seen_as_the_reference_needs_no_turn():
    c = choose_correction(_knee(), "aor", notes := [])
    assert isinstance(c, KneeCorrection) and c.applied and c.method == "aor"
    assert np.degrees(np.linalg.norm(c.femur_axis_angle)) < 0.5 and not notes


def test_unaligned_headings_and_a_still_knee_fall_back_to_the_population():
    c = choose_correction(_knee(headings_shared=False), "aor", notes := [])
    assert c.method == "population" and "headings were not aligned" in c.reason
    still = _knee(n=300)
    still = KneeInputs(*[getattr(still, f) for f in ("side", "femur_R")],
                       np.tile(still.tibia_R[0], (300, 1, 1)),
                       *[getattr(still, f) for f in ("axis_femur", "axis_tibia",
                                                     "pose_tibia_in_femur", "placement_thigh",
                                                     "placement_shank", "rate_hz")])
    c = choose_correction(still, "aor", notes)
    assert c.method == "population" and any("corrected as the reference" in n for n in notes)


def test_functional_without_a_trusted_calibration_says_so_and_uses_eq_1_8():
    untrusted = KneeCalibration("right", A_F, A_T, 40.0, 0.6, False, 30.0, False, "not trusted")
    c = choose_correction(_knee(calibration=untrusted), "functional", notes := [])
    assert c.method == "aor" and "not trusted; corrected by eq 1-8" in notes[0]
    trusted = KneeCalibration("right", A_F, A_T, 1.0, 0.1, True, 0.0, True, "", True)
    assert choose_correction(_knee(calibration=trusted), "functional", []).method == "functional"


def test_the_correction_becomes_part_of_the_placements_and_the_foot_follows():
    c = choose_correction(_knee(tibia_turn=np.array([0.0, 0.2, 0.0])), "aor", [])
    assert np.degrees(np.linalg.norm(c.tibia_axis_angle)) > 5.0
    pose = {"right_femur": np.eye(3), "right_tibia": np.eye(3), "right_foot": rot_z(0.1)}
    placements = {f"right_{s}_imu": np.eye(4) for s in ("femur", "tibia", "foot")}
    out = apply_correction(placements, c, pose)
    np.testing.assert_allclose(out["right_tibia_imu"][:3, :3], c.tibia_rotation.T, atol=1e-12)
    assert not np.allclose(out["right_foot_imu"][:3, :3], np.eye(3))
    with pytest.raises(KeyError):
        CORRECTIONS["wang"]


def _half_turned(turn_deg: float) -> KneeInputs:
    """The misplaced tibia sensor of ``_knee``, whose error changes by ``turn_deg`` about the
    tibia's long axis half-way through the walk (a sensor slipping on the shank)."""
    k = _knee(tibia_turn=(0.0, np.radians(8.0), 0.0))
    T = k.tibia_R.copy()
    T[len(T) // 2:] = T[len(T) // 2:] @ exp3(np.array([0.0, np.radians(turn_deg), 0.0]))
    return KneeInputs(k.side, k.femur_R, T, *[getattr(k, f) for f in (
        "axis_femur", "axis_tibia", "pose_tibia_in_femur", "placement_thigh", "placement_shank",
        "rate_hz")])


def test_a_correction_the_two_halves_agree_on_is_applied():
    c = choose_correction(_half_turned(0.0), "aor", notes := [])
    assert c.applied and not notes
    assert np.degrees(np.linalg.norm(c.tibia_axis_angle)) > 5.0  # the 8 deg turn is corrected


def test_a_correction_the_data_do_not_determine_is_not_applied():
    from pipeline.calibration.correction import correction_spread
    from pipeline.process.knee_correction import MAX_SPREAD_DEG

    k = _half_turned(12.0)
    spread = np.degrees(correction_spread(k.femur_R, k.tibia_R, A_F, A_T))
    assert spread > MAX_SPREAD_DEG
    c = choose_correction(k, "aor", notes := [])
    assert not c.applied and np.allclose(c.tibia_rotation, np.eye(3))
    assert len(notes) == 1 and "do not determine" in notes[0] and f"{spread:.1f} deg" in notes[0]
    assert c.method == "aor"  # not replaced by the population's knee
