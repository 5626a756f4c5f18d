"""OpenSim files: ``.sto`` orientation tables (OpenSense) and ``.mot``/``.sto`` numeric tables.

Orientation ``.sto`` (what OpenSense reads and writes)::

    DataRate=100.000000
    DataType=Quaternion
    version=3
    OpenSimVersion=4.2
    endheader
    time<TAB>torso_imu<TAB>pelvis_imu ...
    0<TAB>w,x,y,z<TAB>w,x,y,z ...

Each cell is a scalar-first quaternion giving the sensor's orientation in the IMU world frame.
OpenSense's conventions (a fixed ``sensor_to_opensim_rotations`` taking the IMU world to
OpenSim's y-up world, the first sample as calibration pose, heading from the pelvis sensor) are
applied elsewhere; :func:`rotate_world` and :func:`sensor_to_opensim_matrix` provide the first.

Numeric ``.mot`` (OpenSim Storage, version 1): ``name``, ``version=1``, ``nRows``, ``nColumns``
(time included), ``inDegrees=yes|no``, ``endheader``, then a tab-separated table starting with
``time``. Inside the pipeline angles are radians; :func:`write_mot` converts to degrees when
``in_degrees`` and :func:`read_mot` converts back, for the angular columns (all but OpenSim's
translational coordinates ``*_tx``, ``*_ty``, ``*_tz`` unless told otherwise).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.atomic import atomic_write
from pipeline.io.checks import (
    check_quaternions,
    check_rate,
    check_time,
    make_quaternions_continuous,
)
from pipeline.io.gaps import DEFAULT_MAX_GAP_S, fill_gaps
from pipeline.io.notes import Notes
from pipeline.io.text import parse_table, read_text_lines
from pipeline.rotations import matrix_from_quat, quat_from_matrix, rot_x, rot_y, rot_z

__all__ = [
    "SENSOR_TO_SEGMENT",
    "MotTable",
    "OrientationTrial",
    "map_sensors",
    "read_mot",
    "read_orientations_sto",
    "rotate_world",
    "sensor_to_opensim_matrix",
    "write_mot",
    "write_orientations_sto",
]

SENSOR_TO_SEGMENT: dict[str, str] = {
    "pelvis_imu": "pelvis",
    "femur_r_imu": "right_femur",
    "tibia_r_imu": "right_tibia",
    "calcn_r_imu": "right_foot",
    "femur_l_imu": "left_femur",
    "tibia_l_imu": "left_tibia",
    "calcn_l_imu": "left_foot",
    "torso_imu": "torso",
}
"""OpenSense sensor column name -> segment name used by the pipeline."""


@dataclass(frozen=True)
class OrientationTrial:
    """IMU orientations on one time base.

    ``sensors[name]`` is ``(N, 4)`` unit quaternions ``[w, x, y, z]`` (sign-continuous): the
    sensor frame's orientation in the IMU world frame, ``p_world = R(q) p_sensor``.
    """

    time: np.ndarray
    rate_hz: float
    sensors: dict[str, np.ndarray]
    header: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    source: Path | None = None

    @property
    def n_samples(self) -> int:
        return int(self.time.size)

    @property
    def sensor_names(self) -> tuple[str, ...]:
        return tuple(self.sensors)


def _split_header(lines: list[str], path: Path) -> tuple[str, dict[str, str], int]:
    """Header (name line, key=value pairs) and the index of the ``endheader`` line."""
    try:
        end = next(i for i, ln in enumerate(lines) if ln.strip().lower() == "endheader")
    except StopIteration:
        raise InputError(
            "no 'endheader' line: expected an OpenSim .sto/.mot header ending in 'endheader'",
            file=path,
        ) from None
    name, header = "", {}
    for i, ln in enumerate(lines[:end]):
        s = ln.strip()
        if "=" in s:
            k, v = s.split("=", 1)
            header[k.strip()] = v.strip()
        elif i == 0:
            name = s
    return name, header, end


def _labels_and_rows(lines: list[str], end: int, path: Path) -> tuple[list[str], list[str], int]:
    i = end + 1
    while i < len(lines) and not lines[i].strip():
        i += 1
    if i >= len(lines):
        raise InputError("no column labels after 'endheader'", file=path)
    labels = [s.strip() for s in lines[i].rstrip("\r\n").split("\t")]
    if labels[0].lower() != "time":
        raise InputError(
            f"first column must be 'time', found {labels[0]!r}", file=path, field="labels"
        )
    if len(set(labels)) != len(labels):
        dup = sorted({x for x in labels if labels.count(x) > 1})
        raise InputError(f"duplicate column label(s) {dup}", file=path, field="labels")
    rows = lines[i + 1 :]
    while rows and not rows[-1].strip():
        rows.pop()
    if not rows:
        raise InputError("no data rows after the column labels", file=path)
    return labels, rows, i + 2  # 1-based file line of the first data row


def _declared_rate(header: dict[str, str], path: Path) -> float | None:
    raw = header.get("DataRate")
    if raw is None:
        return None
    try:
        return float(raw)
    except ValueError:
        raise InputError(f"DataRate={raw!r} is not a number", file=path, field="DataRate") from None


def read_orientations_sto(
    path: str | Path,
    *,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
    rate_rtol: float = 0.01,
) -> OrientationTrial:
    """Read an OpenSense orientation ``.sto`` into an :class:`OrientationTrial`.

    Checks: header with ``endheader``; ``DataType=Quaternion`` when given; every row complete;
    every cell ``w,x,y,z``; time strictly increasing; rate from the time stamps equal to
    ``DataRate`` within ``rate_rtol``; missing quaternions (``nan`` cells) filled by slerp up to
    ``max_gap_s`` and refused beyond; quaternions unit (normalised within 10 %) and
    sign-continuous. Repairs are listed in ``notes``.
    """
    path = Path(path)
    lines = read_text_lines(path)
    _, header, end = _split_header(lines, path)
    dtype = header.get("DataType")
    if dtype is not None and dtype.lower() != "quaternion":
        raise InputError(
            f"DataType={dtype}: expected Quaternion (an orientation file); "
            "numeric tables are read with read_mot",
            file=path,
            field="DataType",
        )
    labels, rows, first_line = _labels_and_rows(lines, end, path)
    sensors_names = labels[1:]
    if not sensors_names:
        raise InputError("no sensor columns after 'time'", file=path, field="labels")
    flat = ["time"] + [f"{s}[{c}]" for s in sensors_names for c in "wxyz"]
    expanded = [ln.replace(",", "\t") for ln in rows]
    try:
        data = parse_table(expanded, flat, file=path, first_line=first_line)
    except InputError as e:
        raise InputError(
            e.message + f"; expected 'time' then {len(sensors_names)} cells 'w,x,y,z'",
            file=path,
            field=e.field,
        ) from None
    notes = Notes()
    time = check_time(data[:, 0], file=path, first_line=first_line)
    info = check_rate(time, _declared_rate(header, path), rtol=rate_rtol, notes=notes, file=path)
    sensors: dict[str, np.ndarray] = {}
    for k, name in enumerate(sensors_names):
        q = data[:, 1 + 4 * k : 5 + 4 * k]
        q = fill_gaps(
            time, q, kind="quaternion", max_gap_s=max_gap_s, notes=notes, file=path, field=name
        )
        sensors[name] = check_quaternions(
            q, notes=notes, file=path, field=name, first_line=first_line
        )
    return OrientationTrial(
        time=time,
        rate_hz=float(_declared_rate(header, path) or info.rate_hz),
        sensors=sensors,
        header=header,
        notes=notes.as_tuple(),
        source=path,
    )


def write_orientations_sto(path: str | Path, trial: OrientationTrial) -> Path:
    """Write an orientation ``.sto`` that OpenSense reads (atomic; full double precision)."""
    path = Path(path)
    names = list(trial.sensors)
    head = [
        f"DataRate={trial.rate_hz:.6f}",
        "DataType=Quaternion",
        "version=3",
        "OpenSimVersion=4.2",
        "endheader",
        "\t".join(["time", *names]),
    ]
    with atomic_write(path, newline="\n") as f:
        f.write("\n".join(head) + "\n")
        for i in range(trial.n_samples):
            cells = [repr(float(trial.time[i]))]
            for n in names:
                cells.append(",".join(repr(float(v)) for v in trial.sensors[n][i]))
            f.write("\t".join(cells) + "\n")
    return path


# --------------------------------------------------------------------------------------------
# world rotation and sensor names


def sensor_to_opensim_matrix(rotations_xyz: Iterable[float]) -> np.ndarray:
    """OpenSense's ``sensor_to_opensim_rotations`` as a matrix.

    OpenSense builds a space-fixed X-Y-Z sequence: ``R = Rz(c) Ry(b) Rx(a)`` for
    ``(a, b, c)``; e.g. ``(-pi/2, 0, 0)`` takes an Xsens z-up world to OpenSim's y-up world.
    """
    a, b, c = (float(v) for v in rotations_xyz)
    return rot_z(c) @ rot_y(b) @ rot_x(a)


def rotate_world(trial: OrientationTrial, R: np.ndarray) -> OrientationTrial:
    """Express every orientation in a rotated world: ``R_sensor' = R @ R_sensor``.

    Pre-multiplication changes the world frame only; the sensor frames (and so the relative
    orientations between sensors) are unchanged. Returns a new trial with a note.
    """
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
        raise ValueError(f"expected a 3x3 rotation matrix, got {R!r}")
    sensors = {}
    for name, q in trial.sensors.items():
        rotated = quat_from_matrix(R @ matrix_from_quat(q))
        sensors[name] = make_quaternions_continuous(rotated)[0]
    angle = np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))
    note = f"world frame rotated by a fixed rotation of {angle:.4g} deg (pre-multiplied)"
    return dataclasses.replace(trial, sensors=sensors, notes=(*trial.notes, note))


def map_sensors(
    trial: OrientationTrial,
    required: Iterable[str] | None = None,
    mapping: Mapping[str, str] = SENSOR_TO_SEGMENT,
) -> dict[str, np.ndarray]:
    """Segment name -> ``(N, 4)`` quaternions, for every sensor column named in ``mapping``.

    ``required`` lists segment names that must be present (e.g. ``["pelvis", "right_femur",
    "right_tibia"]``); a missing one is refused naming the file, the sensor column expected for
    it and the columns available.
    """
    out = {seg: trial.sensors[s] for s, seg in mapping.items() if s in trial.sensors}
    if required is not None:
        seg_to_sensor = {seg: s for s, seg in mapping.items()}
        missing = [r for r in required if r not in out]
        if missing:
            unknown = [m for m in missing if m not in seg_to_sensor]
            if unknown:
                raise ValueError(f"unknown segment name(s) {unknown}; known: {list(seg_to_sensor)}")
            want = ", ".join(f"{seg_to_sensor[m]} (for {m})" for m in missing)
            raise InputError(
                f"missing sensor column(s) {want}; available columns: "
                f"{', '.join(trial.sensors) or 'none'}",
                file=trial.source,
            )
    return out


# --------------------------------------------------------------------------------------------
# numeric .mot / .sto tables

_TRANSLATION_SUFFIXES = ("_tx", "_ty", "_tz")


def _angle_columns(names: Iterable[str], angle_columns: Iterable[str] | None) -> set[str]:
    if angle_columns is not None:
        return set(angle_columns)
    return {n for n in names if not n.endswith(_TRANSLATION_SUFFIXES)}


@dataclass(frozen=True)
class MotTable:
    """A numeric OpenSim table; ``columns`` in SI (angles in radians) whatever the file used."""

    time: np.ndarray
    columns: dict[str, np.ndarray]
    in_degrees: bool
    name: str = ""
    header: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    source: Path | None = None


def write_mot(
    path: str | Path,
    time: np.ndarray,
    columns: Mapping[str, np.ndarray],
    in_degrees: bool = True,
    *,
    angle_columns: Iterable[str] | None = None,
    name: str = "Coordinates",
) -> Path:
    """Write a version-1 OpenSim Storage table (``.mot``) atomically.

    ``columns`` hold SI values (angles in radians). With ``in_degrees`` the angular columns
    (``angle_columns``, default all but ``*_tx/_ty/_tz``) are written in degrees and the header
    says ``inDegrees=yes``, as OpenSim's IK output does.
    """
    path = Path(path)
    t = np.asarray(time, dtype=float).ravel()
    names = list(columns)
    if "time" in names:
        raise ValueError("'time' is passed separately, not as a column")
    cols = []
    for n in names:
        c = np.asarray(columns[n], dtype=float).ravel()
        if c.size != t.size:
            raise ValueError(f"column {n!r} has {c.size} values, time has {t.size}")
        cols.append(c)
    check_time(t, file=path, min_samples=1)
    ang = _angle_columns(names, angle_columns) if in_degrees else set()
    data = np.column_stack(
        [t] + [np.degrees(c) if n in ang else c for n, c in zip(names, cols, strict=True)]
    )
    head = [
        name,
        "version=1",
        f"nRows={t.size}",
        f"nColumns={len(names) + 1}",
        f"inDegrees={'yes' if in_degrees else 'no'}",
        "endheader",
        "\t".join(["time", *names]),
    ]
    with atomic_write(path, newline="\n") as f:
        f.write("\n".join(head) + "\n")
        for row in data:
            f.write("\t".join(f"{v:.17g}" for v in row) + "\n")
    return path


def read_mot(
    path: str | Path,
    *,
    angle_columns: Iterable[str] | None = None,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
) -> MotTable:
    """Read an OpenSim numeric ``.mot``/``.sto`` table; angles are returned in radians.

    Checks the header (``endheader``, ``nRows``/``nColumns`` against the data: a shorter table
    is reported as truncated), time strictly increasing, and fills short NaN gaps (noted).
    """
    path = Path(path)
    lines = read_text_lines(path)
    name, header, end = _split_header(lines, path)
    labels, rows, first_line = _labels_and_rows(lines, end, path)
    data = parse_table(rows, labels, file=path, first_line=first_line)
    for key, have in (("nRows", data.shape[0]), ("nColumns", data.shape[1])):
        if key in header:
            try:
                want = int(header[key])
            except ValueError:
                raise InputError(f"{key}={header[key]!r} is not an integer", file=path) from None
            if want != have:
                hint = " (file truncated?)" if key == "nRows" and have < want else ""
                raise InputError(
                    f"header says {key}={want} but the table has {have}{hint}",
                    file=path,
                    field=key,
                )
    in_deg = header.get("inDegrees", "no").strip().lower() == "yes"
    notes = Notes()
    time = check_time(data[:, 0], file=path, first_line=first_line, min_samples=1)
    names = labels[1:]
    ang = _angle_columns(names, angle_columns) if in_deg else set()
    cols = {}
    for k, n in enumerate(names):
        c = data[:, k + 1]
        if time.size > 1:
            c = fill_gaps(time, c, max_gap_s=max_gap_s, notes=notes, file=path, field=n)
        cols[n] = np.radians(c) if n in ang else c
    return MotTable(
        time=time,
        columns=cols,
        in_degrees=in_deg,
        name=name,
        header=header,
        notes=notes.as_tuple(),
        source=path,
    )
