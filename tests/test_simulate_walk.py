"""The simulated walk (pipeline.simulate.walk): feet that rest on their footprints, legs that
reach them exactly, q/v/a consistent, and the gait analysis recovering its strides and the
pelvis's path from the sensors alone."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import matrix_from_quat
from pipeline.simulate.model import simulate_trial
from pipeline.simulate.motions import joint_trajectories, ramp
from pipeline.simulate.walk import walk_trajectories
from pipeline.simulate.walk_feet import FLAT, PUSH_OFF

MEASURES = Measures("m", 1.75)
STANDING = 2.0


@pytest.fixture(scope="module")
def trial():
    sk = Skeleton.build(geometry_from_measures(MEASURES)[0], knee="free", root="freeflyer")
    return simulate_trial(sk, "walk", duration_s=12.0, seed=3, standing_s=STANDING)


def _flat_samples(trial, side: str) -> np.ndarray:
    """Samples where the foot lies flat on a footprint after a step (truth from the plan)."""
    tau = ramp(trial.time, STANDING)[3]
    T = trial.walk.T
    ic = trial.walk.contacts(side)[0]
    flat = np.zeros(trial.time.size, bool)
    for c in ic:
        flat |= (tau > c + FLAT * T + 0.02) & (tau < c + PUSH_OFF * T - 0.02)
    return flat


def test_feet_rest_flat_on_their_footprints(trial):
    for side in ("right", "left"):
        flat = _flat_samples(trial, side)
        assert flat.sum() > 100
        imu = trial.imus[f"{side}_foot_imu"]  # the sensor's true pose
        starts = np.flatnonzero(np.diff(flat.astype(int)) == 1) + 1
        for a in starts:
            b = a + int(np.argmin(flat[a:]))
            assert np.ptp(imu.position[a:b], axis=0).max() < 1e-9, (side, a)
            assert np.ptp(imu.rotation[a:b], axis=0).max() < 1e-9, (side, a)
        # every footprint on the standing feet's floor (the two legs' leans put the standing
        # feet a few mm apart in height)
        ajc_z = trial.walk.footprints[side][:, 2]
        assert np.ptp(ajc_z) < 0.005


def test_feet_invert_in_push_off_and_land_flat(trial):
    """The foot is not a sagittal hinge: its lateral axis tips down (the sole turned medially)
    by up to the drawn inversion at the end of push-off (5-10 deg, less its pitch's share), and
    lies level again while flat."""
    from pipeline.simulate.walk import FOOT_INVERSION_DEG

    up = np.array([0.0, 0.0, 1.0])
    for side, sign in (("right", 1.0), ("left", -1.0)):
        imu = trial.imus[f"{side}_foot_imu"]
        R = imu.rotation @ imu.R_segment.T  # the foot segment in the world (z up)
        lateral_down = -sign * np.degrees(np.arcsin(np.clip(R[:, :, 2] @ up, -1, 1)))
        assert 0.5 * FOOT_INVERSION_DEG[1][0] < lateral_down.max() <= FOOT_INVERSION_DEG[1][1]
        assert np.abs(lateral_down[_flat_samples(trial, side)]).max() < 0.5


def _axial_range(trial, segment: str) -> float:
    """The segment's largest turn about its own long axis (deg) over one stride mid-walk: its
    world rotation relative to the stride's start, the y component of its log."""
    from pipeline.rotations import log3

    imu = trial.imus[f"right_{segment}_imu"]
    R = imu.rotation @ imu.R_segment.T
    ic = np.searchsorted(trial.time, trial.walk.contacts("right")[0])
    a, b = ic[2], ic[3]
    turn = [log3(R[a].T @ R[k])[1] for k in range(a, b)]
    return float(np.degrees(np.ptp(turn)))


def test_a_free_ankle_lets_the_tibia_turn_on_its_planted_foot(trial):
    """Built with ``ankle='free'``, the walk turns the foot relative to the tibia by
    ``k * inversion`` (:mod:`pipeline.simulate.subtalar` eq 1): the feet keep
    their poses, and the tibia and femur turn about their long axes further over a stride
    than under the model's two-axis ankle."""
    from pipeline.simulate.subtalar import ANKLE_TURN_PER_INVERSION

    sk = Skeleton.build(geometry_from_measures(MEASURES)[0], knee="free", root="freeflyer",
                        ankle="free")
    free = simulate_trial(sk, "walk", duration_s=12.0, seed=3, standing_s=STANDING)
    for side in ("right", "left"):
        foot = f"{side}_foot_imu"
        np.testing.assert_allclose(free.imus[foot].rotation, trial.imus[foot].rotation,
                                   atol=1e-6)
        # the foot's inversion in the world: the vertical in its frame, (., cos r, -sin r) times
        # the cosine of its pitch
        R = free.imus[foot].rotation @ free.imus[foot].R_segment.T
        up = np.einsum("nji,j->ni", R, [0.0, 0.0, 1.0])
        inverted = (1.0 if side == "right" else -1.0) * np.arctan2(-up[:, 2], up[:, 1])
        turn = free.q[:, sk.q_index(f"{side}_ankle_Y")]
        big = np.abs(inverted) > np.radians(2.0)
        k = turn[big] / inverted[big]
        assert big.sum() > 50 and np.ptp(k) < 1e-6, np.ptp(k)
        assert ANKLE_TURN_PER_INVERSION[0] <= k[0] <= ANKLE_TURN_PER_INVERSION[1]
    for segment in ("tibia", "femur"):
        assert _axial_range(free, segment) > _axial_range(trial, segment) + 2.5, segment


def test_the_pelvis_moves_through_the_room_and_turns(trial):
    p = trial.q[:, :3]
    walked = np.sum(np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1))
    assert walked > 0.8 * trial.walk.speed * (12.0 - STANDING - 1.0)
    heading = np.unwrap(np.arctan2(*np.diff(p[-200:, :2], axis=0).T[::-1]))
    assert abs(abs(np.mean(heading)) - abs(trial.walk.turn)) < np.deg2rad(10)
    # the standing start is still
    assert np.ptp(p[: int(100 * STANDING) - 5], axis=0).max() < 1e-9


def test_v_and_a_are_the_time_derivatives_of_q(trial):
    # at 1000 Hz: a heel strike turns the ankle at up to ~250 rad/s^2 within a tenth of a
    # second, which a central difference at 100 Hz cannot follow (at 500 Hz the integral of a
    # over 0.1 s missed v's change by 1.3e-3 max|v| at one heel strike: the trapezoid's error,
    # 0.3e-3 at 2000 Hz)
    t = np.arange(3000) / 1000.0
    q, v, a, _ = walk_trajectories(trial.skeleton, t, 0.3, np.random.default_rng(1))
    h, moving = 1 / 1000.0, slice(400, None)  # after the ramp's start (its jerk jumps there)

    def close(fd, exact, tol):
        np.testing.assert_allclose(fd[moving], exact[1:-1][moving], atol=tol)

    # a = dv/dt, integrated over 0.1 s windows: the foot's pitch lobes make the jerk jump at
    # their ends, where a central difference of v errs by ~h |jump| / 4 (~5 rad/s^2 here)
    steps = np.cumsum(0.5 * h * (a[1:] + a[:-1]), axis=0)
    np.testing.assert_allclose((v[500::100] - v[400:-100:100]),
                               steps[499::100] - steps[399:-100:100],
                               atol=1e-3 * np.abs(v).max())
    # five-point differences: the swinging knee's jerk (it flexes to ~65 deg) defeats three
    five = (q[:-4, 7:] - 8 * q[1:-3, 7:] + 8 * q[3:-1, 7:] - q[4:, 7:]) / (12 * h)
    np.testing.assert_allclose(five[moving], v[2:-2, 6:][moving],
                               atol=3e-3 * np.abs(v[:, 6:]).max())
    R = matrix_from_quat(q[:, [6, 3, 4, 5]])
    dp = (q[2:, :3] - q[:-2, :3]) / (2 * h)
    close(np.einsum("nji,nj->ni", R[1:-1], dp), v[:, :3], 1e-3)


def test_the_sinusoidal_generator_refuses_the_walk(trial):
    with pytest.raises(InputError, match="walk"):
        joint_trajectories(trial.skeleton, "walk", trial.time)


def test_strides_and_the_pelvis_path_are_recovered_from_the_sensors(trial):
    from pipeline.process import process_recording

    run = process_recording(trial.raw_recording(magnetometers=False), MEASURES)
    strides = run.gait.strides
    assert len(strides) >= 10
    tau = ramp(trial.time, STANDING)[3]
    for side in ("right", "left"):
        ic = np.interp(trial.walk.contacts(side)[0], tau, trial.time, right=np.nan)
        lengths = trial.walk.stride_lengths(side)
        for st in (s for s in strides if s.side == side):
            j = int(np.nanargmin(np.abs(ic - st.start_s)))
            assert abs(st.start_s - ic[j]) < 0.03
            assert abs(st.stride_length_m - lengths[j]) < 0.03
    path = run.gait.pelvis_path
    ours = path[:, [0, 2]] * [1.0, -1.0]  # the model's y-up world to the simulator's z-up
    truth = trial.q[:, :2]
    ok = np.all(np.isfinite(ours), axis=1)
    a, b = ours[ok] - ours[ok].mean(0), truth[ok] - truth[ok].mean(0)
    u, _, vt = np.linalg.svd(a.T @ b)
    err = np.linalg.norm(a @ (u @ vt) - b, axis=1)
    walked = np.sum(np.linalg.norm(np.diff(truth, axis=0), axis=1))
    assert err.mean() < 0.01 * walked
