"""pipeline.io.config: the TOML configuration of `pipeline ik`, read with checks, written back."""

import pytest

from pipeline.errors import InputError
from pipeline.io.config import config_text, read_config
from pipeline.model.anthropometry import Measures
from pipeline.process.options import IKOptions

GOOD = """
[subject]
sex = "f"
height_m = 1.62
knee_width_m = 0.095

[sensors]
pelvis_imu = "00B421AF"

[ik]
orientations = "data/walk.sto"
sensor_to_model = [-1.5708, 0, 0]
correction = "none"
joint_limits = false
foot_length_m = 0.25
"""


def _write(tmp_path, text, name="subject.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_reads_sections_and_resolves_paths_against_the_file(tmp_path):
    cfg = read_config(_write(tmp_path, GOOD))
    assert cfg.subject == {"sex": "f", "height_m": 1.62, "knee_width_m": 0.095}
    assert cfg.sensors == {"pelvis_imu": "00B421AF"}
    assert cfg.ik["orientations"] == str((tmp_path / "data" / "walk.sto").resolve())
    assert cfg.ik["sensor_to_model"] == [-1.5708, 0, 0] and cfg.ik["joint_limits"] is False


@pytest.mark.parametrize(
    "text, field, expected",
    [
        ("[subjects]\nsex = 'm'\n", "subjects", "unknown section"),
        ("[subject]\nweight_kg = 70\n", "subject.weight_kg", "unknown key"),
        ("[ik]\ncorection = 'aor'\n", "ik.corection", "unknown key"),
        ("[subject]\nheight_m = '1.8'\n", "subject.height_m", "expected a number"),
        ("[ik]\njoint_limits = 1\n", "ik.joint_limits", "expected true or false"),
        ("[ik]\nfoot_length_m = true\n", "ik.foot_length_m", "expected a number"),
        ("[ik]\nsensor_to_model = ['a', 0, 0]\n", "ik.sensor_to_model", "list of numbers"),
        ("[sensors]\npelvis_imu = 3\n", "sensors.pelvis_imu", "expected text"),
        ("ik = 3\n", "ik", "expected a table"),
    ],
)
def test_refuses_unknown_keys_and_wrong_types_naming_file_and_key(tmp_path, text, field, expected):
    path = _write(tmp_path, text)
    with pytest.raises(InputError) as exc:
        read_config(path)
    assert exc.value.field == field and expected in exc.value.message
    assert exc.value.file == str(path)


def test_invalid_toml_and_missing_file(tmp_path):
    with pytest.raises(InputError, match="not valid TOML"):
        read_config(_write(tmp_path, "[ik\n"))
    with pytest.raises(InputError, match="no such configuration file"):
        read_config(tmp_path / "absent.toml")


def test_written_configuration_reads_back_to_the_same_options(tmp_path):
    measures = Measures("m", 1.8, knee_width_m=0.1)
    options = IKOptions(correction="aor-ipopt", knee="hinge", sensor_to_model=(-1.5708, 0, 0),
                        knee_axis_femur=(0.0, 0.0, 1.0), knee_axis_tibia=(0.1, 0.0, 1.0),
                        sensor_map={"pelvis_imu": "P1"}, joint_limits=False)  # fmt: skip
    text = config_text(measures, options, orientations=tmp_path / "a.sto", header="made by a test")
    assert text.startswith("# made by a test\n")
    cfg = read_config(_write(tmp_path, text, "back.toml"))
    assert Measures(**cfg.subject) == measures
    ik = dict(cfg.ik)
    assert ik.pop("orientations") == str((tmp_path / "a.sto").resolve())
    for key in ("sensor_to_model", "knee_axis_femur", "knee_axis_tibia"):
        ik[key] = tuple(ik[key])
    assert IKOptions(**ik, sensor_map=cfg.sensors) == options
