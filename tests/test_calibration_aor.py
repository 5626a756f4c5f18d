"""Knee AoR (Wang eq 1-8) and its orientation correction (eq 9-13) on cases with known truth."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from pipeline.calibration.aor import (
    KneeAoR,
    apply_correction,
    correction_rotations,
    elevation_coordinate,
    flexion_coordinate,
    frame_pairs,
    knee_aor,
    population_aor,
    projection_angles,
    select_windows,
)
from pipeline.errors import InputError
from pipeline.rotations import (
    angle_between,
    exp3,
    log3,
    normalize,
    rot_x,
    rot_y,
    rot_z,
    rotation_aligning,
)

DEG = np.pi / 180


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    return exp3(normalize(rng.normal(size=3)) * rng.uniform(0.3, 3.0))


def _hinge(rng, *, n=3000, noise_deg=0.0, lab=None, abd_deg=3.0, hip_sign=1.0):
    """Supine hip flexion with a knee hinge.

    Femur: hip flexion about the femoral z axis (0..75 deg, 6 cycles with rests) plus a little
    abduction; tibia: rotation about the knee axis ``a_F`` (femoral frame) by minus the knee
    flexion (0..95 deg), starting from ``T0``; returns frames and the true axes.
    """
    t = np.arange(n) / 100.0
    cycle = 0.5 * (1 - np.cos(2 * np.pi * t / 5.0))
    hip = 75 * DEG * cycle**1.3
    knee = 95 * DEG * cycle
    abd = abd_deg * DEG * np.sin(2 * np.pi * t / 7.0)
    lab = np.eye(3) if lab is None else lab
    F = lab @ rot_z(hip_sign * hip) @ rot_x(abd)
    a_F = normalize(np.array([-0.15, -0.08, 1.0]))
    T0 = rot_y(8 * DEG) @ rot_x(-4 * DEG)
    T = F @ exp3(-knee[:, None] * a_F) @ T0
    if noise_deg:
        F = F @ exp3(rng.normal(scale=noise_deg * DEG, size=(n, 3)))
        T = T @ exp3(rng.normal(scale=noise_deg * DEG, size=(n, 3)))
    return F, T, a_F, T0.T @ a_F


def test_hinge_axis_recovered_exactly_without_noise():
    F, T, a_F, a_T = _hinge(np.random.default_rng(0))
    aor = knee_aor(F, T)
    assert angle_between(aor.femur_axis, a_F) < 1e-9
    assert angle_between(aor.tibia_axis, a_T) < 1e-9
    assert aor.sd_angle_femur < 1e-9 and aor.sd_angle_tibia < 1e-9
    assert aor.n_pairs > 100
    assert np.all(aor.femur_axes[:, 2] > 0)  # flexion and extension pairs both point right


def test_hinge_with_noise_cluster_offset_and_lab_rotation():
    rng = np.random.default_rng(1)
    lab = _random_rotation(rng)
    F, T, a_F, a_T = _hinge(rng, noise_deg=0.5, lab=lab)
    cluster = _random_rotation(rng)  # tibia marker cluster: tibia frame times a constant offset
    aor = knee_aor(F, T @ cluster, tibia_frames_R=T)
    assert np.degrees(angle_between(aor.femur_axis, a_F)) < 0.3
    assert np.degrees(angle_between(aor.tibia_axis, a_T)) < 0.3
    assert 0 < aor.sd_angle_femur < 3 * DEG
    # the world frame does not matter
    Q = _random_rotation(rng)
    aor_q = knee_aor(Q @ F, Q @ T @ cluster, tibia_frames_R=Q @ T)
    assert np.array_equal(aor_q.pairs, aor.pairs)
    np.testing.assert_allclose(aor_q.femur_axis, aor.femur_axis, atol=1e-9)
    np.testing.assert_allclose(aor_q.tibia_axis, aor.tibia_axis, atol=1e-9)
    np.testing.assert_allclose(aor_q.world_axes, aor.world_axes @ Q.T, atol=1e-9)


def test_eq2_eq3_axis_angle_and_flip_by_hand():
    # femur still (identity); tibia turns about femoral z by +30 deg (extension) then -30 deg.
    F = np.repeat(np.eye(3)[None], 4, axis=0)
    T = np.stack([np.eye(3), rot_z(30 * DEG), np.eye(3), rot_z(-30 * DEG)])
    aor = knee_aor(F, T, pairs=np.array([[0, 1], [2, 3]]), rel_angle_threshold=0.0)
    np.testing.assert_allclose(aor.angles, [30 * DEG, 30 * DEG])
    np.testing.assert_allclose(aor.femur_axes, [[0, 0, 1], [0, 0, 1]], atol=1e-12)  # flipped
    np.testing.assert_allclose(aor.femur_axis, [0, 0, 1], atol=1e-12)


def test_eq6_angle_weighted_mean_by_hand():
    v1 = normalize(np.array([0.2, 0.0, 1.0]))
    v2 = normalize(np.array([0.0, -0.3, 1.0]))
    F = np.repeat(np.eye(3)[None], 4, axis=0)
    T = np.stack([np.eye(3), exp3(0.4 * v1), np.eye(3), exp3(0.8 * v2)])
    aor = knee_aor(F, T, pairs=np.array([[0, 1], [2, 3]]), rel_angle_threshold=0.0)
    np.testing.assert_allclose(aor.femur_axis, normalize(0.4 * v1 + 0.8 * v2), atol=1e-12)
    # eq 7-8 with tibia = identity at frames 0 and 2: tibial axes equal the world axes
    np.testing.assert_allclose(aor.tibia_axis, aor.femur_axis, atol=1e-12)
    # dispersion: angle-weighted RMS of the deviations
    d = angle_between(np.stack([v1, v2]), aor.femur_axis)
    assert aor.sd_angle_femur == pytest.approx(np.sqrt((0.4 * d[0] ** 2 + 0.8 * d[1] ** 2) / 1.2))


def test_small_angles_and_left_axes_dropped():
    F = np.repeat(np.eye(3)[None], 6, axis=0)
    T = np.stack(
        [np.eye(3), rot_z(40 * DEG), np.eye(3), rot_z(10 * DEG), np.eye(3), rot_x(40 * DEG)]
    )
    pairs = np.array([[0, 1], [2, 3], [4, 5]])
    aor = knee_aor(F, T, pairs=pairs)  # 10 deg < 0.5 * 40 deg; x axis has z = 0 < 0.6
    assert aor.n_pairs == 1 and np.array_equal(aor.pairs, [[0, 1]])
    with pytest.raises(InputError, match="no frame pair"):
        knee_aor(F, T, pairs=pairs, min_angle=50 * DEG)


def test_select_windows_and_pairs_by_hand():
    c = np.concatenate([np.arange(11), np.arange(9, -1, -1)]).astype(float)  # 0..10..0
    # band [1.5, 8.5]: values 2..8 rising (indices 2-8) and falling (12-18)
    assert select_windows(c, min_length=5) == [(2, 9), (12, 19)]
    assert select_windows(c, min_length=8) == []
    valid = np.ones(c.size, bool)
    valid[5] = False  # a missing sample splits the rising run
    assert select_windows(c, valid, min_length=3) == [(2, 5), (6, 9), (12, 19)]
    p = frame_pairs([(0, 10)])
    np.testing.assert_array_equal(p, np.stack([np.arange(5), np.arange(5) + 5], axis=1))
    assert frame_pairs([(0, 10)], step=8).tolist() == [[0, 8], [1, 9]]


def test_flexion_and_elevation_coordinates():
    rng = np.random.default_rng(2)
    lab = _random_rotation(rng)
    F, T, _, _ = _hinge(rng, lab=lab, abd_deg=0.0)
    hip = np.arccos(np.clip(np.einsum("ni,ni->n", F[:, :, 1], F[0][:, 1][None]), -1, 1))
    phi = flexion_coordinate(F)
    # planar flexion: the coordinate is the hip flexion angle up to sign and offset
    np.testing.assert_allclose(np.abs(phi - phi[0]), hip, atol=1e-9)
    # elevation = sin(hip flexion from rest): rest found at the knee-extended end
    np.testing.assert_allclose(elevation_coordinate(F, T), np.sin(hip), atol=1e-9)
    # hip moving the other way round about the lab (and the SVD normal's sign is arbitrary)
    Fm, Tm, _, _ = _hinge(rng, lab=lab, abd_deg=0.0, hip_sign=-1.0)
    np.testing.assert_allclose(elevation_coordinate(Fm, Tm), np.sin(hip), atol=1e-9)
    # with abduction the flexion coordinate still tracks hip flexion closely
    F2, T2, _, _ = _hinge(rng, lab=lab, abd_deg=3.0)
    hip2 = np.arccos(np.clip(np.einsum("ni,ni->n", F2[:, :, 1], F2[0][:, 1][None]), -1, 1))
    assert abs(np.corrcoef(flexion_coordinate(F2), hip2)[0, 1]) > 0.999
    np.testing.assert_allclose(elevation_coordinate(F2, T2), np.sin(hip2), atol=0.06)


def test_population_projection_sd_by_hand():
    def fake(vf, vt):
        z = np.zeros((0, 3))
        return KneeAoR(vf, vt, 0, 0.0, 0.0, np.zeros((0, 2), int), np.zeros(0), z, z, z)

    angles = np.array([-5.0, 0.0, 5.0]) * DEG
    vf = [np.array([np.sin(a), 0.0, np.cos(a)]) for a in angles]  # transverse only
    vt = [np.array([0.0, np.sin(a), np.cos(a)]) for a in 2 * angles]  # frontal only
    pop = population_aor([fake(f, t) for f, t in zip(vf, vt, strict=True)])
    np.testing.assert_allclose(pop.femur_axis, [0, 0, 1], atol=1e-12)
    assert pop.sd_femur_transverse == pytest.approx(5 * DEG)
    assert pop.sd_femur_frontal == pytest.approx(0.0, abs=1e-12)
    assert pop.sd_tibia_frontal == pytest.approx(10 * DEG)
    np.testing.assert_allclose(pop.femur_transverse, angles)
    tr, fr = projection_angles(np.array([0.1, 0.2, 1.0]))
    assert tr == pytest.approx(np.arctan(0.1)) and fr == pytest.approx(np.arctan(0.2))


def test_eq10_12_correction_by_hand():
    v = np.array([0.0, np.sin(10 * DEG), np.cos(10 * DEG)])  # measured, tilted 10 deg up
    z = np.zeros((0, 3))
    measured = KneeAoR(v, v, 0, 0.0, 0.0, np.zeros((0, 2), int), np.zeros(0), z, z, z)
    R_f, R_t = correction_rotations(measured, np.array([0, 0, 1.0]), np.array([0, 0, 1.0]))
    # R_co maps the reference (z) onto the measured axis: rotation about x by -10 deg
    np.testing.assert_allclose(R_f, rot_x(-10 * DEG), atol=1e-12)
    np.testing.assert_allclose(R_t, rot_x(-10 * DEG), atol=1e-12)
    # eq 13: right-multiplication
    seq = np.stack([np.eye(3), rot_z(0.3)])
    np.testing.assert_allclose(apply_correction(seq, R_f), seq @ R_f)


def test_correction_recovers_known_misalignment():
    rng = np.random.default_rng(3)
    F, T, a_F, a_T = _hinge(rng, noise_deg=0.2, lab=_random_rotation(rng))
    # IMC frames with calibration errors (rotations in each segment's own frame) that tilt the
    # axis: 8 and 6 deg about axes perpendicular to the femoral and tibial knee axes.
    E_f = exp3(8 * DEG * normalize(np.cross(a_F, [0.2, 1.0, 0])))
    w_t = normalize(np.cross(a_T, [1.0, 0.3, 0]))
    E_t = exp3(6 * DEG * w_t)
    F_hat, T_hat = F @ E_f, T @ E_t
    measured = knee_aor(F_hat, T_hat)  # eq 9: same method on the IMC frames
    assert np.degrees(angle_between(measured.femur_axis, a_F)) > 5
    R_f, R_t = correction_rotations(measured, a_F, a_T)
    F_c, T_c = apply_correction(F_hat, R_f), apply_correction(T_hat, R_t)
    after = knee_aor(F_c, T_c)
    assert np.degrees(angle_between(after.femur_axis, a_F)) < 0.2
    assert np.degrees(angle_between(after.tibia_axis, a_T)) < 0.2
    # the error rotation was the smallest one tilting the axis, so the frames come back too
    assert np.degrees(np.linalg.norm(log3(R_f @ E_f))) < 0.3
    assert np.degrees(np.linalg.norm(log3(R_t @ E_t))) < 0.3
    # eq 11 as printed (v x V) with eq 13 doubles the error instead of removing it
    R_lit = rotation_aligning(measured.femur_axis, a_F)
    lit = knee_aor(apply_correction(F_hat, R_lit), T_hat)
    err0 = angle_between(measured.femur_axis, a_F)
    assert angle_between(lit.femur_axis, a_F) == pytest.approx(2 * err0, rel=0.05)


def test_bad_inputs():
    F = np.repeat(np.eye(3)[None], 4, axis=0)
    with pytest.raises(ValueError, match="N, 3, 3"):
        knee_aor(F, F[:3])
    with pytest.raises(InputError, match="no usable frame pairs"):
        knee_aor(F, F)  # no motion at all
    nan = F.copy()
    nan[:] = np.nan
    with pytest.raises(InputError):
        knee_aor(nan, nan, pairs=np.array([[0, 1]]))


def test_reexpress_tibia_matches_direct_call():
    from pipeline.calibration.aor import reexpress_tibia

    rng = np.random.default_rng(4)
    F, T, _, a_T = _hinge(rng, noise_deg=0.3)
    cluster = _random_rotation(rng)
    a = knee_aor(F, T @ cluster)
    b = reexpress_tibia(a, T)
    c = knee_aor(F, T @ cluster, tibia_frames_R=T)
    np.testing.assert_allclose(b.tibia_axis, c.tibia_axis, atol=1e-12)
    assert replace(b, tibia_axes=None).n_pairs == c.n_pairs
    assert np.degrees(angle_between(b.tibia_axis, a_T)) < 0.3
