import numpy as np
import pytest

from pipeline import rotations as rot
from pipeline.rotations import exp3, rotation_aligning_with_twist


def test_elementary_rotations_by_hand():
    # a quarter turn about z maps x onto y; about x maps y onto z; about y maps z onto x
    np.testing.assert_allclose(rot.rot_z(np.pi / 2) @ [1, 0, 0], [0, 1, 0], atol=1e-15)
    np.testing.assert_allclose(rot.rot_x(np.pi / 2) @ [0, 1, 0], [0, 0, 1], atol=1e-15)
    np.testing.assert_allclose(rot.rot_y(np.pi / 2) @ [0, 0, 1], [1, 0, 0], atol=1e-15)
    assert rot.rot_z(np.zeros(5)).shape == (5, 3, 3)


def test_skew_is_cross_product():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(2, 10, 3))
    np.testing.assert_allclose(np.einsum("nij,nj->ni", rot.skew(a), b), np.cross(a, b))


def test_exp_log_round_trip_and_shapes():
    rng = np.random.default_rng(1)
    v = rng.normal(size=(50, 3))
    v *= (rng.uniform(0, 3.0, 50) / np.linalg.norm(v, axis=1))[:, None]
    R = rot.exp3(v)
    assert R.shape == (50, 3, 3)
    np.testing.assert_allclose(rot.log3(R), v, atol=1e-12)
    np.testing.assert_allclose(rot.exp3(v[0]), R[0])
    axis, angle = rot.axis_angle(R)
    np.testing.assert_allclose(axis * angle[:, None], v, atol=1e-12)


def test_quaternion_convention_scalar_first():
    # 90 deg about z: w = cos 45, z = sin 45
    q = np.array([np.cos(np.pi / 4), 0, 0, np.sin(np.pi / 4)])
    np.testing.assert_allclose(rot.matrix_from_quat(q), rot.rot_z(np.pi / 2), atol=1e-15)
    np.testing.assert_allclose(rot.quat_from_matrix(rot.rot_z(np.pi / 2)), q, atol=1e-15)
    # non-unit quaternions are normalised, zero ones refused
    np.testing.assert_allclose(rot.matrix_from_quat(2 * q), rot.rot_z(np.pi / 2), atol=1e-15)
    with pytest.raises(ValueError):
        rot.matrix_from_quat(np.zeros(4))


def test_euler_zyx_matches_matlab_eul2rotm_order():
    e = np.array([0.3, -0.2, 0.7])
    expected = rot.rot_z(0.3) @ rot.rot_y(-0.2) @ rot.rot_x(0.7)
    np.testing.assert_allclose(rot.matrix_from_euler_zyx(e), expected)
    np.testing.assert_allclose(rot.euler_zyx_from_matrix(expected), e, atol=1e-12)


def test_project_to_so3():
    rng = np.random.default_rng(2)
    R = rot.exp3(rng.normal(size=(4, 3)))
    noisy = R + 1e-3 * rng.normal(size=R.shape)
    P = rot.project_to_so3(noisy)
    np.testing.assert_allclose(
        np.einsum("nji,njk->nik", P, P), np.broadcast_to(np.eye(3), P.shape), atol=1e-12
    )
    np.testing.assert_allclose(np.linalg.det(P), 1.0)
    assert np.max(np.abs(P - R)) < 5e-3


def test_rotation_aligning_wang_eq_10_12_by_hand():
    # a = x, b = y: axis x × y = z, angle 90 deg -> Rz(90)
    R = rot.rotation_aligning([1, 0, 0], [0, 2, 0])
    np.testing.assert_allclose(R, rot.rot_z(np.pi / 2), atol=1e-15)
    # general vectors: R a_hat = b_hat, and the rotation is about a × b
    rng = np.random.default_rng(3)
    for _ in range(20):
        a, b = rng.normal(size=(2, 3))
        R = rot.rotation_aligning(a, b)
        np.testing.assert_allclose(R @ rot.normalize(a), rot.normalize(b), atol=1e-12)
        axis, _ = rot.axis_angle(R)
        np.testing.assert_allclose(axis, rot.normalize(np.cross(a, b)), atol=1e-9)
    np.testing.assert_allclose(rot.rotation_aligning([0, 0, 1], [0, 0, 3]), np.eye(3))
    R = rot.rotation_aligning([0, 0, 1], [0, 0, -1])
    np.testing.assert_allclose(R @ [0, 0, 1], [0, 0, -1], atol=1e-12)


def test_angle_between_is_accurate_for_tiny_angles():
    assert rot.angle_between([1, 0, 0], [1, 1e-9, 0]) == pytest.approx(1e-9, rel=1e-6)
    assert rot.angle_between([1, 0, 0], [-1, 0, 0]) == pytest.approx(np.pi)


def test_rotation_aligning_with_twist_by_hand():
    x, y, z = np.eye(3)
    R = rotation_aligning_with_twist(x, y, z, x)  # x -> y exactly, then z -> x: a cyclic shift
    np.testing.assert_allclose(R, [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-12)
    rng = np.random.default_rng(0)
    R_true = exp3(rng.normal(size=3))
    a, c = rng.normal(size=3), rng.normal(size=3)
    np.testing.assert_allclose(rotation_aligning_with_twist(a, R_true @ a, c, R_true @ c), R_true)
    ref = exp3(np.array([0.1, -0.2, 0.05])) @ R_true  # nearest rotation with R a = R_true a
    R = rotation_aligning_with_twist(a, R_true @ a, np.eye(3), ref.T)
    np.testing.assert_allclose(R @ a, R_true @ a, atol=1e-12)
    for phi in (-0.01, 0.01):  # a local optimum of |R - ref| among rotations about the axis
        Rp = exp3(phi * (R_true @ a) / np.linalg.norm(a)) @ R
        assert np.linalg.norm(Rp - ref) > np.linalg.norm(R - ref)


def test_unwrap_angles_by_hand():
    # a heading turning steadily through +180 deg: atan2 wraps to -179, unwrapping continues
    a = np.radians([170.0, 179.0, -179.0, -170.0, np.nan, -160.0])
    out = rot.unwrap_angles(a)
    np.testing.assert_allclose(np.degrees(out[[0, 1, 2, 3, 5]]), [170, 179, 181, 190, 200])
    assert np.isnan(out[4]) and np.isnan(a[4])
    np.testing.assert_array_equal(rot.unwrap_angles(np.array([0.1])), [0.1])


def test_space_fixed_xyz_by_hand():
    # OpenSense's Xsens setting (-pi/2, 0, 0) is Rx(-90 deg): it takes z (up) to y
    R = rot.matrix_from_euler_xyz_fixed([-np.pi / 2, 0, 0])
    np.testing.assert_allclose(R @ [0, 0, 1], [0, 1, 0], atol=1e-15)
    a = np.array([0.3, -0.4, 1.1])
    np.testing.assert_allclose(rot.matrix_from_euler_xyz_fixed(a),
                               rot.rot_z(1.1) @ rot.rot_y(-0.4) @ rot.rot_x(0.3))
    back = rot.euler_xyz_fixed_from_matrix(rot.matrix_from_euler_xyz_fixed(a))
    np.testing.assert_allclose(back, a)


def _hard_rotations(n=400, seed=3):
    """Random rotations plus the hard cases: identity, tiny angles, angles at and near pi."""
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(n, 3))
    axes /= np.linalg.norm(axes, axis=1, keepdims=True)
    angles = np.concatenate([
        rng.uniform(0.0, np.pi, n - 60), np.zeros(10), 10.0 ** -rng.uniform(5, 12, 20),
        np.pi - 10.0 ** -rng.uniform(3, 10, 20), np.full(10, np.pi),
    ])
    return axes * angles[:, None]


def test_maps_agree_with_scipy_and_pinocchio():
    import pinocchio as pin
    from scipy.spatial.transform import Rotation

    v = _hard_rotations()
    R = rot.exp3(v)
    np.testing.assert_allclose(R, Rotation.from_rotvec(v).as_matrix(), atol=1e-14)
    np.testing.assert_allclose(R[:5], [pin.exp3(x) for x in v[:5]], atol=1e-14)
    # log3: the same rotation back (at pi the sign of the vector is a free choice)
    np.testing.assert_allclose(rot.exp3(rot.log3(R)), R, atol=1e-12)
    far = np.linalg.norm(v, axis=1) < np.pi - 1e-6
    np.testing.assert_allclose(rot.log3(R)[far], v[far], atol=1e-9)
    np.testing.assert_allclose(rot.log3(R[:40]), [pin.log3(m) for m in R[:40]], atol=1e-9)
    q = rot.quat_from_matrix(R)
    ref = Rotation.from_matrix(R).as_quat()[:, [3, 0, 1, 2]]
    ref[ref[:, 0] < 0] *= -1
    both = np.abs(q[:, 0]) > 1e-9  # at w = 0, q and -q are both valid
    np.testing.assert_allclose(q[both], ref[both], atol=1e-12)
    np.testing.assert_allclose(rot.matrix_from_quat(q), R, atol=1e-13)
    e = Rotation.from_matrix(R[:300]).as_euler("ZYX")
    np.testing.assert_allclose(rot.matrix_from_euler_zyx(rot.euler_zyx_from_matrix(R)), R,
                               atol=1e-12)
    np.testing.assert_allclose(rot.euler_zyx_from_matrix(R[:300]), e, atol=1e-9)
    xyz = Rotation.from_matrix(R[:300]).as_euler("xyz")
    np.testing.assert_allclose(rot.euler_xyz_fixed_from_matrix(R[:300]), xyz, atol=1e-9)


def test_euler_zyx_at_gimbal_lock_rebuilds_the_rotation():
    for y in (np.pi / 2, -np.pi / 2):
        R = rot.matrix_from_euler_zyx(np.array([0.4, y, -0.3]))
        e = rot.euler_zyx_from_matrix(R)
        assert e[2] == 0.0
        np.testing.assert_allclose(rot.matrix_from_euler_zyx(e), R, atol=1e-12)


def test_quat_xyzw_integrate_is_pinocchio_spherical_integrate():
    import pinocchio as pin

    model = pin.Model()
    model.addJoint(0, pin.JointModelSpherical(), pin.SE3.Identity(), "ball")
    rng = np.random.default_rng(4)
    q = rng.normal(size=(30, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    v = rng.normal(size=(30, 3)) * np.r_[np.full(20, 1.0), np.full(10, 1e-8)][:, None]
    ours = rot.quat_xyzw_integrate(q, v)
    ref = [pin.integrate(model, a, b) for a, b in zip(q, v, strict=True)]
    np.testing.assert_allclose(ours, ref, atol=1e-12)
    np.testing.assert_allclose(rot.matrix_from_quat_xyzw(ours),
                               rot.matrix_from_quat_xyzw(q) @ rot.exp3(v), atol=1e-12)


def test_nan_in_nan_out():
    R = np.full((2, 3, 3), np.nan)
    assert np.isnan(rot.log3(R)).all() and np.isnan(rot.quat_from_matrix(R)).all()


def test_cross_is_numpys_cross_with_broadcasting():
    rng = np.random.default_rng(5)
    a, b = rng.normal(size=(2, 40, 3))
    np.testing.assert_allclose(rot.cross(a, b), np.cross(a, b), atol=1e-15)
    np.testing.assert_allclose(rot.cross(a[0], b), np.cross(a[0], b), atol=1e-15)
    np.testing.assert_array_equal(rot.cross([1.0, 0, 0], [0, 1.0, 0]), [0, 0, 1.0])
