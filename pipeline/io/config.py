"""The configuration file of ``pipeline ik`` (TOML): the subject, the sensor names and the options.

::

    [subject]
    sex = "m"
    height_m = 1.80            # optional: shank_lateral_m, shank_medial_m, knee_width_m, ...

    [sensors]                  # our sensor name = the recording's name or device id
    pelvis_imu = "00B421AF"
    femur_r_imu = "thigh_R"

    [ik]                       # any option of `pipeline ik`, named as its flag without dashes
    orientations = "walk.sto"  # paths relative to this file
    sensor_to_model = [-1.5708, 0.0, 0.0]
    correction = "aor"

Reading uses the standard library (``tomllib``); writing uses ``tomli-w`` (the file is data the
user reads and edits, so it is written by a TOML library rather than by hand). Every run writes
the resolved configuration (:func:`config_text`): every option with the value used, absolute
input paths, the subject's measures; running ``pipeline ik --config`` with it reproduces the
run. Unknown sections and keys, wrong types and values are refused naming the file and the key.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from pipeline.errors import InputError

__all__ = ["IK_KEYS", "SUBJECT_KEYS", "Config", "config_text", "read_config"]

SUBJECT_KEYS = ("sex", "height_m", "shank_lateral_m", "shank_medial_m", "knee_width_m",
                "ankle_width_m")  # fmt: skip
#: ``[ik]`` keys and the TOML types each accepts (besides the :class:`IKOptions` fields, the input
#: and output paths).
IK_KEYS: dict[str, tuple[type, ...]] = {
    "orientations": (str,),
    "out": (str,),
    "knee": (str,),
    "correction": (str,),
    "knee_axis_femur": (list,),
    "knee_axis_tibia": (list,),
    "segment_orientations": (bool,),
    "calibration_pose": (str,),
    "static_trial": (str,),
    "filter": (str,),
    "calibration_method": (str,),
    "drift": (str,),
    "sensor_to_model": (list,),
    "heading": (str,),
    "foot_length_m": (float, int),
    "joint_limits": (bool,),
    "strict": (bool,),
    "rerun": (bool,),
    "osim": (bool,),
}
_PATHS = ("orientations", "out", "static_trial")
_TYPE_NAMES = {str: "text", list: "a list of numbers", bool: "true or false", float: "a number",
               int: "a number"}  # fmt: skip


@dataclass(frozen=True)
class Config:
    """What a configuration file holds: ``subject`` (``[subject]`` keys -> values), ``sensors``
    (our name -> the recording's), ``ik`` (option -> value, paths made absolute)."""

    subject: dict[str, object]
    sensors: dict[str, str]
    ik: dict[str, object]
    source: Path | None = None


def read_config(path: str | Path) -> Config:
    """Read and check a configuration file (module docstring)."""
    import tomllib  # here: ~10 ms of import that a command without --config does not pay

    path = Path(path)
    try:
        with open(path, "rb") as fh:
            data = tomllib.load(fh)
    except FileNotFoundError:
        raise InputError("no such configuration file", file=path) from None
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"not valid TOML: {exc}", file=path) from None
    unknown = set(data) - {"subject", "sensors", "ik"}
    if unknown:
        raise InputError(f"unknown section(s) {sorted(unknown)}; expected [subject], [sensors], "
                         "[ik]", file=path, field=sorted(unknown)[0])  # fmt: skip
    for section in data:
        if not isinstance(data[section], dict):
            raise InputError("expected a table", file=path, field=section)
    subject = dict(data.get("subject", {}))
    for key, value in subject.items():
        if key not in SUBJECT_KEYS:
            raise InputError(f"unknown key; expected one of {list(SUBJECT_KEYS)}", file=path,
                             field=f"subject.{key}")  # fmt: skip
        want = (str,) if key == "sex" else (float, int)
        _check_type(value, want, path, f"subject.{key}")
    sensors = dict(data.get("sensors", {}))
    for key, value in sensors.items():
        _check_type(value, (str,), path, f"sensors.{key}")
    ik = dict(data.get("ik", {}))
    for key, value in ik.items():
        if key not in IK_KEYS:
            raise InputError(f"unknown key; expected one of {list(IK_KEYS)}", file=path,
                             field=f"ik.{key}")  # fmt: skip
        _check_type(value, IK_KEYS[key], path, f"ik.{key}")
        if key in _PATHS:
            p = Path(value).expanduser()
            ik[key] = str(p if p.is_absolute() else (path.parent / p).resolve())
    return Config(subject, sensors, ik, path)


def _check_type(value: object, types: tuple[type, ...], path: Path, key: str) -> None:
    ok = isinstance(value, types) and not (isinstance(value, bool) and bool not in types)
    if ok and list in types:
        ok = all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
    if not ok:
        raise InputError(f"expected {_TYPE_NAMES[types[0]]}, got {value!r}", file=path, field=key)


def config_text(
    measures: object,
    options: object,
    *,
    orientations: str | Path,
    header: str = "",
) -> str:
    """The resolved configuration of a run as TOML text: the subject's ``measures``
    (:class:`~pipeline.model.anthropometry.Measures`), every field of ``options``
    (:class:`~pipeline.process.IKOptions`; unset optional values are left out, as TOML has no
    null) and the absolute input path."""
    import tomli_w

    subject = {k: v for k, v in dataclasses.asdict(measures).items() if v is not None}
    opts = options.as_dict()
    sensors = dict(opts.pop("sensor_map"))
    ik: dict[str, object] = {"orientations": str(Path(orientations).resolve())}
    for key, value in opts.items():
        if value is None:
            continue
        if key == "static_trial":
            value = str(Path(value).resolve())
        ik[key] = value
    doc: dict[str, Mapping[str, object]] = {"subject": subject}
    if sensors:
        doc["sensors"] = sensors
    doc["ik"] = ik
    comment = "".join(f"# {line}\n" if line else "#\n" for line in header.splitlines())
    return comment + tomli_w.dumps(doc)
