"""pipeline.io.formats: every recording format recognised once, by content, every file of a folder
read or named, and the sensor map applied in one place."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io.formats import apply_sensor_map, read_recording, recognise
from pipeline.io.imu_csv import write_imu_csv
from pipeline.io.opensim import write_orientations_sto
from pipeline.io.recording import Recording

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data"
XIMU3 = DATA / "ximu3_lower_body"
S02 = DATA / "gaittoolbox_s02" / "imu"
S02_MAP = {"pelvis_imu": "00B40B91", "femur_l_imu": "00B40C45", "femur_r_imu": "00B40C3C",
           "tibia_l_imu": "00B40C44", "tibia_r_imu": "00B40C47", "calcn_l_imu": "00B40C55",
           "calcn_r_imu": "00B40C48"}


def _imu(folder: Path, name: str, t: np.ndarray, w: float = 1.0) -> Path:
    gyr = np.stack([w * np.sin(t), np.cos(t), 0 * t], axis=1)
    acc = np.tile([0.0, 0.0, 9.81], (t.size, 1))
    return write_imu_csv(folder / f"{name}.csv", Recording.single(name, t, gyr=gyr, acc=acc))


def test_formats_are_recognised_by_content_not_by_name(tmp_path):
    t = np.arange(50) / 100.0
    csv = _imu(tmp_path, "femur_r_imu", t)
    disguised = tmp_path / "femur_r_imu.dat"
    disguised.write_text(csv.read_text())
    q = np.tile([1.0, 0, 0, 0], (50, 1))
    sto = write_orientations_sto(tmp_path / "w.sto",
                                 Recording.from_orientations(t, 100.0, {"pelvis_imu": q}))
    assert recognise(csv).name == recognise(disguised).name == "imu_csv"
    assert recognise(sto).name == "sto"
    (tmp_path / "notes.txt").write_text("a walk on Tuesday\n")
    assert recognise(tmp_path / "notes.txt") is None
    # one IMU CSV given to ik is read as an IMU CSV (not as an .sto)
    rec = read_recording(csv)
    assert rec.sensor_names == ("femur_r_imu",) and rec.time[0] == 0.0


def test_time_need_not_be_the_first_column(tmp_path):
    t = np.arange(40) / 100.0
    text = _imu(tmp_path, "femur_r_imu", t).read_text().splitlines()
    moved = [",".join(line.split(",")[1:4] + line.split(",")[:1] + line.split(",")[4:])
             for line in text]
    (tmp_path / "femur_r_imu.csv").write_text("\n".join(moved) + "\n")
    rec = read_recording(tmp_path / "femur_r_imu.csv")
    np.testing.assert_allclose(rec.time, t, atol=1e-12)


def test_every_entry_of_a_folder_is_read_or_named(tmp_path):
    t = np.arange(300) / 100.0
    _imu(tmp_path, "femur_r_imu", t)
    _imu(tmp_path, "right_tibia_imu", t)  # pipeline simulate's name
    (tmp_path / "notes.txt").write_text("a walk on Tuesday\n")
    with pytest.raises(InputError, match="is not a recording.*--ignore 'notes.txt'") as exc:
        read_recording(tmp_path)
    assert exc.value.file == str(tmp_path / "notes.txt")
    rec = read_recording(tmp_path, ignore=["*.txt"])
    assert set(rec.sensor_names) == {"femur_r_imu", "tibia_r_imu"}
    assert any("left out" in n and "notes.txt" in n for n in rec.notes)
    (tmp_path / "notes.txt").unlink()
    (tmp_path / ".DS_Store").write_bytes(b"\x00\x01")
    assert set(read_recording(tmp_path).sensor_names) == {"femur_r_imu", "tibia_r_imu"}
    _imu(tmp_path, "thigh_left", t)
    with pytest.raises(InputError, match=r"no sensor name for \['thigh_left.csv'\]"):
        read_recording(tmp_path)
    rec = read_recording(tmp_path, {"femur_l_imu": "thigh_left"})
    assert set(rec.sensor_names) == {"femur_r_imu", "tibia_r_imu", "femur_l_imu"}


def test_a_sensor_map_entry_that_matches_nothing_is_refused_everywhere(tmp_path):
    t = np.arange(300) / 100.0
    _imu(tmp_path, "femur_r_imu", t)
    _imu(tmp_path, "tibia_r_imu", t)
    with pytest.raises(InputError) as exc:
        read_recording(tmp_path, {"pelvis_imu": "00B421AF"})
    assert exc.value.field == "sensors.pelvis_imu" and "00B421AF" in exc.value.message
    q = np.tile([1.0, 0, 0, 0], (300, 1))
    sto = write_orientations_sto(tmp_path / "w.sto", Recording.from_orientations(
        t, 100.0, {"femur_r_imu": q, "tibia_r_imu": q}))
    with pytest.raises(InputError, match="matches '00B421AF'"):
        read_recording(sto, {"pelvis_imu": "00B421AF"})
    with pytest.raises(InputError, match="mapped twice"):
        read_recording(sto, {"pelvis_imu": "femur_r_imu", "femur_l_imu": "femur_r_imu"})


def test_the_map_renames_and_aliases_become_our_names():
    t = np.arange(10) / 100.0
    q = np.tile([1.0, 0, 0, 0], (10, 1))
    rec = Recording.from_orientations(t, 100.0, {"thigh_R": q, "foot_r_imu": q})
    out = apply_sensor_map(rec, {"femur_r_imu": "thigh_R"})
    assert set(out.sensor_names) == {"femur_r_imu", "calcn_r_imu"}
    with pytest.raises(InputError, match="two sensors for calcn_r_imu"):
        apply_sensor_map(Recording.from_orientations(
            t, 100.0, {"foot_r_imu": q, "calcn_r_imu": q}), {})


@pytest.mark.dataset
@pytest.mark.skipif(not XIMU3.exists(), reason="needs ../shared/data/ximu3_lower_body")
def test_the_real_ximu3_folder_is_seven_sensors_on_one_clock():
    rec = read_recording(XIMU3)
    assert set(rec.sensor_names) == {"pelvis_imu", "femur_r_imu", "tibia_r_imu", "calcn_r_imu",
                                     "femur_l_imu", "tibia_l_imu", "calcn_l_imu"}
    assert 18.0 < rec.time[-1] < 18.7 and np.allclose(np.diff(rec.time), 1 / rec.rate_hz)
    for s in rec.sensors.values():
        assert s.gyr.shape == s.acc.shape == s.mag.shape == (rec.time.size, 3)
        assert np.allclose(np.linalg.norm(s.quat, axis=1), 1.0)
    one = read_recording(next(p for p in XIMU3.iterdir() if p.name.startswith("Left Foot")))
    assert one.sensor_names == ("calcn_l_imu",)


@pytest.mark.dataset
@pytest.mark.skipif(not S02.exists(), reason="needs ../shared/data/gaittoolbox_s02")
def test_the_real_xsens_folder_by_device_id():
    rec = read_recording(S02, S02_MAP)
    assert set(rec.sensor_names) == set(S02_MAP)
    assert rec.n_samples == 2503 and rec.rate_hz == 100.0
    assert all(s.quat is not None and s.mag is not None for s in rec.sensors.values())


def _rec(*names):
    q = np.tile([1.0, 0, 0, 0], (5, 1))
    return Recording.from_orientations(np.arange(5) / 100.0, 100.0, {n: q for n in names})


def test_map_by_name_or_unique_part_and_aliases():
    rec = _rec("MT_012005D6_00B421AF", "thigh_R", "shank_R", "foot_r_imu")
    out = apply_sensor_map(rec, {"pelvis_imu": "00B421AF", "femur_r_imu": "thigh_R",
                                 "tibia_r_imu": "shank"})
    assert set(out.sensor_names) == {"pelvis_imu", "femur_r_imu", "tibia_r_imu", "calcn_r_imu"}
    assert apply_sensor_map(_rec("pelvis_imu"), {}) .sensor_names == ("pelvis_imu",)


@pytest.mark.parametrize(
    "names, mapping, message",
    [
        (("a1", "a2"), {"pelvis_imu": "a"}, "several sensors"),
        (("a1",), {"pelvis_imu": "zz"}, "no sensor"),
        (("a1",), {"pelvis_imu": "a1", "femur_r_imu": "a1"}, "mapped twice"),
        (("calcn_r_imu", "foot_r_imu"), {}, "two sensors for calcn_r_imu"),
    ],
)
def test_unmatched_ambiguous_or_duplicate_names_are_refused(names, mapping, message):
    with pytest.raises(InputError, match=message):
        apply_sensor_map(_rec(*names), mapping)


def test_a_sensor_map_that_is_not_a_mapping_is_named(tmp_path):
    """``sensor_map`` given as the CLI's text (an AttributeError before)."""
    with pytest.raises(InputError, match=r"field sensor_map: expected a mapping .* got str "
                                         r"'pelvis_imu=00B40B91'"):
        read_recording(tmp_path, "pelvis_imu=00B40B91")


def test_an_ximu3_folder_mapped_by_device_id():
    """x-IMU3 device folders ``<label> <device id> (<interface>)``: a map by the device id, as
    documented, names them (refused before: only the labels were matched)."""
    folder = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "ximu3_lower_body"
    if not folder.exists():
        pytest.skip("../shared/data/ximu3_lower_body not present")
    ids = {"pelvis_imu": "64F0EDBF", "tibia_r_imu": "64F61B2A", "femur_r_imu": "64F61C2E",
           "calcn_r_imu": "64F619FB", "femur_l_imu": "64F61CC4", "tibia_l_imu": "64F61CB3",
           "calcn_l_imu": "64F0EBCE"}
    by_id, by_label = read_recording(folder, ids), read_recording(folder)
    assert set(by_id.sensor_names) == set(ids)
    for name in ids:
        np.testing.assert_array_equal(by_id.sensors[name].gyr, by_label.sensors[name].gyr)
    swapped = dict(ids, tibia_r_imu="64F61CB3", tibia_l_imu="64F61B2A")  # a map decides
    np.testing.assert_array_equal(read_recording(folder, swapped).sensors["tibia_r_imu"].gyr,
                                  by_label.sensors["tibia_l_imu"].gyr)


def test_a_generic_folder_name_gives_its_parents(tmp_path):
    from pipeline.io.formats import recording_name

    (tmp_path / "S02" / "imu").mkdir(parents=True)
    (tmp_path / "S02" / "walk_fast").mkdir()
    assert recording_name(tmp_path / "S02" / "imu") == "S02"  # not every subject's "imu"
    assert recording_name(tmp_path / "S02" / "walk_fast") == "walk_fast"
    assert recording_name(tmp_path / "S02" / "imu" / "trial.sto") == "trial"
    assert recording_name("example:ximu3_lower_body") == "ximu3_lower_body"
