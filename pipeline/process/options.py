"""Every option of ``pipeline ik`` in one checked value: :class:`IKOptions`.

The CLI, the configuration file (:mod:`pipeline.io.config`) and the Python API
(:func:`pipeline.process.process_recording`) all build one of these, so an option means the same
thing everywhere and a configuration file written by a run holds exactly what made it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from pipeline.calibration.conventions import (
    CALIBRATION_POSES,
    CORRECTIONS,
    DEFAULT_CALIBRATION_POSE,
    DEFAULT_CORRECTION,
    DEFAULT_METHOD,
    DRIFT_CORRECTIONS,
    FILTERS,
    METHODS,
)
from pipeline.calibration.heading import HEADINGS
from pipeline.errors import InputError
from pipeline.io.opensim import SENSOR_TO_SEGMENT
from pipeline.model.conventions import DEFAULT_KNEE, KNEE_MODES
from pipeline.process.sensors import SENSOR_ALIASES

__all__ = ["IKOptions", "check_sensor_to_model"]

_FOOT_LENGTH_RANGE_M = (0.15, 0.35)


@dataclass(frozen=True)
class IKOptions:
    """How a recording is turned into joint angles and landmarks (SI units, radians).

    Attributes:
        knee: ``'free'`` (3 rotations, Wang eq 15-17) or ``'hinge'`` (one about the knee AoR).
        correction: knee-AoR orientation correction ``'none'``, ``'aor'`` (Wang eq 9-13, the
            default) or ``'aor-ipopt'`` (:mod:`pipeline.calibration.correction`).
        knee_axis_femur, knee_axis_tibia: the subject's own knee AoR (right-leg ISB femoral and
            tibial frames, pointing right; normalised); default the population mean of the
            subject's sex (``models/wang2023_knee_aor.csv``). The hinge knee turns about it and
            the correction aims at it. Both or neither.
        segment_orientations: the recording holds segment orientations (ISB frames) rather than
            sensor orientations: no sensor placement is estimated.
        calibration_pose: what the first sample (or the static trial) shows: ``'standing'``,
            ``'supine'`` or ``'seated'``.
        static_trial: path of a separate static recording that gives the calibration pose (the
            mean orientation of each sensor over it); None: the first sample of the trial.
        filter: the attitude filter for raw signals, ``'vqf'`` or ``'pi'``; None: the
            recording's own orientations, VQF where it has none (:mod:`pipeline.process.signals`).
        sensor_to_model: fixed world rotation (rad, space-fixed XYZ, OpenSense's
            ``sensor_to_opensim_rotations``) making the world's y axis point up; None: y-up.
        heading: ``'anatomical'`` or ``'pelvis_imu:<axis>'``
            (:mod:`pipeline.calibration.heading`).
        foot_length_m: heel-to-toe foot length; default from the height (Drillis & Contini).
        joint_limits: keep the joints within the model's ranges (the knee cannot hyperextend).
        sensor_map: our sensor name (``pelvis_imu``, ``femur_r_imu``, ...) -> the name (or a
            unique part of it, e.g. an Xsens id) of the recording's sensor to use for it.
        strict: implausible results raise :class:`~pipeline.errors.QualityError`.
        calibration_method: the joint-constraint calibration of knees with raw signals
            (:mod:`pipeline.process.functional`; reported): ``'ipopt'``, ``'gn'``,
            ``'dwpso'``, ``'gwo'``, or ``'none'`` to skip it.
        drift: heading drift between the sensors (:mod:`pipeline.process.drift`): ``'auto'``
            (corrected for 6-D filter output), ``'joints'`` (always, where the joints'
            calibrations hold) or ``'none'``.
        rerun: write the rerun recording (``pipeline ik`` only).
        osim: also write the model as an OpenSim ``.osim`` whose coordinates are the ``.mot``'s
            columns (``pipeline ik`` only).
    """

    knee: str = DEFAULT_KNEE
    correction: str = DEFAULT_CORRECTION
    knee_axis_femur: tuple[float, float, float] | None = None
    knee_axis_tibia: tuple[float, float, float] | None = None
    segment_orientations: bool = False
    calibration_pose: str = DEFAULT_CALIBRATION_POSE
    static_trial: str | None = None
    filter: str | None = None
    sensor_to_model: tuple[float, float, float] | None = None
    heading: str = "anatomical"
    foot_length_m: float | None = None
    joint_limits: bool = True
    sensor_map: Mapping[str, str] = field(default_factory=dict)
    strict: bool = False
    calibration_method: str = DEFAULT_METHOD
    drift: str = "auto"
    rerun: bool = True
    osim: bool = False

    def __post_init__(self) -> None:
        _choice("knee", self.knee, KNEE_MODES)
        _choice("correction", self.correction, CORRECTIONS)
        _choice("calibration_pose", self.calibration_pose, CALIBRATION_POSES)
        _choice("heading", self.heading, HEADINGS)
        if self.filter is not None:
            _choice("filter", self.filter, FILTERS)
        _choice("calibration_method", self.calibration_method, (*METHODS, "none"))
        _choice("drift", self.drift, DRIFT_CORRECTIONS)
        for name in ("segment_orientations", "joint_limits", "strict", "rerun", "osim"):
            if not isinstance(getattr(self, name), bool):
                raise InputError(f"expected true or false, got {getattr(self, name)!r}",
                                 field=name)  # fmt: skip
        axes = (self.knee_axis_femur, self.knee_axis_tibia)
        if (axes[0] is None) != (axes[1] is None):
            raise InputError("expected both knee axes (femur and tibia) or neither",
                             field="knee_axis_femur")  # fmt: skip
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
                                 field="foot_length_m")  # fmt: skip
            object.__setattr__(self, "foot_length_m", v)
        if self.static_trial is not None and not isinstance(self.static_trial, str):
            object.__setattr__(self, "static_trial", str(self.static_trial))
        if not isinstance(self.sensor_map, Mapping):
            raise InputError("expected a table of sensor = name pairs", field="sensor_map")
        for key, value in self.sensor_map.items():
            if key not in SENSOR_TO_SEGMENT and key not in SENSOR_ALIASES:
                names = sorted(set(SENSOR_TO_SEGMENT) | set(SENSOR_ALIASES))
                raise InputError(f"expected a sensor name among {names}, got "
                                 f"{key!r}", field=f"sensors.{key}")  # fmt: skip
            if not isinstance(value, str) or not value:
                raise InputError(f"expected the recording's sensor name or id as text, got "
                                 f"{value!r}", field=f"sensors.{key}")  # fmt: skip
        object.__setattr__(self, "sensor_map", dict(self.sensor_map))

    def replace(self, **changes: object) -> IKOptions:
        """A copy with some options changed (checked again)."""
        unknown = set(changes) - {f.name for f in dataclasses.fields(self)}
        if unknown:
            raise InputError(f"unknown option(s) {sorted(unknown)}; expected some of "
                             f"{[f.name for f in dataclasses.fields(self)]}")  # fmt: skip
        return dataclasses.replace(self, **changes)

    def as_dict(self) -> dict[str, object]:
        """Option name -> value (lists for vectors), None for an unset optional value."""
        out: dict[str, object] = {}
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            out[f.name] = list(v) if isinstance(v, tuple) else (dict(v) if f.name == "sensor_map"
                                                                 else v)  # fmt: skip
        return out


def _choice(name: str, value: object, choices: tuple[str, ...]) -> None:
    if value not in choices:
        raise InputError(f"expected one of {list(choices)}, got {value!r}", field=name)


def _number(v: object, name: str) -> float:
    if isinstance(v, bool) or not isinstance(v, (int, float, np.floating, np.integer)):
        raise InputError(f"expected a number, got {v!r}", field=name)
    x = float(v)
    if not np.isfinite(x):
        raise InputError(f"expected a finite number, got {v!r}", field=name)
    return x


def _unit(a: object, name: str) -> tuple[float, float, float]:
    try:
        seq = list(a)  # type: ignore[call-overload]
    except TypeError:
        raise InputError(f"expected three numbers, got {a!r}", field=name) from None
    v = np.array([_number(x, name) for x in seq])
    if v.shape != (3,):
        raise InputError(f"expected three numbers, got {len(v)}", field=name)
    n = float(np.linalg.norm(v))
    if n < 1e-9:
        raise InputError("expected a non-zero axis, got a zero vector", field=name)
    if v[2] <= 0:
        raise InputError(f"expected an axis pointing right (z > 0 in the right-leg frame), got "
                         f"{v.tolist()}", field=name)  # fmt: skip
    return tuple(float(x) for x in v / n)  # type: ignore[return-value]


def check_sensor_to_model(angles: object) -> tuple[float, float, float]:
    """The three ``sensor_to_model`` angles (rad) if finite and within [-2 pi, 2 pi]; refused
    otherwise, with a hint when they look like degrees (e.g. ``-90 0 0`` for ``-1.5708 0 0``)."""
    try:
        a = np.asarray(angles, dtype=float).ravel()
    except (TypeError, ValueError):
        raise InputError(f"expected three angles in radians, got {angles!r}",
                         field="sensor_to_model") from None  # fmt: skip
    if a.shape != (3,):
        raise InputError(f"expected three angles, got {a.size}", field="sensor_to_model")
    if not np.all(np.isfinite(a)):
        raise InputError(f"expected finite angles in radians, got {a.tolist()}",
                         field="sensor_to_model")  # fmt: skip
    if np.any(np.abs(a) > 2 * np.pi + 1e-9):
        rad = " ".join(f"{v:.4f}" for v in np.radians(a))
        raise InputError(
            f"angles {a.tolist()} exceed 2 pi: they are radians; if you meant degrees, give "
            f"{rad}",
            field="sensor_to_model",
        )
    return float(a[0]), float(a[1]), float(a[2])
