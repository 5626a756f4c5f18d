"""Every option of ``pipeline ik``, each defined once (:func:`pipeline.option.option`): its type,
default, help, flag, configuration-file key and manifest column all follow from its field here.

Four groups, one dataclass each, each checking its own values:

* :class:`~pipeline.model.measures.Measures`: the subject (``[subject]`` in the file);
* :class:`InputOptions`: what is read (the recording, a static trial, the sensor map);
* :class:`IKOptions`: how a recording becomes joint angles (what
  :func:`pipeline.process.process_recording` takes; it writes nothing);
* :class:`OutputOptions`: what is written and where (the output folder, the switches).

:func:`resolve_settings` merges a configuration file (:mod:`pipeline.io.config`) with the values
a user gave (flags, a manifest row), which override it, into :class:`IKSettings`;
:func:`settings_text` writes them back as the file that reproduces the run. Importable at no
cost (no NumPy): ``pipeline --help`` is built from it.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass
from numbers import Real
from pathlib import Path

from pipeline.calibration.conventions import (
    CALIBRATIONS,
    CORRECTIONS,
    DEFAULT_CALIBRATION_POSE,
    DEFAULT_CORRECTION,
    DEFAULT_FILTER,
    DEFAULT_METHOD,
    DRIFT_CORRECTIONS,
    FILTERS,
    HEADINGS,
    METHODS,
    POSTURES,
)
from pipeline.errors import InputError
from pipeline.io.sensor_names import SENSOR_NAMES
from pipeline.model.conventions import DEFAULT_KNEE, KNEE_MODES
from pipeline.model.measures import Measures
from pipeline.option import Spec, option, specs

__all__ = [
    "GROUPS",
    "IKOptions",
    "IKSettings",
    "InputOptions",
    "OutputOptions",
    "all_specs",
    "check_sensor_to_model",
    "resolve_settings",
    "settings_text",
]

_FOOT_LENGTH_RANGE_M = (0.15, 0.35)
_FORMATS = ("an OpenSim .sto of quaternions, one IMU file (our CSV, Movella DOT .csv, Xsens MT "
            ".txt), or a folder of them (Xsens MT .txt exports, <sensor>.csv, Movella DOT "
            ".csv, x-IMU3 device folders), or example:NAME, a recording shipped with the "
            "package (example:ximu3_lower_body, example:opensense_imu_ik_test)")


@dataclass(frozen=True)
class IKOptions:
    """How a recording is turned into joint angles and landmarks (SI units, radians); each field's
    help says what it does (``pipeline ik --help`` prints the same)."""

    knee: str = option(DEFAULT_KNEE, "choice", "knee model: free (3 rotations, Wang eq 15-17) or "
                       "hinge (one about the knee AoR)", choices=KNEE_MODES)
    correction: str = option(DEFAULT_CORRECTION, "choice", "knee-AoR orientation correction: "
                             "Wang eq 9-13 closed form (aor), whole-trial IPOPT (aor-ipopt), "
                             "towards the gyroscopes' hinge axis where the knee's functional "
                             "calibration is trusted (functional), or none",
                             choices=CORRECTIONS)
    knee_axis_femur: tuple[float, float, float] | None = option(
        None, "vec3", "the subject's knee AoR in the femur frame (pointing right), for the hinge "
        "and the correction; both or neither (default: the population mean of the subject's sex)")
    knee_axis_tibia: tuple[float, float, float] | None = option(
        None, "vec3", "the subject's knee AoR in the tibia frame (pointing right)")
    segment_orientations: bool = option(False, "bool", "the orientations are segment frames "
                                        "(ISB), e.g. an Xsens MVN suit export: no sensor "
                                        "placement is estimated")
    calibration_pose: str = option(DEFAULT_CALIBRATION_POSE, "choice", "the pose the subject "
                                   "holds still somewhere in the recording (or in "
                                   "--static-trial), found and checked; walking: none, each "
                                   "sensor calibrated from the walk (also where no still "
                                   "window shows the pose)", choices=CALIBRATIONS)
    filter: str | None = option(None, "choice", "attitude filter for raw gyroscope and "
                                "accelerometer (and magnetometer) signals; also replaces "
                                "orientations the recording has (default: the recording's own "
                                f"orientations, {DEFAULT_FILTER} where it has none)",
                                choices=FILTERS)
    sensor_to_model: tuple[float, float, float] | None = option(
        None, "vec3", "fixed world rotation (rad, space-fixed XYZ) as OpenSense's "
        "sensor_to_opensim_rotations, making the world's y axis point up (default: y up already); "
        "an Xsens z-up world needs -1.5708 0 0", metavar=("RX", "RY", "RZ"))
    heading: str = option("anatomical", "choice", "how the subject's forward direction is found "
                          "at the calibration pose: from hip and knee flexion (anatomical, "
                          "independent of sensor mounting) or OpenSense's pelvis_imu:-z style",
                          choices=HEADINGS, metavar="{anatomical,pelvis_imu:AXIS}")
    foot_length_m: float | None = option(None, "float", "heel-to-toe foot length in metres "
                                         "(default: 0.152 x height, Drillis & Contini 1966)")
    joint_limits: bool = option(True, "bool", "keep the joints within the model's ranges",
                                off="let the joints leave the model's ranges")
    calibration_method: str = option(DEFAULT_METHOD, "choice", "joint-constraint calibration of "
                                     "knees with raw signals, reported with its trust decision "
                                     "(none skips it)", choices=(*METHODS, "none"))
    drift: str = option("auto", "choice", "sensors whose headings are their own (6-D filter "
                        "output, a disturbed magnetometer's sensor) turned into their neighbours' "
                        "world by the joints (auto), every sensor so (joints), or none",
                        choices=DRIFT_CORRECTIONS)
    posture: str = option("measured", "choice", "the standing posture at the calibration pose: "
                          "the femurs' and tibias' forward lean measured from the joint centres "
                          "the raw signals locate (measured; upright where they cannot), or the "
                          "model's neutral pose with every joint at zero (neutral)",
                          choices=POSTURES)

    def __post_init__(self) -> None:
        for s in specs(IKOptions):
            value = getattr(self, s.name)
            if s.kind == "choice" and not (value is None and s.default is None):
                _choice(s.name, value, s.choices)
            elif s.kind == "bool":
                _bool(s.name, value)
        axes = (self.knee_axis_femur, self.knee_axis_tibia)
        if (axes[0] is None) != (axes[1] is None):
            raise InputError("expected both knee axes (femur and tibia) or neither",
                             field="knee_axis_femur")
        for name, a in zip(("knee_axis_femur", "knee_axis_tibia"), axes, strict=True):
            if a is not None:
                object.__setattr__(self, name, _unit(a, name))
        if self.sensor_to_model is not None:
            object.__setattr__(self, "sensor_to_model", check_sensor_to_model(self.sensor_to_model))
        if self.foot_length_m is not None:
            v = _number(self.foot_length_m, "foot_length_m")
            lo, hi = _FOOT_LENGTH_RANGE_M
            if not lo <= v <= hi:
                hint = " (looks like cm or mm: give metres)" if v > hi else ""
                raise InputError(f"expected a foot length of {lo}-{hi} m, got {v}{hint}",
                                 field="foot_length_m")
            object.__setattr__(self, "foot_length_m", v)

    def replace(self, **changes: object) -> IKOptions:
        """A copy with some options changed (checked again)."""
        return _replace(self, changes)

    def as_dict(self) -> dict[str, object]:
        """Option name -> value (lists for vectors), None for an unset optional value."""
        return {f.name: (list(v) if isinstance(v := getattr(self, f.name), tuple) else v)
                for f in dataclasses.fields(self)}


@dataclass(frozen=True)
class InputOptions:
    """What ``pipeline ik`` reads: the recording, a static trial, and our sensor names for the
    recording's (``pelvis_imu`` -> ``00B421AF``, or any unique part of a name)."""

    orientations: str = option(None, "path", f"the recording: {_FORMATS}", required=True,
                               metavar="PATH")
    static_trial: str | None = option(None, "path", "a separate static recording (same sensors) "
                                      "that gives the calibration pose (default: the first sample "
                                      "of the trial)", metavar="PATH")
    sensor_map: Mapping[str, str] = option({}, "pairs", "our sensor name = the recording's "
                                           "sensor name, label or device id (a unique part of "
                                           "it), e.g. pelvis_imu=00B421AF femur_r_imu=thigh_R "
                                           "(default: the names as they are)", section="sensors",
                                           metavar="NAME=ID",
                                           aliases=("--xsens-map",))
    ignore: tuple[str, ...] = option((), "words", "entries of a recording folder to leave out "
                                     "(file name patterns, e.g. notes.txt '*.log'), each named "
                                     "in the summary (default: none; any other entry that is not "
                                     "a recording is an error)", metavar="PATTERN")

    def __post_init__(self) -> None:
        if isinstance(self.ignore, str) or not all(isinstance(p, str) for p in self.ignore):
            raise InputError(f"expected file name patterns, got {self.ignore!r}", field="ignore")
        object.__setattr__(self, "ignore", tuple(self.ignore))
        for name in ("orientations", "static_trial"):
            v = getattr(self, name)
            if v is not None and not isinstance(v, (str, Path)):
                raise InputError(f"expected a path, got {v!r}", field=name)
            if v is not None:
                object.__setattr__(self, name, str(v))
        if not isinstance(self.sensor_map, Mapping):
            raise InputError("expected a table of sensor = name pairs", field="sensor_map")
        for key, value in self.sensor_map.items():
            if key not in SENSOR_NAMES:
                raise InputError(f"expected a sensor name among {list(SENSOR_NAMES)}, got "
                                 f"{key!r}", field=f"sensors.{key}")
            if not isinstance(value, str) or not value:
                raise InputError(f"expected the recording's sensor name or id as text, got "
                                 f"{value!r}", field=f"sensors.{key}")
        object.__setattr__(self, "sensor_map", dict(self.sensor_map))

    def replace(self, **changes: object) -> InputOptions:
        return _replace(self, changes)


#: Where ``<name>_landmarks.csv``'s positions are: relative to the pelvis, or in the room.
LANDMARK_FRAMES = ("pelvis", "world")


@dataclass(frozen=True)
class OutputOptions:
    """What ``pipeline ik`` writes, and where."""

    out: str = option(None, "path", "output folder", required=True, metavar="DIR")
    name: str | None = option(None, "text", "the outputs' name (<name>_ik.mot, ...; default: the "
                              "recording's file or folder name; a generic folder name such as "
                              "imu or data: its parent folder's)")
    rerun: bool = option(True, "bool", "write the .rrd recording (rerun)",
                         off="do not write the .rrd recording (rerun)")
    report: bool = option(True, "bool", "write <name>_report.html, the one-page gait report "
                          "(needs matplotlib, the 'report' extra: without it the run says so "
                          "and writes the rest)", off="do not write <name>_report.html")
    osim: bool = option(False, "bool", "also write <name>.osim, an OpenSim model whose "
                        "coordinates are the .mot's columns")
    landmarks: str = option("pelvis", "choice", "landmark positions in <name>_landmarks.csv "
                            "relative to the pelvis (pelvis) or in the room (world: carried by "
                            "the feet, with a foot sensor on each foot; else relative to the "
                            "pelvis, with a note)", choices=LANDMARK_FRAMES)
    overwrite: bool = option(False, "bool", "replace a previous run's outputs of the same "
                             "recording in --out, removing its files of that name first (e.g. "
                             "an old .osim or .rrd); without it such a run is refused, naming "
                             "the files")
    strict: bool = option(False, "bool", "implausible results (e.g. a large orientation "
                          "residual) exit with code 3 and write nothing (otherwise they are "
                          "flagged in the summary and on stderr)")

    def __post_init__(self) -> None:
        if self.out is not None and not isinstance(self.out, (str, Path)):
            raise InputError(f"expected a path, got {self.out!r}", field="out")
        if self.out is not None:
            object.__setattr__(self, "out", str(self.out))
        for s in specs(OutputOptions):
            if s.kind == "bool":
                _bool(s.name, getattr(self, s.name))
            elif s.kind == "choice":
                _choice(s.name, getattr(self, s.name), s.choices)

    def replace(self, **changes: object) -> OutputOptions:
        return _replace(self, changes)


#: The option groups of ``pipeline ik``, in the order of its help.
GROUPS = (InputOptions, Measures, IKOptions, OutputOptions)


def all_specs() -> list[Spec]:
    """Every option of ``pipeline ik`` (the flags, the file's keys, the manifest's columns)."""
    return specs(*GROUPS)


@dataclass(frozen=True)
class IKSettings:
    """A run of ``pipeline ik`` resolved: the subject, the inputs, the options, the outputs."""

    subject: Measures
    inputs: InputOptions
    options: IKOptions
    outputs: OutputOptions


def resolve_settings(config: str | Path | None, values: Mapping[str, object]) -> IKSettings:
    """:class:`IKSettings` from a configuration file (optional) and ``values`` (option name ->
    value, None = not given; flags or a manifest row), which override the file's. Refused with
    the file and the key when an option is missing, unknown or wrong."""
    from pipeline.io.config import read_config

    merged: dict[str, object] = {}
    where = None
    if config is not None:
        merged.update(read_config(config, all_specs()))
        where = Path(config)
    known = {s.name for s in all_specs()}
    unknown = sorted(set(values) - known)
    if unknown:
        raise InputError(f"unknown option(s) {unknown}", file=where)
    for key, value in values.items():
        if value is None:
            continue
        if key == "sensor_map" and merged.get("sensor_map"):  # flags add to the file's table
            value = {**merged["sensor_map"], **value}  # type: ignore[dict-item]
        merged[key] = value
    for s in all_specs():
        if s.required and s.name not in merged:
            table = f"[{s.section}] {s.name}"
            raise InputError(f"{s.flag} is required (or {table} in the configuration file)",
                             file=where)
    try:
        return IKSettings(*(_build(cls, merged) for cls in (Measures, InputOptions, IKOptions,
                                                            OutputOptions)))
    except InputError as exc:
        if exc.file is None and where is not None:
            raise InputError(exc.message, file=where, field=exc.field) from None
        raise


#: Options that say where and how to write, not what the run computes: not in ``_config.toml``.
NOT_RECORDED = ("out", "overwrite")


def settings_text(settings: IKSettings, header: str = "") -> str:
    """The resolved configuration as TOML text (every option with the value used, absolute
    paths; unset optional values left out): ``pipeline ik --config`` with it reproduces the run
    (the output folder and ``overwrite`` are not written: :data:`NOT_RECORDED`)."""
    from pipeline.io.config import config_text
    from pipeline.option import to_toml

    doc: dict[str, dict[str, object]] = {"subject": {}, "sensors": {}, "ik": {}}
    for group in (settings.subject, settings.inputs, settings.options, settings.outputs):
        for s in specs(type(group)):
            if s.name in NOT_RECORDED:
                continue
            v = to_toml(s, getattr(group, s.name))
            if v is None:
                continue
            if s.kind == "pairs":
                doc[s.section].update(v)  # type: ignore[arg-type]
            else:
                doc[s.section][s.name] = v
    return config_text({k: v for k, v in doc.items() if v}, header)


def _build(cls: type, values: Mapping[str, object]) -> object:
    names = {s.name for s in specs(cls)}
    return cls(**{k: v for k, v in values.items() if k in names})


def _replace(obj, changes: Mapping[str, object]):
    unknown = set(changes) - {f.name for f in dataclasses.fields(obj)}
    if unknown:
        raise InputError(f"unknown option(s) {sorted(unknown)}; expected some of "
                         f"{[f.name for f in dataclasses.fields(obj)]}")
    return dataclasses.replace(obj, **changes)


def _choice(name: str, value: object, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise InputError(f"expected one of {list(choices)}, got {value!r}", field=name)


def _bool(name: str, value: object) -> None:
    if not isinstance(value, bool):
        raise InputError(f"expected true or false, got {value!r}", field=name)


def _number(v: object, name: str) -> float:
    if isinstance(v, bool) or not isinstance(v, Real):
        raise InputError(f"expected a number, got {v!r}", field=name)
    x = float(v)
    if not math.isfinite(x):
        raise InputError(f"expected a finite number, got {v!r}", field=name)
    return x


def _three(a: object, name: str) -> list[float]:
    try:
        seq = list(a)  # type: ignore[call-overload]
    except TypeError:
        raise InputError(f"expected three numbers, got {a!r}", field=name) from None
    if len(seq) != 3:
        raise InputError(f"expected three numbers, got {len(seq)}", field=name)
    return [_number(x, name) for x in seq]


def _unit(a: object, name: str) -> tuple[float, float, float]:
    v = _three(a, name)
    n = math.sqrt(sum(x * x for x in v))
    if n < 1e-9:
        raise InputError("expected a non-zero axis, got a zero vector", field=name)
    if v[2] <= 0:
        raise InputError(f"expected an axis pointing right (z > 0 in the right-leg frame), got "
                         f"{v}", field=name)
    return tuple(x / n for x in v)  # type: ignore[return-value]


def check_sensor_to_model(angles: object) -> tuple[float, float, float]:
    """The three ``sensor_to_model`` angles (rad) if finite and within [-2 pi, 2 pi]; refused
    otherwise, with a hint when they look like degrees (e.g. ``-90 0 0`` for ``-1.5708 0 0``)."""
    try:
        seq = [float(x) for x in (angles if hasattr(angles, "__iter__") else [angles])]  # type: ignore[union-attr]
    except (TypeError, ValueError):
        raise InputError(f"expected three angles in radians, got {angles!r}",
                         field="sensor_to_model") from None
    if len(seq) != 3:
        raise InputError(f"expected three angles, got {len(seq)}", field="sensor_to_model")
    if not all(math.isfinite(x) for x in seq):
        raise InputError(f"expected finite angles in radians, got {seq}", field="sensor_to_model")
    if any(abs(x) > 2 * math.pi + 1e-9 for x in seq):
        rad = " ".join(f"{math.radians(x):.4f}" for x in seq)
        raise InputError(f"angles {seq} exceed 2 pi: they are radians; if you meant degrees, give "
                         f"{rad}", field="sensor_to_model")
    return seq[0], seq[1], seq[2]
