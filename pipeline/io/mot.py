"""OpenSim numeric tables (``.mot`` joint angles, numeric ``.sto``): written and read in SI units.

Angles are degrees in the file (``inDegrees=yes``) and radians inside; translation columns
(``*_tx``, ``*_ty``, ``*_tz``) stay in metres.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.atomic import atomic_write
from pipeline.io.checks import check_time
from pipeline.io.gaps import DEFAULT_MAX_GAP_S, fill_gaps
from pipeline.io.notes import Notes
from pipeline.io.sto_header import labels_and_rows, split_header
from pipeline.io.text import parse_table, read_text_lines

__all__ = ["MotTable", "read_mot", "write_mot"]


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
    # one format per row (~2x faster); numbers as Python prints them (0.03, not
    # 0.029999999999999999: the shortest text that reads back to the same number)
    row_fmt = "\t".join(["%r"] * data.shape[1]) + "\n"
    with atomic_write(path, newline="\n") as f:
        f.write("\n".join(head) + "\n")
        for start in range(0, len(data), 10_000):  # bounded memory on long tables
            rows = data[start : start + 10_000].tolist()
            f.write("".join([row_fmt % tuple(row) for row in rows]))
    return path


def read_mot(
    path: str | Path,
    *,
    angle_columns: Iterable[str] | None = None,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
) -> MotTable:
    """Read an OpenSim numeric ``.mot``/``.sto`` table; angles are returned in radians.

    Checks the header (``endheader``, ``nRows``/``nColumns`` against the data: a shorter table
    is reported as truncated), time strictly increasing, and fills short NaN gaps (noted); a
    longer one (a joint a run left blank) stays NaN, noted.
    """
    path = Path(path)
    lines = read_text_lines(path)
    name, header, end = split_header(lines, path)
    labels, rows, first_line = labels_and_rows(lines, end, path)
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
            c = fill_gaps(time, c, max_gap_s=max_gap_s, notes=notes, file=path, field=n,
                          keep_long=True)
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
