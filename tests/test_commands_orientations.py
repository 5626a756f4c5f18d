"""pipeline orientations: raw IMU signals to an OpenSense-compatible orientation .sto."""

import numpy as np
import pytest

from pipeline.cli import main
from pipeline.io.imu_csv import write_imu_csv
from pipeline.io.opensim import read_orientations_sto
from pipeline.io.recording import Recording
from pipeline.model.measures import Measures
from pipeline.process import process_recording
from pipeline.simulate.model import simulate_trial


@pytest.fixture(scope="module")
def raw_folder(tmp_path_factory):
    """A pipeline-simulate-style folder (the model's frame names) without quaternions."""
    folder = tmp_path_factory.mktemp("raw")
    trial = simulate_trial(motion="gait", duration_s=8.0, seed=5, standing_s=2.0)
    for frame, imu in trial.imus.items():
        s = imu.recording.sensor
        write_imu_csv(folder / f"{frame}.csv",
                      Recording.single(frame, trial.time, gyr=s.gyr, acc=s.acc))
    return folder


def test_writes_an_sto_that_pipeline_ik_reads_like_the_folder(raw_folder, tmp_path, capsys):
    sto = tmp_path / "walk.sto"
    assert main(["orientations", "--imu", str(raw_folder), "--filter", "pi", "--out",
                 str(sto)]) == 0
    out = capsys.readouterr().out
    assert "sensor_to_opensim_rotations -1.5708 0 0" in out and "by PI" in out
    rec = read_orientations_sto(sto)
    assert set(rec.sensor_names) == {"pelvis_imu", "femur_r_imu", "tibia_r_imu", "calcn_r_imu",
                                     "femur_l_imu", "tibia_l_imu", "calcn_l_imu"}
    assert sto.read_text().split("endheader")[0].count("WorldUp=z") == 1
    # the .sto (z-up world, as OpenSense expects) through ik == the raw folder through ik with
    # the same information (the raw folder's gyroscopes would also give the knees' functional
    # calibration and the joints' heading alignment, which the .sto cannot carry)
    m = Measures("m", 1.75)
    from_sto = process_recording(rec, m, sensor_to_model=(-np.pi / 2, 0, 0))
    from pipeline.io.formats import read_recording as read_imu_folder

    from_raw = process_recording(read_imu_folder(raw_folder), m, filter="pi",
                                 calibration_method="none", drift="none",
                                 posture="neutral")
    # within 0.05 deg: the raw folder's still start also gives each sensor's accelerometer
    # vertical at the calibration pose (pipeline.process.pose.still_gravity)
    for key in ("right_knee_flexion", "left_hip_flexion"):
        np.testing.assert_allclose(from_sto.joint_angles[key], from_raw.joint_angles[key],
                                   atol=np.radians(0.05))


def test_one_file_and_bad_output_name(raw_folder, tmp_path):
    assert main(["orientations", "--imu", str(raw_folder / "pelvis_imu.csv"), "--out",
                 str(tmp_path / "p.sto")]) == 0
    assert read_orientations_sto(tmp_path / "p.sto").sensor_names == ("pelvis_imu",)
    assert main(["orientations", "--imu", str(raw_folder), "--out", str(tmp_path / "p.csv")]) == 2
