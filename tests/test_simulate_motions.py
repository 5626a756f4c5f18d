"""Motions of the simulator (pipeline.simulate.motions): q, v, a exact and consistent, limit-safe
for every motion and seed, deterministic, and bad requests refused."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.model import Skeleton, SubjectGeometry
from pipeline.rotations import matrix_from_quat
from pipeline.simulate.motions import RAMP_S, SINUSOIDAL, joint_trajectories, standing_start


@pytest.fixture(scope="module")
def skeleton(tmp_path_factory):
    geometry = SubjectGeometry.default(1.75, "m", "right")
    return Skeleton.build(
        geometry, knee="hinge", root="freeflyer"
    )


def _vee(M):
    return 0.5 * np.stack(
        [M[..., 2, 1] - M[..., 1, 2], M[..., 0, 2] - M[..., 2, 0], M[..., 1, 0] - M[..., 0, 1]],
        axis=-1,
    )


@pytest.mark.parametrize("knee", ["hinge", "free"])
def test_joint_limits_respected(tmp_path, knee):
    sk = Skeleton.build(
        SubjectGeometry.default(1.62, "f", "right"), knee=knee, root="freeflyer"
    )
    t = np.arange(3000) / 100.0
    for motion in SINUSOIDAL:
        for seed in range(4):
            q, v, a = joint_trajectories(sk, motion, t, seed)
            assert np.all(q[:, 7:] >= sk.lower_limits[7:]), (motion, seed)
            assert np.all(q[:, 7:] <= sk.upper_limits[7:]), (motion, seed)
            np.testing.assert_allclose(np.linalg.norm(q[:, 3:7], axis=1), 1.0)


@pytest.mark.parametrize("standing_s", [0.0, 0.3])
@pytest.mark.parametrize("motion", SINUSOIDAL)
def test_v_and_a_are_the_time_derivatives_of_q(skeleton, motion, standing_s):
    rate = 1000.0
    h = 1.0 / rate
    t = np.arange(2000) / rate  # with standing_s 0.3: still, the whole ramp, 0.2 s of motion
    if standing_s:
        q, v, a = standing_start(skeleton, motion, t, standing_s, seed=1)
    else:
        q, v, a = joint_trajectories(skeleton, motion, t, seed=1)
    nq, nv = skeleton.model.nq, skeleton.model.nv
    assert q.shape == (2000, nq) and v.shape == a.shape == (2000, nv)
    assert nq - 7 == nv - 6  # 1-DoF joints after the free flyer

    # the ramp is C2: its third derivative jumps at both ends, where a central difference errs
    # by ~h |jump| / 4; those two samples apart, central differences err by h^2/6 |x'''| (at
    # most 2e-5 of the largest value here)
    ends = np.isclose(t[1:-1], standing_s) | np.isclose(t[1:-1], standing_s + RAMP_S)
    keep = ~ends if standing_s else np.ones(t.size - 2, bool)

    def close(fd, exact):
        np.testing.assert_allclose(
            fd[keep], exact[keep], atol=1e-4 * max(1.0, np.abs(exact).max())
        )

    # a = dv/dt for every component (the root velocity is in the pelvis frame, as in Pinocchio)
    close((v[2:] - v[:-2]) / (2 * h), a[1:-1])
    # joint angles: v = dq/dt
    close((q[2:, 7:] - q[:-2, 7:]) / (2 * h), v[1:-1, 6:])
    # root: q[3:7] is (x, y, z, w); v[:3] = R^T p', [v[3:6]]x = R^T R'
    R = matrix_from_quat(q[:, [6, 3, 4, 5]])
    dp = (q[2:, :3] - q[:-2, :3]) / (2 * h)
    close(np.einsum("nji,nj->ni", R[1:-1], dp), v[1:-1, :3])
    close(_vee(np.swapaxes(R[1:-1], 1, 2) @ (R[2:] - R[:-2]) / (2 * h)), v[1:-1, 3:6])


def test_standing_start_is_upright_then_the_motion(skeleton):
    t = np.arange(600) / 100.0
    q, v, a = standing_start(skeleton, "gait", t, 1.0, seed=2)
    still = t < 1.0
    np.testing.assert_allclose(v[still], 0.0, atol=1e-12)
    np.testing.assert_allclose(a[still], 0.0, atol=1e-12)
    np.testing.assert_allclose(q[still, 7:], 0.0, atol=1e-12)
    R = matrix_from_quat(q[:, [6, 3, 4, 5]])
    # upright: the pelvis y axis up and its z axis (right) horizontal, facing the path's heading
    np.testing.assert_allclose(R[still, :, 1], np.tile([0, 0, 1.0], (still.sum(), 1)), atol=1e-12)
    # after the ramp: the motion itself, delayed by half the ramp (tau = t - start - RAMP_S / 2)
    q_m, _, _ = joint_trajectories(skeleton, "gait", t - 1.0 - RAMP_S / 2, seed=2)
    after = t > 1.0 + RAMP_S
    np.testing.assert_allclose(q[after, 7:], q_m[after, 7:], atol=1e-12)
    np.testing.assert_allclose(np.abs(np.sum(q[after, 3:7] * q_m[after, 3:7], axis=1)), 1.0)
    np.testing.assert_allclose(q[after, :3], q_m[after, :3], atol=1e-12)


def test_static_is_the_neutral_pose_at_rest(skeleton):
    q, v, a = joint_trajectories(skeleton, "static", np.arange(50) / 100.0, seed=4)
    np.testing.assert_array_equal(q[:, 7:], 0.0)
    np.testing.assert_array_equal(v, 0.0)
    np.testing.assert_array_equal(a, 0.0)
    np.testing.assert_allclose(q, np.tile(q[0], (50, 1)))  # pelvis fixed
    # pelvis y (up) along world z: rot_x(90 deg), quaternion (x, y, z, w) = (sin 45, 0, 0, cos 45)
    np.testing.assert_allclose(np.abs(q[0, 3:7]), [np.sqrt(0.5), 0, 0, np.sqrt(0.5)], atol=1e-12)


def test_seeded_and_refusals(skeleton):
    t = np.arange(100) / 100.0
    gait = joint_trajectories(skeleton, "gait", t, seed=3)
    with pytest.raises(InputError, match="expected a motion in"):
        joint_trajectories(skeleton, "rich", t)  # one name per motion, the same everywhere
    rng = np.random.default_rng(3)
    for x, y in zip(joint_trajectories(skeleton, "gait", t, seed=rng), gait, strict=True):
        np.testing.assert_array_equal(x, y)  # an int seed is default_rng(seed)
    other = joint_trajectories(skeleton, "gait", t, seed=4)[0]
    assert not np.allclose(other, gait[0])
    with pytest.raises(InputError, match="expected a motion in"):
        joint_trajectories(skeleton, "running", t)
    fixed = skeleton.with_root("fixed")
    with pytest.raises(InputError, match="freeflyer"):
        joint_trajectories(fixed, "gait", t)


def test_gait_legs_move_in_antiphase():
    """One stride rate per trial, the left leg half a stride after the right."""
    from pipeline.model import Skeleton, SubjectGeometry
    from pipeline.simulate.motions import joint_trajectories

    sk = Skeleton.build(SubjectGeometry.default(1.75, "m", "right"), knee="hinge", root="freeflyer")
    t = np.arange(1500) / 100.0
    for seed in range(3):
        q, _, _ = joint_trajectories(sk, "gait", t, seed)
        right, left = q[:, sk.q_index("right_hip_Z")], q[:, sk.q_index("left_hip_Z")]
        assert np.corrcoef(right, left)[0, 1] < -0.9, seed
