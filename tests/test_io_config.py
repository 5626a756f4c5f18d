"""pipeline.io.config: the TOML configuration of `pipeline ik` read with checks (the keys and
their types come from the options' one definition), written back."""

import os

import pytest

from pipeline.errors import InputError
from pipeline.io.config import config_text, read_config
from pipeline.process.options import all_specs

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
    cfg = read_config(_write(tmp_path, GOOD), all_specs())
    assert cfg["sex"] == "f" and cfg["height_m"] == 1.62 and cfg["knee_width_m"] == 0.095
    assert cfg["sensor_map"] == {"pelvis_imu": "00B421AF"}
    assert cfg["orientations"] == str((tmp_path / "data" / "walk.sto").resolve())
    assert cfg["sensor_to_model"] == (-1.5708, 0, 0) and cfg["joint_limits"] is False


@pytest.mark.parametrize(
    "text, field, expected",
    [
        ("[subjects]\nsex = 'm'\n", "subjects", "unknown section"),
        ("[subject]\nweight_kg = 70\n", "subject.weight_kg", "unknown key"),
        ("[ik]\ncorection = 'aor'\n", "ik.corection", "unknown key"),
        ("[subject]\nheight_m = '1.8'\n", "subject.height_m", "expected a number"),
        ("[ik]\njoint_limits = 1\n", "ik.joint_limits", "expected true or false"),
        ("[ik]\nfoot_length_m = true\n", "ik.foot_length_m", "expected a number"),
        ("[ik]\nsensor_to_model = ['a', 0, 0]\n", "ik.sensor_to_model", "three numbers"),
        ("[ik]\nsensor_to_model = [0, 0]\n", "ik.sensor_to_model", "three numbers"),
        ("[sensors]\npelvis_imu = 3\n", "sensors.pelvis_imu", "expected text"),
        ("ik = 3\n", "ik", "expected a table"),
    ],
)
def test_refuses_unknown_keys_and_wrong_types_naming_file_and_key(tmp_path, text, field, expected):
    path = _write(tmp_path, text)
    with pytest.raises(InputError) as exc:
        read_config(path, all_specs())
    assert exc.value.field == field and expected in exc.value.message
    assert exc.value.file == str(path)


def test_invalid_toml_missing_file_and_what_is_not_a_text_file(tmp_path):
    with pytest.raises(InputError, match="not valid TOML"):
        read_config(_write(tmp_path, "[ik\n"), all_specs())
    with pytest.raises(InputError, match="no such configuration file"):
        read_config(tmp_path / "absent.toml", all_specs())
    latin = tmp_path / "latin.toml"
    latin.write_bytes('[subject]\nsex = "f" # Müller\n'.encode("latin-1"))
    with pytest.raises(InputError, match="not UTF-8"):
        read_config(latin, all_specs())
    utf16 = tmp_path / "u16.toml"
    utf16.write_bytes('[subject]\nsex = "f"\n'.encode("utf-16"))
    with pytest.raises(InputError, match="not UTF-8|NUL"):
        read_config(utf16, all_specs())
    binary = tmp_path / "b.toml"
    binary.write_bytes(b"\x00\x01\x02abc")
    with pytest.raises(InputError, match="NUL"):
        read_config(binary, all_specs())
    with pytest.raises(InputError, match="regular file"):
        read_config(tmp_path, all_specs())


@pytest.mark.skipif(not hasattr(os, "mkfifo"), reason="needs FIFOs")
def test_a_fifo_is_refused_without_blocking(tmp_path):
    fifo = tmp_path / "c.toml"
    os.mkfifo(fifo)
    with pytest.raises(InputError, match="regular file"):
        read_config(fifo, all_specs())


def test_text_has_the_header_as_comments():
    text = config_text({"subject": {"sex": "m"}}, "one\n\ntwo")
    assert text.startswith("# one\n#\n# two\n[subject]\n")
