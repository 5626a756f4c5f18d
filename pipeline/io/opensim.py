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
import re
from collections.abc import Iterable, Mapping
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
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SENSOR_TO_SEGMENT
from pipeline.io.sto_header import declared_rate, labels_and_rows, split_header
from pipeline.io.text import parse_table, read_text_lines
from pipeline.rotations import matrix_from_euler_xyz_fixed, matrix_from_quat, quat_from_matrix

__all__ = [
    "map_sensors",
    "read_orientations_sto",
    "rotate_world",
    "sensor_to_opensim_matrix",
    "write_orientations_sto",
]




_MISSING_CELL = re.compile(r"(?<=\t)(?:nan)?(?=\t|$)", re.IGNORECASE)


def _missing_cells(row: str, cells: int) -> str:
    """A row's empty (or single ``nan``) quaternion cells as four NaN: a sensor without that
    sample (its gap is filled or kept missing by :func:`~pipeline.io.gaps.fill_gaps`); a
    trailing tab after the row's ``cells`` cells is a separator, not a cell."""
    row = row.rstrip("\r")
    if row.endswith("\t") and row.count("\t") >= cells:
        row = row[:-1]
    return _MISSING_CELL.sub("nan,nan,nan,nan", row)


def read_orientations_sto(
    path: str | Path,
    *,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
    rate_rtol: float = 0.01,
) -> Recording:
    """Read an OpenSense orientation ``.sto`` into a :class:`~pipeline.io.recording.Recording`.

    Checks: header with ``endheader``; ``DataType=Quaternion`` when given; every row complete;
    every cell ``w,x,y,z``; time strictly increasing; rate from the time stamps equal to
    ``DataRate`` within ``rate_rtol``; missing quaternions (empty or ``nan`` cells) filled by
    slerp up to ``max_gap_s`` and left missing beyond (noted, never bridged); quaternions unit
    (normalised within 10 %) and sign-continuous. Repairs are listed in ``notes``.
    """
    path = Path(path)
    lines = read_text_lines(path)
    _, header, end = split_header(lines, path)
    dtype = header.get("DataType")
    if dtype is not None and dtype.lower() != "quaternion":
        raise InputError(
            f"DataType={dtype}: expected Quaternion (an orientation file); "
            "numeric tables are read with read_mot",
            file=path,
            field="DataType",
        )
    labels, rows, first_line = labels_and_rows(lines, end, path)
    sensors_names = labels[1:]
    if not sensors_names:
        raise InputError("no sensor columns after 'time'", file=path, field="labels")
    flat = ["time"] + [f"{s}[{c}]" for s in sensors_names for c in "wxyz"]
    cells = 1 + len(sensors_names)
    rows = [_missing_cells(r, cells) if "\t\t" in r or r.endswith("\t") or "nan" in r.lower()
            else r for r in rows]
    try:
        data = parse_table(rows, flat, file=path, first_line=first_line, also_sep=",")
    except InputError as e:
        raise InputError(
            e.message + f"; expected 'time' then {len(sensors_names)} cells 'w,x,y,z'",
            file=path,
            field=e.field,
        ) from None
    notes = Notes()
    time = check_time(data[:, 0], file=path, first_line=first_line)
    info = check_rate(time, declared_rate(header, path), rtol=rate_rtol, notes=notes, file=path)
    sensors: dict[str, np.ndarray] = {}
    for k, name in enumerate(sensors_names):
        q = data[:, 1 + 4 * k : 5 + 4 * k]
        q = fill_gaps(
            time, q, kind="quaternion", max_gap_s=max_gap_s, notes=notes, file=path, field=name,
            keep_long=True)
        sensors[name] = check_quaternions(
            q, notes=notes, file=path, field=name, first_line=first_line, allow_missing=True
        )
    rate = float(declared_rate(header, path) or info.rate_hz)
    return Recording.from_orientations(time, rate, sensors, header=header, notes=notes.as_tuple(),
                                       source=path)


def write_orientations_sto(
    path: str | Path, trial: Recording, header: Mapping[str, str] | None = None
) -> Path:
    """Write the orientations of a recording as an ``.sto`` that OpenSense reads (atomic; full
    double precision); sensors without orientations are left out. ``header``: extra
    ``key=value`` lines (OpenSim ignores keys it does not know)."""
    path = Path(path)
    quats = trial.orientations()
    names = list(quats)
    head = [
        f"DataRate={trial.rate_hz:.6f}",
        "DataType=Quaternion",
        "version=3",
        "OpenSimVersion=4.2",
        *(f"{k}={v}" for k, v in (header or {}).items()),
        "endheader",
        "\t".join(["time", *names]),
    ]
    with atomic_write(path, newline="\n") as f:
        f.write("\n".join(head) + "\n")
        for i in range(trial.n_samples):
            cells = [repr(float(trial.time[i]))]
            for n in names:
                cells.append(",".join(repr(float(v)) for v in quats[n][i]))
            f.write("\t".join(cells) + "\n")
    return path


# --------------------------------------------------------------------------------------------
# world rotation and sensor names


def sensor_to_opensim_matrix(rotations_xyz: Iterable[float]) -> np.ndarray:
    """OpenSense's ``sensor_to_opensim_rotations`` as a matrix.

    OpenSense builds a space-fixed X-Y-Z sequence: ``R = Rz(c) Ry(b) Rx(a)`` for
    ``(a, b, c)``; e.g. ``(-pi/2, 0, 0)`` takes an Xsens z-up world to OpenSim's y-up world.
    """
    return matrix_from_euler_xyz_fixed([float(v) for v in rotations_xyz])


def rotate_world(trial: Recording, R: np.ndarray) -> Recording:
    """Express every orientation in a rotated world: ``R_sensor' = R @ R_sensor``.

    Pre-multiplication changes the world frame only; the sensor frames (and so the relative
    orientations between sensors, and the signals in sensor frames) are unchanged. Returns a new
    recording with a note.
    """
    R = np.asarray(R, dtype=float)
    if R.shape != (3, 3) or not np.allclose(R @ R.T, np.eye(3), atol=1e-9):
        raise ValueError(f"expected a 3x3 rotation matrix, got {R!r}")
    sensors = dict(trial.sensors)
    for name, q in trial.orientations().items():
        rotated = quat_from_matrix(R @ matrix_from_quat(q))
        sensors[name] = sensors[name].replace(quat=make_quaternions_continuous(rotated)[0])
    angle = np.degrees(np.arccos(np.clip((np.trace(R) - 1) / 2, -1, 1)))
    note = f"world frame rotated by a fixed rotation of {angle:.4g} deg (pre-multiplied)"
    return dataclasses.replace(trial, sensors=sensors, notes=(*trial.notes, note))


def map_sensors(
    trial: Recording,
    required: Iterable[str] | None = None,
    mapping: Mapping[str, str] = SENSOR_TO_SEGMENT,
) -> dict[str, np.ndarray]:
    """Segment name -> ``(N, 4)`` quaternions, for every sensor column named in ``mapping``.

    ``required`` lists segment names that must be present (e.g. ``["pelvis", "right_femur",
    "right_tibia"]``); a missing one is refused naming the file, the sensor column expected for
    it and the columns available.
    """
    quats = trial.orientations()
    out = {seg: quats[s] for s, seg in mapping.items() if s in quats}
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
