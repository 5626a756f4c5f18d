"""The project's raw IMU CSV: one sensor per file, SI units.

Header (required columns; order free, extra columns ignored and noted)::

    time,gyr_x,gyr_y,gyr_z,acc_x,acc_y,acc_z[,mag_x,mag_y,mag_z][,quat_w,quat_x,quat_y,quat_z]

``time`` in s, ``gyr`` in rad/s and ``acc`` (specific force) in m/s^2 in the sensor frame;
optional ``mag`` (magnetometer, any unit, sensor frame) and ``quat`` = scalar-first orientation
of the sensor in its world frame. Empty cells are
missing samples (filled up to ``max_gap_s`` and reported; refused beyond). Gyroscopes in deg/s
and accelerometers in g are detected from their magnitude and refused with a hint.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.atomic import atomic_write
from pipeline.io.checks import (
    check_acc_units,
    check_gyro_units,
    check_quaternions,
    check_rate,
    check_time,
)
from pipeline.io.gaps import DEFAULT_MAX_GAP_S, fill_gaps
from pipeline.io.notes import Notes
from pipeline.io.recording import Recording
from pipeline.io.tables import write_array_csv
from pipeline.io.text import parse_table, read_text_lines

__all__ = [
    "ACC_COLUMNS",
    "GYR_COLUMNS",
    "MAG_COLUMNS",
    "QUAT_COLUMNS",
    "read_imu_csv",
    "write_imu_csv",
]

GYR_COLUMNS = ("gyr_x", "gyr_y", "gyr_z")
ACC_COLUMNS = ("acc_x", "acc_y", "acc_z")
QUAT_COLUMNS = ("quat_w", "quat_x", "quat_y", "quat_z")
MAG_COLUMNS = ("mag_x", "mag_y", "mag_z")


def read_imu_csv(
    path: str | Path,
    *,
    rate_hz: float | None = None,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
    rate_rtol: float = 0.01,
) -> Recording:
    """Read a raw IMU CSV into a one-sensor :class:`~pipeline.io.recording.Recording` named after
    the file (its stem).

    Checks: header with the required columns (missing ones listed with those found), complete
    rows (a file cut mid-row is refused), numbers, strictly increasing time, the rate against
    ``rate_hz`` when declared, NaN gaps, quaternion norms and continuity, and the units of
    ``gyr`` and ``acc``.
    """
    path = Path(path)
    lines = read_text_lines(path)
    labels = [s.strip().lower() for s in lines[0].split(",")]
    required = ("time", *GYR_COLUMNS, *ACC_COLUMNS)
    missing = [c for c in required if c not in labels]
    if missing:
        raise InputError(
            f"missing column(s) {', '.join(missing)}; expected header "
            f"'{','.join(required)}[,{','.join(QUAT_COLUMNS)}]', found '{lines[0].strip()}'",
            file=path,
            field="header",
        )
    if len(set(labels)) != len(labels):
        dup = sorted({x for x in labels if labels.count(x) > 1})
        raise InputError(f"duplicate column(s) {dup}", file=path, field="header")
    has_q = [c in labels for c in QUAT_COLUMNS]
    if any(has_q) and not all(has_q):
        raise InputError(
            f"incomplete quaternion: expected all of {', '.join(QUAT_COLUMNS)}",
            file=path,
            field="header",
        )
    has_m = [c in labels for c in MAG_COLUMNS]
    if any(has_m) and not all(has_m):
        raise InputError(f"incomplete magnetometer: expected all of {', '.join(MAG_COLUMNS)}",
                         file=path, field="header")
    notes = Notes()
    extra = [c for c in labels if c not in (*required, *QUAT_COLUMNS, *MAG_COLUMNS)]
    if extra:
        notes.add(f"ignored column(s) {', '.join(extra)}", file=path)
    rows = lines[1:]
    while rows and not rows[-1].strip():
        rows.pop()
    if not rows:
        raise InputError("no data rows after the header", file=path)
    data = parse_table(rows, labels, sep=",", file=path, first_line=2)
    idx = {c: k for k, c in enumerate(labels)}
    time = check_time(data[:, idx["time"]], file=path, first_line=2)
    check_rate(time, rate_hz, rtol=rate_rtol, notes=notes, file=path)

    def cols(names: tuple[str, ...], field: str, kind: str = "vector") -> np.ndarray:
        v = data[:, [idx[c] for c in names]]
        return fill_gaps(
            time, v, kind=kind, max_gap_s=max_gap_s, notes=notes, file=path, field=field,
            keep_long=True)

    gyr = cols(GYR_COLUMNS, "gyr")
    acc = cols(ACC_COLUMNS, "acc")
    check_gyro_units(gyr, file=path, field="gyr")
    check_acc_units(acc, file=path, field="acc")
    mag = cols(MAG_COLUMNS, "mag") if all(has_m) else None
    quat = None
    if all(has_q):
        quat = check_quaternions(
            cols(QUAT_COLUMNS, "quat", "quaternion"),
            allow_missing=True,
            notes=notes,
            file=path,
            field="quat",
            first_line=2,
        )
    return Recording.single(path.stem, time, quat=quat, gyr=gyr, acc=acc, mag=mag, source=path,
                            notes=notes.as_tuple())


def write_imu_csv(path: str | Path, rec: Recording) -> Path:
    """Write a one-sensor ``rec`` as a raw IMU CSV (atomic, full double precision)."""
    path = Path(path)
    n = rec.time.size
    parts = [
        np.asarray(rec.time, float).reshape(n, 1),
        np.asarray(rec.gyr, float),
        np.asarray(rec.acc, float),
    ]
    header = ["time", *GYR_COLUMNS, *ACC_COLUMNS]
    if rec.mag is not None:
        parts.append(np.asarray(rec.mag, float))
        header += MAG_COLUMNS
    if rec.quat is not None:
        parts.append(np.asarray(rec.quat, float))
        header += QUAT_COLUMNS
    for p in parts:
        if p.shape[0] != n:
            raise ValueError(f"array with {p.shape[0]} rows, time has {n}")
    data = np.hstack(parts)
    with atomic_write(path, newline="\n") as f:
        write_array_csv(f, header, data, digits=17, nan="")
    return path
