"""pipeline.process.walking_pose: each sensor's placement from the walk itself, no pose held: on
the simulated walk against its true placements and joint angles, and on the real walk cut to
start mid-walk against Vicon."""

import numpy as np
import pytest
from _helpers import s02_cut

from pipeline.analysis.joint_angles import joint_angles
from pipeline.errors import InputError
from pipeline.model.measures import Measures
from pipeline.model.scaling import geometry_from_measures
from pipeline.process import process_recording
from pipeline.process.walking_pose import walking_frames

SUBJECT = Measures("m", 1.75)


@pytest.fixture(scope="module")
def walk():
    """The simulated walk from its first step (no standing; free knee and ankle, soft tissue,
    wandering biases)."""
    from pipeline.model.skeleton import Skeleton
    from pipeline.simulate.artefacts import Artefacts
    from pipeline.simulate.model import simulate_trial

    sk = Skeleton.build(geometry_from_measures(SUBJECT)[0], knee="free", root="freeflyer",
                        ankle="free")
    return simulate_trial(sk, "walk", duration_s=12.0, seed=0, standing_s=0.0,
                          artefacts=Artefacts())


def _placement_errors(run, trial) -> dict[str, float]:
    out = {}
    for frame, imu in trial.imus.items():
        D = run.placements[frame][:3, :3] @ imu.R_segment.T
        out[frame] = float(np.degrees(np.arccos(np.clip((np.trace(D) - 1) / 2, -1, 1))))
    return out


def test_the_walk_calibrates_every_sensor_without_a_pose(walk):
    """Measured (seeds 0-2): placements within 1-7 deg of the truth but the thighs' (10-17 deg,
    about their long axis: the walking flexion axis is the hip's, not the femur's z), sagittal
    angles within 0.7-3.7 deg RMS."""
    run = process_recording(walk.raw_recording(), SUBJECT)
    assert run.calibration.startswith("from the walk, no pose (no still window)")
    assert not run.flags
    errors = _placement_errors(run, walk)
    assert max(e for f, e in errors.items() if "femur" not in f) < 8.0, errors
    assert max(errors.values()) < 20.0, errors
    truth = joint_angles(walk.skeleton, walk.q)
    for side in ("right", "left"):
        for joint in ("hip", "knee", "ankle"):
            key = f"{side}_{joint}_flexion"
            rms = np.degrees(np.sqrt(np.mean((run.joint_angles[key] - truth[key]) ** 2)))
            assert rms < 4.5, (key, rms)


def test_signals_that_do_not_locate_the_joints_are_refused(walk):
    """Orientations' own rates and gravity alone (no joint accelerations): the centres' fit
    puts the knee and hip a few centimetres apart, and the walk's calibration is refused."""
    from pipeline.io.opensim import sensor_to_opensim_matrix
    from pipeline.io.recording import SensorSignals
    from pipeline.io.sensor_names import SEGMENT_SENSOR
    from pipeline.process.gait import gait_of
    from pipeline.rotations import log3

    rec, W = walk.raw_recording(), sensor_to_opensim_matrix((-np.pi / 2, 0.0, 0.0))
    segments = ("pelvis", "right_femur", "right_tibia")
    rotations, sensors = {}, dict(rec.sensors)
    for seg in segments:
        R = walk.imus[f"{seg}_imu"].rotation  # z-up world
        gyr = np.vstack([log3(np.swapaxes(R[:-1], 1, 2) @ R[1:]) * 100.0, np.zeros((1, 3))])
        acc = np.einsum("nji,j->ni", R, [0.0, 0.0, 9.81])
        sensors[SEGMENT_SENSOR[seg]] = SensorSignals(gyr=gyr, acc=acc)
        rotations[seg] = W @ R  # the model's y-up world
    bare = rec.with_sensors(sensors)
    gait = gait_of(bare, [])
    with pytest.raises(InputError, match="the walk does not locate the joints"):
        walking_frames(bare, rotations, gait, geometry_from_measures(SUBJECT)[0], ("right",))


@pytest.mark.dataset
@pytest.mark.parametrize("path", ["vendor", "vqf6"])
def test_the_real_walk_from_mid_walk(path):
    """S02 cut to 13.0-20.75 s (mid-walk, no still moment): calibrated from the walk; sagittal
    RMSE against Vicon (measured: median 5.0-5.1, right knee 2.9, left knee 6.5-7.3: Vicon's left
    knee, whose own standing pose reads 11.5 deg where the markers read 0.6, README)."""
    import sys
    from pathlib import Path

    rec = s02_cut(1300, 2075, path)
    if rec is None:
        pytest.skip("no S02 data")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_real_gait import DATA, SAGITTAL

    from pipeline.io.mot import read_mot
    from pipeline.process import mot_columns

    options = {"sensor_to_model": (-np.pi / 2, 0, 0)} if path == "vendor" else {"filter": "vqf"}
    run = process_recording(rec, Measures("m", 1.72), **options)
    assert run.calibration.startswith("from the walk, no pose (no still window)")
    assert not run.flags
    vicon = read_mot(DATA / "vicon" / "S02-Trial-Walk-1_vicon_ik.mot").columns
    cols = mot_columns(run)
    rmse = {c: float(np.degrees(np.sqrt(np.mean((cols[c] - vicon[c][1300:2075]) ** 2))))
            for c in SAGITTAL}
    assert np.median(list(rmse.values())) < 5.5, rmse
    assert rmse["knee_angle_r"] < 4.0 and rmse["knee_angle_l"] < 8.0, rmse
