"""pipeline.calibration.placement: IMU frames from a hinge calibration, against the simulator."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.calibration.ipopt import calibrate_ipopt
from pipeline.calibration.joint_constraints import joint_data
from pipeline.calibration.placement import imu_placements_from_calibration
from pipeline.model import Skeleton, SubjectGeometry, build_urdf
from pipeline.rotations import log3
from pipeline.simulate.model import simulate_trial


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    geometry = SubjectGeometry.default(1.75, "m", "right")
    folder = tmp_path_factory.mktemp("placement")
    sk = Skeleton.build(geometry, knee="hinge", root="freeflyer")
    gait = simulate_trial(sk, "gait", seed=11)
    static = simulate_trial(sk, "static", duration_s=2.0, seed=11)  # same seed: same placements
    a, b = gait.imus["right_femur_imu"].recording, gait.imus["right_tibia_imu"].recording
    res = calibrate_ipopt(
        joint_data(gait.time, a.gyr, a.acc, b.gyr, b.acc), "hinge", quat_1=a.quat, quat_2=b.quat
    )
    acc = tuple(
        static.imus[f"right_{s}_imu"].recording.acc.mean(axis=0) for s in ("femur", "tibia")
    )
    return geometry, gait, res, acc, folder


def _placement_errors(est, gait, seg):
    s = gait.imus[f"right_{seg}_imu"]
    T = est.placements[f"right_{seg}_imu"]
    a_f, a_t = gait.skeleton.knee_axis("right")
    axis = a_f if seg == "femur" else a_t
    rot_err = log3(T[:3, :3] @ s.R_segment.T)  # segment frame
    dp = T[:3, 3] - s.p_segment
    return rot_err, dp, axis


def test_placements_from_calibration_with_a_static_pose(calibrated):
    geometry, gait, res, acc, folder = calibrated
    est = imu_placements_from_calibration(
        gait.skeleton, res.axis_1, res.axis_2, res.position_1_m, res.position_2_m, static_acc=acc
    )
    assert est.twist_from == "static pose"
    axial = []
    for seg in ("femur", "tibia"):
        rot_err, dp, axis = _placement_errors(est, gait, seg)
        default_err = np.linalg.norm(log3(gait.imus[f"right_{seg}_imu"].misalignment))
        assert np.degrees(np.linalg.norm(rot_err)) < 1.0 < np.degrees(default_err)
        assert np.linalg.norm(dp - (dp @ axis) * axis) < 0.004  # across the axis: observable
        axial.append(dp @ axis)
    # along the axis only one common shift is undetermined: the relative position is recovered
    assert abs(axial[0] - axial[1]) < 0.004
    # and the result is written into the model as IMU frames
    path = build_urdf(geometry, folder / "calibrated.urdf", imu_placements=est.placements)
    sk = Skeleton.from_urdf(path)
    for name, T in est.placements.items():
        seg = name.removesuffix("_imu")
        np.testing.assert_allclose(sk.relative_pose(name, seg, sk.neutral()), T, atol=1e-9)


def test_placements_without_static_pose_recover_the_observable_part(calibrated):
    _, gait, res, _, _ = calibrated
    est = imu_placements_from_calibration(
        gait.skeleton, -res.axis_1, -res.axis_2, res.position_1_m, res.position_2_m
    )  # flipped signs are fixed from the model's IMU frames
    assert est.twist_from == "default" and any("undetermined" in n for n in est.notes)
    for seg in ("femur", "tibia"):
        rot_err, _, axis = _placement_errors(est, gait, seg)
        tilt = np.linalg.norm(rot_err - (rot_err @ axis) * axis)  # the part off the knee axis
        assert np.degrees(tilt) < 0.6
        mis = log3(gait.imus[f"right_{seg}_imu"].misalignment)
        assert np.degrees(np.linalg.norm(mis - (mis @ axis) * axis)) > 2.0  # it was misaligned
