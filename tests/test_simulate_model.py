"""Model-based simulator: signals vs finite differences of the FK poses, truth, noise, seeds,
and the end-to-end check that the Hu 2021 hinge calibration recovers the simulated knee axis."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.analysis.landmarks import frame_trajectories, landmark_trajectories
from pipeline.calibration.ipopt import calibrate_ipopt
from pipeline.calibration.joint_constraints import joint_data, project_hinge_positions
from pipeline.errors import InputError
from pipeline.model import Skeleton, SubjectGeometry
from pipeline.rotations import angle_between, log3, matrix_from_quat
from pipeline.simulate.model import GRAVITY, SensorNoise, simulate_trial

NO_NOISE = SensorNoise.none()


@pytest.fixture(scope="module")
def skeleton(tmp_path_factory):
    geometry = SubjectGeometry.default(1.75, "m", "right")
    return Skeleton.build(
        geometry, knee="hinge", root="freeflyer"
    )


@pytest.fixture(scope="module")
def gait(skeleton):
    return simulate_trial(skeleton, "gait", seed=3)


def _vee(M):
    return 0.5 * np.stack(
        [M[..., 2, 1] - M[..., 1, 2], M[..., 0, 2] - M[..., 2, 0], M[..., 1, 0] - M[..., 0, 1]],
        axis=-1,
    )


@pytest.mark.parametrize("motion", ["gait", "supine_hip_flexion"])
def test_signals_match_finite_differences_of_fk_poses(skeleton, motion):
    rate = 1000.0
    tr = simulate_trial(skeleton, motion, duration_s=2.0, rate_hz=rate, seed=1, noise=NO_NOISE)
    h = 1.0 / rate
    segs = sorted({s.segment for s in tr.imus.values()})
    fk = frame_trajectories(tr.skeleton, tr.q, segs)  # independent FK from q alone
    for s in tr.imus.values():
        R_seg, p_seg = fk[s.segment]
        R = R_seg @ s.R_segment
        p = p_seg + R_seg @ s.p_segment
        np.testing.assert_allclose(s.rotation, R, atol=1e-12)
        np.testing.assert_allclose(s.position, p, atol=1e-12)
        np.testing.assert_allclose(matrix_from_quat(s.recording.quat), R, atol=1e-9)
        # gyro: [w]x = R^T dR/dt (central differences of the FK rotations)
        w_fd = _vee(np.swapaxes(R[1:-1], 1, 2) @ (R[2:] - R[:-2]) / (2 * h))
        gyr = s.recording.gyr[1:-1]
        assert np.max(np.abs(w_fd - gyr)) < 1e-4 * max(1.0, np.max(np.abs(gyr))), s.frame
        # accelerometer: R^T (second difference of the FK position - g)
        a_fd = (p[2:] - 2 * p[1:-1] + p[:-2]) / h**2 - GRAVITY
        f_fd = np.einsum("nji,nj->ni", R[1:-1], a_fd)
        assert np.max(np.abs(f_fd - s.recording.acc[1:-1])) < 2e-4, s.frame
    # and the pelvis velocity itself: v[:3] = R^T dp/dt of the free-flyer root
    dp = (tr.q[2:, :3] - tr.q[:-2, :3]) / (2 * h)
    R_p = fk["pelvis"][0][1:-1]
    np.testing.assert_allclose(np.einsum("nji,nj->ni", R_p, dp), tr.v[1:-1, :3], atol=1e-4)


def test_static_pose_reads_plus_g_up(skeleton):
    tr = simulate_trial(skeleton, "static", duration_s=1.0, seed=0, noise=NO_NOISE)
    for s in tr.imus.values():
        acc_world = np.einsum("nij,nj->ni", s.rotation, s.recording.acc)
        np.testing.assert_allclose(acc_world, np.tile([0, 0, 9.81], (100, 1)), atol=1e-9)
        np.testing.assert_allclose(s.recording.gyr, 0.0, atol=1e-12)
    # standing in the neutral pose: the segment y axes point up
    R_femur = frame_trajectories(tr.skeleton, tr.q[:1], ["right_femur"])["right_femur"][0][0]
    np.testing.assert_allclose(R_femur[:, 1], [0, 0, 1], atol=1e-12)


def test_noise_and_bias_statistics(skeleton):
    noisy = simulate_trial(skeleton, "static", duration_s=20.0, seed=5)
    clean = simulate_trial(skeleton, "static", duration_s=20.0, seed=5, noise=NO_NOISE)
    n = SensorNoise()
    for name, s in noisy.imus.items():
        c = clean.imus[name]
        np.testing.assert_allclose(s.R_segment, c.R_segment)  # same placements
        e = s.recording.gyr - c.recording.gyr
        assert np.all(np.abs(e.mean(axis=0) - s.gyro_bias) < 5 * n.gyro_sd / np.sqrt(2000))
        assert np.all(np.abs(e.std(axis=0) / n.gyro_sd - 1) < 0.06)
        e = s.recording.acc - c.recording.acc
        assert np.all(np.abs(e.std(axis=0) / n.acc_sd - 1) < 0.06)
        assert np.all(np.abs(e.mean(axis=0)) < 5 * n.acc_sd / np.sqrt(2000))  # no acc bias
    assert np.std([s.gyro_bias for s in noisy.imus.values()]) > 0.2 * n.gyro_bias_sd


def test_orientation_noise(skeleton):
    tr = simulate_trial(
        skeleton, "static", duration_s=5.0, seed=0, noise=SensorNoise(orientation_sd_deg=1.0)
    )
    s = tr.imus["right_tibia_imu"]
    err = log3(np.swapaxes(s.rotation, 1, 2) @ matrix_from_quat(s.recording.quat))
    assert abs(np.degrees(err.std()) - 1.0) < 0.05


def test_knee_axis_and_joint_centres_consistent(gait):
    """One physical knee axis and one knee centre seen from both sensors at every sample."""
    t = gait.hinge_truth("right")
    s1, s2 = gait.imus["right_femur_imu"], gait.imus["right_tibia_imu"]
    np.testing.assert_allclose(s1.rotation @ t["axis_1"], s2.rotation @ t["axis_2"], atol=1e-12)
    c1 = s1.position + s1.rotation @ t["position_1_m"]
    c2 = s2.position + s2.rotation @ t["position_2_m"]
    np.testing.assert_allclose(c1, c2, atol=1e-12)
    # the relative angular velocity (world) is along the axis (noise-free)
    clean = simulate_trial(gait.skeleton, "gait", seed=gait.seed, noise=NO_NOISE)
    c1, c2 = clean.imus["right_femur_imu"], clean.imus["right_tibia_imu"]
    w_rel = np.einsum("nij,nj->ni", c2.rotation, c2.recording.gyr) - np.einsum(
        "nij,nj->ni", c1.rotation, c1.recording.gyr
    )
    axis_world = c1.rotation @ t["axis_1"]
    assert np.max(np.linalg.norm(np.cross(w_rel, axis_world), axis=1)) < 1e-9
    assert np.max(np.abs(w_rel)) > 1.0  # the knee does move
    # hip and ankle centres: one point from both of their sensors
    for joint in ("right_hip", "left_hip", "right_ankle", "left_knee"):
        (n1, o1), (n2, o2) = gait.joint_centres[joint].items()
        a, b = gait.imus[n1], gait.imus[n2]
        p1 = a.position + a.rotation @ o1
        p2 = b.position + b.rotation @ o2
        np.testing.assert_allclose(p1, p2, atol=1e-12, err_msg=joint)


def test_knee_axis_from_model_matches_geometry(skeleton):
    g = SubjectGeometry.default(1.75, "m", "right")
    a_f, a_t = skeleton.knee_axis("right")
    np.testing.assert_allclose(a_f, g.knee_axis_femur, atol=1e-12)
    np.testing.assert_allclose(a_t, g.knee_axis_tibia, atol=1e-12)


def test_misalignment_and_offset_are_the_truth(gait):
    for s in gait.imus.values():
        T = gait.skeleton.relative_pose(s.frame, s.segment, gait.skeleton.neutral())
        np.testing.assert_allclose(s.R_segment, T[:3, :3] @ s.misalignment, atol=1e-12)
        np.testing.assert_allclose(s.p_segment, T[:3, 3] + s.offset_m, atol=1e-12)
        angle = np.degrees(np.linalg.norm(log3(s.misalignment)))
        assert 7.5 - 1e-9 <= angle <= 15.0 + 1e-9
        assert 0.01 - 1e-12 <= np.linalg.norm(s.offset_m) <= 0.02 + 1e-12


def test_free_knee_has_no_hinge_truth(tmp_path):
    sk = Skeleton.build(
        SubjectGeometry.default(1.62, "f", "right"), knee="free", root="freeflyer"
    )
    tr = simulate_trial(sk, "gait", duration_s=1.0, seed=0)
    assert tr.knee_axis == {}
    with pytest.raises(InputError):
        tr.hinge_truth()


def test_still_thigh_is_nearly_still(skeleton):
    tr = simulate_trial(skeleton, "still_thigh", duration_s=10.0, seed=2, noise=NO_NOISE)
    thigh = np.linalg.norm(tr.imus["right_femur_imu"].recording.gyr, axis=1)
    shank = np.linalg.norm(tr.imus["right_tibia_imu"].recording.gyr, axis=1)
    assert thigh.max() < 0.1 and shank.max() > 2.0  # tremor only: < 6 deg/s
    hip = [tr.skeleton.q_index(f"right_hip_{a}") for a in "ZXY"]
    assert np.degrees(np.ptp(tr.q[:, hip], axis=0)).max() < 1.0
    knee = tr.q[:, tr.skeleton.q_index("right_knee")]
    assert np.degrees(np.ptp(knee)) > 60.0
    np.testing.assert_allclose(tr.v[:, :6], 0.0)  # pelvis fixed (seated)


def test_gait_moves_the_pelvis(gait):
    x = gait.q[:, 0]
    assert 15.0 < x[-1] - x[0] < 20.0  # ~1.2 m/s for 15 s
    assert np.ptp(np.linalg.norm(gait.v[:, 3:6], axis=1)) > 0.1


def test_landmarks_are_fk_of_landmark_frames(skeleton):
    tr = simulate_trial(skeleton, "gait", duration_s=1.0, seed=0, noise=NO_NOISE)
    fk = landmark_trajectories(tr.skeleton, tr.q)
    for name, p in tr.landmarks.items():
        np.testing.assert_allclose(p, fk[name], atol=1e-12)
    noisy = simulate_trial(skeleton, "gait", duration_s=1.0, seed=0)
    e = np.concatenate([noisy.landmarks[n] - fk[n] for n in fk])
    assert abs(e.std() / SensorNoise().landmark_sd_m - 1) < 0.1


def test_deterministic_with_seed(skeleton):
    a = simulate_trial(skeleton, "gait", duration_s=1.0, seed=7)
    b = simulate_trial(skeleton, "gait", duration_s=1.0, seed=7)
    c = simulate_trial(skeleton, "gait", duration_s=1.0, seed=8)
    d = simulate_trial(skeleton, "supine_hip_flexion", duration_s=1.0, seed=7)
    for name in a.imus:
        np.testing.assert_array_equal(a.imus[name].recording.gyr, b.imus[name].recording.gyr)
        np.testing.assert_array_equal(a.imus[name].recording.acc, b.imus[name].recording.acc)
        assert not np.allclose(a.imus[name].recording.gyr, c.imus[name].recording.gyr)
        np.testing.assert_array_equal(a.imus[name].R_segment, d.imus[name].R_segment)
    np.testing.assert_array_equal(a.q, b.q)


def test_fixed_root_skeleton_is_reloaded_with_a_free_flyer(tmp_path):
    sk = Skeleton.build(SubjectGeometry.default(1.75, "m", "right"), knee="hinge")
    tr = simulate_trial(sk, "static", duration_s=0.5, seed=0)
    assert tr.skeleton.root == "freeflyer" and tr.q.shape[1] == sk.nq + 7
    default = simulate_trial(motion="static", duration_s=0.2)  # default 1.75 m hinge-knee subject
    assert default.skeleton.knee == "hinge" and default.q.shape == (20, 19)


def test_bad_inputs(skeleton):
    with pytest.raises(InputError, match="motion"):
        simulate_trial(skeleton, "running", duration_s=1.0)
    with pytest.raises(InputError, match="duration"):
        simulate_trial(skeleton, "gait", duration_s=-1.0)
    with pytest.raises(InputError, match="at least 8 samples"):
        simulate_trial(skeleton, "gait", duration_s=0.05)


def _axis_errors_deg(res, truth):
    s = 1.0 if np.dot(res.axis_1, truth["axis_1"]) > 0 else -1.0
    return (
        np.degrees(angle_between(s * res.axis_1, truth["axis_1"])),
        np.degrees(angle_between(s * res.axis_2, truth["axis_2"])),
    )


def test_hinge_calibration_recovers_simulated_knee_axis(gait):
    """End to end: Hu 2021 hinge calibration (IPOPT) on the simulated thigh and shank IMUs at
    realistic noise (0.01 rad/s, 0.05 m/s^2, gyro bias 0.005 rad/s, 7.5-15 deg misalignment)."""
    a = gait.imus["right_femur_imu"].recording
    b = gait.imus["right_tibia_imu"].recording
    data = joint_data(gait.time, a.gyr, a.acc, b.gyr, b.acc)
    res = calibrate_ipopt(data, "hinge", quat_1=a.quat, quat_2=b.quat)
    truth = gait.hinge_truth("right")
    e1, e2 = _axis_errors_deg(res, truth)
    assert e1 < 0.5 and e2 < 0.5
    # the knee axis in the sensor frames differs from the model's IMU-frame axis (misalignment)
    a_f, _ = gait.skeleton.knee_axis("right")
    assert np.degrees(angle_between(truth["axis_1"], a_f)) > 5.0
    o1, o2 = project_hinge_positions(
        truth["position_1_m"], truth["position_2_m"], truth["axis_1"], truth["axis_2"]
    )
    assert np.linalg.norm(res.position_1_m - o1) < 0.004
    assert np.linalg.norm(res.position_2_m - o2) < 0.004
    assert res.observability.undetermined == ()


def test_still_thigh_calibration_is_flagged(skeleton):
    tr = simulate_trial(skeleton, "still_thigh", seed=0)
    a = tr.imus["right_femur_imu"].recording
    b = tr.imus["right_tibia_imu"].recording
    res = calibrate_ipopt(joint_data(tr.time, a.gyr, a.acc, b.gyr, b.acc), "hinge")
    assert any("axis_1" in u for u in res.observability.undetermined)
