"""pipeline.process.options: every option of `pipeline ik` defined once, checked in one place, and
accepted alike by its flag, the configuration file and a batch manifest."""

import csv

import numpy as np
import pytest

from pipeline.cli import build_parser
from pipeline.commands.batch import read_manifest
from pipeline.errors import InputError
from pipeline.model.measures import Measures
from pipeline.option import from_flag, specs
from pipeline.process.options import (
    IKOptions,
    InputOptions,
    OutputOptions,
    all_specs,
    check_sensor_to_model,
    resolve_settings,
    settings_text,
)


def test_defaults_are_the_documented_ones():
    o = IKOptions()
    assert (o.knee, o.calibration_pose, o.heading) == ("free", "standing", "anatomical")
    assert o.joint_limits and not o.segment_orientations
    out = OutputOptions(out="x")
    assert out.rerun and not out.strict and not out.osim


def test_output_switches_are_apart_from_the_processing_options():
    assert {s.name for s in specs(OutputOptions)} == {"out", "name", "rerun", "report", "osim",
                                                      "landmarks", "overwrite", "strict"}
    assert not {"rerun", "osim", "strict", "sensor_map", "orientations"} & {
        s.name for s in specs(IKOptions)}


@pytest.mark.parametrize(
    "changes, field",
    [
        ({"knee": "ball"}, "knee"),
        ({"correction": "wang"}, "correction"),
        ({"calibration_pose": "kneeling"}, "calibration_pose"),
        ({"heading": "north"}, "heading"),
        ({"joint_limits": "yes"}, "joint_limits"),
        ({"knee_axis_femur": (0, 0, 1)}, "knee_axis_femur"),  # one axis without the other
        ({"knee_axis_femur": (0, 0, 0), "knee_axis_tibia": (0, 0, 1)}, "knee_axis_femur"),
        ({"knee_axis_femur": (0, 0, -1), "knee_axis_tibia": (0, 0, 1)}, "knee_axis_femur"),
    ],
)
def test_bad_values_are_refused_naming_the_option(changes, field):
    with pytest.raises(InputError) as exc:
        IKOptions(**changes)
    assert exc.value.field == field


@pytest.mark.parametrize("sensor_map, field", [({"thigh": "T1"}, "sensors.thigh"),
                                               ({"pelvis_imu": ""}, "sensors.pelvis_imu")])
def test_bad_sensor_names_are_refused(sensor_map, field):
    with pytest.raises(InputError) as exc:
        InputOptions(orientations="a.sto", sensor_map=sensor_map)
    assert exc.value.field == field


def test_units_hints_for_degrees_and_centimetres():
    with pytest.raises(InputError, match="if you meant degrees, give -1.5708 0.0000 0.0000"):
        check_sensor_to_model((-90, 0, 0))
    with pytest.raises(InputError, match="looks like cm"):
        IKOptions(foot_length_m=26.0)
    with pytest.raises(InputError, match="finite"):
        check_sensor_to_model((np.nan, 0, 0))


def test_axes_are_normalised_and_replace_checks_names():
    o = IKOptions(knee_axis_femur=(0, 0, 2), knee_axis_tibia=(0.3, 0, 0.4))
    assert o.knee_axis_femur == (0.0, 0.0, 1.0)
    np.testing.assert_allclose(o.knee_axis_tibia, (0.6, 0.0, 0.8))
    assert o.replace(knee="hinge").knee == "hinge"
    with pytest.raises(InputError, match="unknown option"):
        o.replace(kne="hinge")


# ---------------------------------------------------------------------------------------------
# one definition: the flag, the configuration file and a manifest give the same settings

def _value(spec):
    """A non-default value of every option, as flag words, TOML text and a manifest cell."""
    by_name = {
        "orientations": ("walk.sto",), "static_trial": ("still.sto",),
        "sensor_map": ("pelvis_imu=P1", "femur_r_imu=T1"), "ignore": ("notes.txt", "*.log"),
        "sex": ("f",), "height_m": ("1.62",), "shank_lateral_m": ("0.41",),
        "shank_medial_m": ("0.40",), "knee_width_m": ("0.095",), "ankle_width_m": ("0.07",),
        "pelvis_width_m": ("0.25",),
        "knee_axis_femur": ("0", "0.1", "1"), "knee_axis_tibia": ("0.1", "0", "1"),
        "sensor_to_model": ("-1.5708", "0", "0"), "foot_length_m": ("0.25",),
        "name": ("subject01",),
    }
    if spec.name in by_name:
        return by_name[spec.name]
    if spec.kind == "bool":
        return ()
    if spec.kind == "choice":
        return (next(c for c in spec.choices if c != spec.default),)
    raise AssertionError(f"no test value for {spec.name} ({spec.kind})")


def _toml(spec, words):
    if spec.kind == "bool":
        return f"{spec.name} = {'false' if spec.default else 'true'}"
    if spec.kind == "vec3":
        return f"{spec.name} = [{', '.join(words)}]"
    if spec.kind == "words":
        return f"{spec.name} = [{', '.join(repr(w) for w in words)}]"
    if spec.kind in ("float",):
        return f"{spec.name} = {words[0]}"
    return f'{spec.name} = "{words[0]}"'


def _cell(spec, words):
    if spec.kind == "bool":
        return "false" if spec.default else "true"
    return " ".join(words)


def test_every_option_is_accepted_by_flag_config_and_manifest_alike(tmp_path):
    options = [s for s in all_specs() if s.name != "out"]
    # flags
    argv = ["ik", "--out", str(tmp_path / "o")]
    for s in options:
        argv += [s.flag, *_value(s)]
    args = build_parser().parse_args(argv)
    flagged = resolve_settings(None, {s.name: from_flag(s, getattr(args, s.name))
                                      for s in all_specs()})
    # configuration file (relative paths against the file's folder)
    tables: dict[str, list[str]] = {"subject": [], "sensors": [], "ik": []}
    for s in options:
        if s.kind == "pairs":
            tables["sensors"] += [f'{k} = "{v}"' for k, v in (w.split("=") for w in _value(s))]
        else:
            tables[s.section].append(_toml(s, _value(s)))
    text = "\n".join(f"[{t}]\n" + "\n".join(lines) for t, lines in tables.items())
    (tmp_path / "c.toml").write_text(text)
    filed = resolve_settings(tmp_path / "c.toml", {"out": str(tmp_path / "o")})
    # manifest (relative paths against the manifest's folder)
    with open(tmp_path / "m.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["subject", *(s.name for s in options)])
        w.writerow(["s1", *(_cell(s, _value(s)) for s in options)])
    (row,) = read_manifest(tmp_path / "m.csv")
    values = {k: v for k, v in row.items() if k not in ("row", "line", "subject")}
    listed = resolve_settings(None, {**values, "out": str(tmp_path / "o")})
    # paths given relative: the CLI's are relative to the working directory
    for settings in (filed, listed):
        assert settings.inputs.orientations == str((tmp_path / "walk.sto").resolve())
    assert flagged.subject == filed.subject == listed.subject == Measures(
        "f", 1.62, 0.41, 0.40, 0.095, 0.07, 0.25)
    assert flagged.options == filed.options == listed.options
    assert flagged.outputs == filed.outputs == listed.outputs
    assert flagged.inputs.sensor_map == filed.inputs.sensor_map == listed.inputs.sensor_map
    assert flagged.inputs.ignore == filed.inputs.ignore == listed.inputs.ignore == (
        "notes.txt", "*.log")
    for s in specs(IKOptions):  # every option took its non-default value
        assert getattr(listed.options, s.name) != s.default, s.name
    assert not listed.outputs.rerun and listed.outputs.osim and listed.outputs.strict


def test_settings_written_read_back_to_the_same_settings(tmp_path):
    values = {"orientations": str(tmp_path / "a.sto"), "out": str(tmp_path / "o"), "sex": "m",
              "height_m": 1.8, "knee_width_m": 0.1, "correction": "aor-ipopt", "knee": "hinge",
              "sensor_to_model": (-1.5708, 0, 0), "knee_axis_femur": (0.0, 0.0, 1.0),
              "knee_axis_tibia": (0.1, 0.0, 1.0), "sensor_map": {"pelvis_imu": "P1"},
              "joint_limits": False}
    settings = resolve_settings(None, values)
    text = settings_text(settings, "made by a test")
    assert text.startswith("# made by a test\n")
    (tmp_path / "back.toml").write_text(text)
    again = resolve_settings(tmp_path / "back.toml", {"out": str(tmp_path / "o")})
    assert again == settings


def test_missing_required_options_say_where_to_give_them(tmp_path):
    with pytest.raises(InputError, match=r"--orientations is required \(or \[ik\] orientations"):
        resolve_settings(None, {"sex": "m", "height_m": 1.8, "out": "o"})
    with pytest.raises(InputError, match=r"--sex is required \(or \[subject\] sex"):
        resolve_settings(None, {"orientations": "a.sto", "height_m": 1.8, "out": "o"})
    (tmp_path / "c.toml").write_text("[ik]\ncorrection = 'none'\n")
    with pytest.raises(InputError) as exc:
        resolve_settings(tmp_path / "c.toml", {"sex": "m", "height_m": 1.8, "out": "o"})
    assert exc.value.file == str(tmp_path / "c.toml")


def test_flags_add_to_the_files_sensor_table(tmp_path):
    (tmp_path / "c.toml").write_text("[sensors]\npelvis_imu = 'P1'\n")
    s = resolve_settings(tmp_path / "c.toml", {"orientations": "a.sto", "out": "o", "sex": "m",
                                                "height_m": 1.8,
                                                "sensor_map": {"femur_r_imu": "T1"}})
    assert s.inputs.sensor_map == {"pelvis_imu": "P1", "femur_r_imu": "T1"}
