"""Text files and delimited tables: read the lines of a file, parse rows of numbers.

The first step of every text reader (.sto/.mot, Xsens .txt, IMU CSV). Refusals are
:class:`~pipeline.errors.InputError` naming the file, the row (counted from 0 over the data rows,
with the 1-based file line when the reader passes ``first_line``) and the column. Missing cells
become NaN; :func:`pipeline.io.gaps.fill_gaps` decides what to do with them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pipeline.errors import InputError

__all__ = ["FileLike", "parse_table", "read_text_lines", "where"]

FileLike = str | Path | None
"""A file named in messages (path or name), or None when there is no file."""


def where(row: int, first_line: int | None) -> str:
    """``row r`` or, when the data start at file line ``first_line``, ``row r (line L)``."""
    return f"row {row}" if first_line is None else f"row {row} (line {first_line + row})"


def parse_table(
    lines: list[str],
    labels: list[str],
    *,
    sep: str = "\t",
    file: FileLike = None,
    first_line: int | None = None,
    also_sep: str | None = None,
    chunk: int = 20_000,
) -> np.ndarray:
    """Parse delimited text rows into an ``(N, len(labels))`` float array.

    Refuses a row with the wrong number of fields (typically a file cut mid-row) and a cell that
    is not a number, naming the row, the file line and the column. Empty cells and ``NaN`` become
    NaN (missing samples, handled by :func:`fill_gaps`). ``also_sep``: a second separator (the
    commas inside an OpenSense quaternion cell). Rows are parsed ``chunk`` at a time, so the
    split strings of an hour-long file never exist at once.
    """
    if len(lines) > chunk:
        parts = []
        for start in range(0, len(lines), chunk):
            line0 = None if first_line is None else first_line + start
            parts.append(parse_table(lines[start : start + chunk], labels, sep=sep, file=file,
                                     first_line=line0, also_sep=also_sep, chunk=chunk))
        return np.concatenate(parts)
    n = len(labels)
    fast = _parse_whole(lines, n, sep, also_sep)
    if fast is not None:
        return fast
    if also_sep is not None:
        lines = [ln.replace(also_sep, sep) for ln in lines]
    rows = [ln.rstrip("\r\n").split(sep) for ln in lines]
    for r, cells in enumerate(rows):
        if len(cells) != n:
            hint = " (file truncated?)" if r == len(rows) - 1 and len(cells) < n else ""
            raise InputError(
                f"{where(r, first_line)} has {len(cells)} fields, expected {n}{hint}", file=file
            )
    if not rows:
        return np.zeros((0, n))
    try:
        return np.array(rows, dtype=float)
    except ValueError:
        pass
    out = np.empty((len(rows), n))
    for r, cells in enumerate(rows):
        for c, cell in enumerate(cells):
            s = cell.strip()
            if not s:
                out[r, c] = np.nan
                continue
            try:
                out[r, c] = float(s)
            except ValueError:
                raise InputError(
                    f"{s!r} at {where(r, first_line)} is not a number", file=file, field=labels[c]
                ) from None
    return out


def _parse_whole(lines: list[str], n: int, sep: str, also_sep: str | None) -> np.ndarray | None:
    """The rows as one float conversion when every row has ``n`` non-empty cells (counted by
    separators), else None (the row-by-row parse then finds and names the fault)."""
    if not lines:
        return None
    seps = n - 1
    if any(ln.count(sep) + (ln.count(also_sep) if also_sep else 0) != seps for ln in lines):
        return None
    text = "\n".join(lines)
    for s in (sep, also_sep):
        if s:
            text = text.replace(s, " ")
    tokens = text.split()
    if len(tokens) != len(lines) * n:  # an empty cell
        return None
    try:
        return np.array(tokens, dtype=float).reshape(len(lines), n)
    except ValueError:  # a cell that is not a number
        return None


def read_text_lines(path: str | Path) -> list[str]:
    """Lines of a text file (without line ends); refuses a missing, unreadable or empty file."""
    p = Path(path)
    if not p.is_file():
        raise InputError("file not found" if not p.exists() else "not a file", file=p)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError as e:
        raise InputError(f"not a UTF-8 text file ({e.reason} at byte {e.start})", file=p) from None
    except OSError as e:
        raise InputError(f"cannot read: {e.strerror}", file=p) from None
    if not text.strip():
        raise InputError("file is empty", file=p)
    return text.splitlines()
