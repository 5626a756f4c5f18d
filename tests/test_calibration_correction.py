"""pipeline.calibration.correction: the knee-AoR correction of one leg as pipeline ik applies it."""

import numpy as np
import pytest

from pipeline.calibration.correction import (
    MIN_EXCURSION,
    carried_correction,
    correct_knee,
    corrected_placement,
    knee_excursion,
    knee_hinge_residual,
    population_correction,
)
from pipeline.errors import InputError
from pipeline.rotations import exp3, normalize, rot_x, rot_y, rot_z


def _knee_about(axis_f, axis_t, n=400, seed=0):
    """Femur and tibia frames of a hip-and-knee flexion whose knee turns exactly about
    ``axis_f`` (femur) = ``axis_t`` (tibia): T = F R0 Rot(a_t, -theta), R0 a_t = a_f."""
    from pipeline.rotations import rotation_aligning

    t = np.linspace(0, 8, n)
    F = rot_z(np.radians(40) * (1 - np.cos(1.5 * t))) @ rot_x(np.radians(5) * np.sin(t))
    theta = np.radians(45) * (1 - np.cos(1.5 * t + 0.4))
    R0 = rotation_aligning(axis_t, axis_f)
    T = F @ R0 @ exp3(-theta[:, None] * np.asarray(axis_t)[None])
    return F, T


def test_correction_carries_the_seen_axis_onto_the_reference_by_hand():
    """Sensors that are 8 and 6 deg off: the knee turns about z in the true frames, so the
    mis-rotated frames see it elsewhere; the closed form rotates each frame back so the axis
    has the reference coordinates (Wang eq 9-13), and the hinge residual about the reference
    vanishes."""
    z = np.array([0.0, 0.0, 1.0])
    F, T = _knee_about(z, z)
    E_F, E_T = exp3([0.1, 0.08, 0.0]), exp3([0.0, -0.1, 0.03])  # frame errors: F_hat = F E_F
    c = correct_knee(F @ E_F, T @ E_T, z, z)
    assert c.applied and c.n_pairs > 10
    np.testing.assert_allclose(c.measured_femur_axis, E_F.T @ z, atol=1e-6)  # seen: E_F^T z
    np.testing.assert_allclose(c.femur_rotation @ z, E_F.T @ z, atol=1e-6)  # R_co V = v
    np.testing.assert_allclose(c.tibia_rotation @ z, E_T.T @ z, atol=1e-6)
    assert np.degrees(c.hinge_residual_before) > 3.0
    assert np.degrees(c.hinge_residual_after) < 1e-3
    # the corrected frames see the reference axis: (F_hat R_co)^T (world axis) = V
    world = (F @ z)[0]
    np.testing.assert_allclose(((F @ E_F @ c.femur_rotation)[0]).T @ world, z, atol=1e-6)
    d = c.as_dict()
    assert d["applied"] and len(d["femur_axis_angle_deg"]) == 3
    assert np.linalg.norm(d["femur_axis_angle_deg"]) == pytest.approx(
        np.degrees(np.arccos(np.clip((E_F.T @ z) @ z, -1, 1))), abs=1e-4)


def test_ipopt_method_agrees_with_the_closed_form_on_an_exact_hinge():
    a = normalize(np.array([-0.15, -0.18, 0.97]))
    F, T = _knee_about(a, a)
    E = exp3([0.05, 0.0, -0.06])
    closed = correct_knee(F @ E, T, a, a)
    nlp = correct_knee(F @ E, T, a, a, method="aor-ipopt")
    np.testing.assert_allclose(nlp.femur_rotation @ a, closed.femur_rotation @ a, atol=1e-4)
    assert np.degrees(nlp.hinge_residual_after) < 0.05


def test_a_still_knee_is_left_uncorrected_with_the_reason():
    F = np.tile(np.eye(3), (200, 1, 1))
    c = correct_knee(F, F, np.array([0, 0, 1.0]), np.array([0, 0, 1.0]))
    assert not c.applied and "could not be estimated" in c.reason
    np.testing.assert_allclose(c.femur_rotation, np.eye(3))
    with pytest.raises(InputError):
        correct_knee(F, F, np.array([0, 0, 1.0]), np.array([0, 0, 1.0]), method="none")
    with pytest.raises(InputError, match="correct_knee_to_axes"):  # it needs measured axes
        correct_knee(F, F, np.array([0, 0, 1.0]), np.array([0, 0, 1.0]), method="functional")


def test_corrected_placement_keeps_the_sensor_where_it_is():
    """R_s = e_hat P and e = e_hat R_co give R_s = e P' with P' = R_co^T P (position kept)."""
    P = np.eye(4)
    P[:3, :3], P[:3, 3] = exp3([0.3, -1.0, 0.2]), [0.05, -0.2, 0.04]
    C = exp3([0.1, 0.05, -0.2])
    e_hat = exp3([0.7, 0.1, 0.3])
    P2 = corrected_placement(P, C)
    np.testing.assert_allclose((e_hat @ C) @ P2[:3, :3], e_hat @ P[:3, :3], atol=1e-12)
    np.testing.assert_allclose(P2[:3, 3], P[:3, 3])


def test_knee_excursion_and_a_knee_that_moves_too_little():
    """The excursion is the largest shank-in-thigh rotation between two samples (here the knee
    swings 10 -> 40 -> 25 deg about a fixed axis: 30 deg); a knee moving 5 deg defines no axis
    for eq 1-8 (MIN_EXCURSION 10 deg) and is left to the caller, with the reason."""
    a = normalize(np.array([0.1, -0.2, 1.0]))
    flex = np.radians(np.concatenate([np.linspace(10, 40, 100), np.linspace(40, 25, 50)]))
    F = np.repeat(rot_x(0.3)[None], flex.size, axis=0)
    T = F @ exp3(-flex[:, None] * a)
    np.testing.assert_allclose(knee_excursion(F, T), np.radians(30.0), atol=1e-9)
    small = F @ exp3(-np.radians(np.linspace(0, 5, 150))[:, None] * a)
    c = correct_knee(F, small, a, a)
    assert np.degrees(MIN_EXCURSION) == 10.0
    assert not c.applied and "moves 5 deg" in c.reason and "10 deg" in c.reason


def test_population_correction_by_hand():
    """No AoR seen: the free knee's pose (tibia aligned with the femur) gets the turn that aligns
    a_T onto a_F, as eq 10-12 would for a knee of the population; the hinge model's own pose
    (that turn already in it) gets none; the femur is never turned."""
    from pipeline.rotations import rotation_aligning

    a_F, a_T = normalize(np.array([-0.15, -0.18, 0.97])), normalize(np.array([0.0, -0.04, 1.0]))
    F = np.repeat(np.eye(3)[None], 50, axis=0)
    free = population_correction(F, F, a_F, a_T, np.eye(3), reason="still")
    R0 = rotation_aligning(a_T, a_F)
    np.testing.assert_allclose(free.tibia_rotation, R0, atol=1e-12)
    np.testing.assert_allclose(free.femur_rotation, np.eye(3), atol=1e-15)
    assert free.applied and free.method == "population" and free.reason == "still"
    assert free.measured_femur_axis is None and free.measured_tibia_axis is None
    hinge = population_correction(F, F @ R0, a_F, a_T, R0, reason="still")
    np.testing.assert_allclose(hinge.tibia_rotation, np.eye(3), atol=1e-12)
    # after it the reference axis is carried alike by both (a knee of the population)
    assert np.degrees(free.hinge_residual_after) < 1e-6


def test_carried_correction_by_hand():
    """A child aligned with its parent inherits R_co itself; a child turned 90 deg about z (its x
    is the parent's y) sees a turn about the parent's x as a turn about its own -y."""
    C = rot_x(0.2)
    np.testing.assert_allclose(carried_correction(C, np.eye(3)), C, atol=1e-15)
    np.testing.assert_allclose(carried_correction(C, rot_z(np.pi / 2)), rot_y(-0.2), atol=1e-15)
    # and it is what keeps the child's pose in the parent: e_parent R_co R_c = e_child C_child
    e, R_c, C = exp3([0.4, -0.2, 0.9]), exp3([0.1, 0.3, -0.2]), exp3([-0.05, 0.15, 0.1])
    np.testing.assert_allclose(e @ C @ R_c, (e @ R_c) @ carried_correction(C, R_c), atol=1e-14)


def test_hinge_residual_is_the_rms_angle_between_the_carried_axes():
    F = np.tile(np.eye(3), (4, 1, 1))
    T = np.stack([rot_x(a) for a in np.radians([0.0, 10.0, 10.0, 0.0])])
    z = np.array([0.0, 0.0, 1.0])
    assert np.degrees(knee_hinge_residual(F, T, z, z)) == pytest.approx(np.sqrt(50.0))


def test_correct_knee_to_axes_by_hand():
    """Eq 10-12 towards given axes: R_co V = v (reference V, measured v), each measured axis
    turned to point right (eq 6 leaves the signs free, also the one of each axis alone)."""
    from pipeline.calibration.correction import correct_knee_to_axes

    F = np.tile(np.eye(3), (10, 1, 1))
    a = np.array([0.0, 0.0, 1.0])
    v_F, v_T = exp3([0.1, 0.0, 0.0]) @ a, exp3([0.0, -0.2, 0.0]) @ a
    c = correct_knee_to_axes(F, F, v_F, v_T, a, a, side="left")
    assert c.applied and c.method == "functional" and c.side == "left"
    np.testing.assert_allclose(c.femur_rotation @ a, v_F, atol=1e-12)
    np.testing.assert_allclose(c.tibia_rotation @ a, v_T, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(c.femur_axis_angle), 0.1, atol=1e-12)
    for signs in ((-1, -1), (1, -1), (-1, 1)):
        flipped = correct_knee_to_axes(F, F, signs[0] * v_F, signs[1] * v_T, a, a)
        np.testing.assert_allclose(flipped.femur_rotation, c.femur_rotation, atol=1e-12)
        np.testing.assert_allclose(flipped.tibia_rotation, c.tibia_rotation, atol=1e-12)


def test_correct_knee_to_axes_refuses_an_axis_far_from_medio_lateral():
    """As eq 1-8's bound (femoral z > 0.6): an axis 60 deg from z means placements that are off;
    the correction is not applied and says why."""
    from pipeline.calibration.correction import correct_knee_to_axes

    F = np.tile(np.eye(3), (10, 1, 1))
    a = np.array([0.0, 0.0, 1.0])
    v = rot_x(np.radians(60.0)) @ a  # z = 0.5
    c = correct_knee_to_axes(F, F, v, a, a, a)
    assert not c.applied and "z = 0.50" in c.reason
    np.testing.assert_array_equal(c.femur_rotation, np.eye(3))
    assert correct_knee_to_axes(F, F, rot_x(np.radians(50.0)) @ a, a, a, a).applied
