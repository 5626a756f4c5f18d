"""The one CSV writer, and the Markdown helpers of reports.

* :func:`csv_text`: rows of named values (reports, summaries);
* :func:`write_array_csv`: a numeric array with a header (signals, trajectories, configurations),
  streamed to an open text file row by row.

Both format floats with ``digits`` significant digits (``%.{digits}g``).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Iterable, Mapping, Sequence
from typing import TextIO

import numpy as np

__all__ = ["csv_text", "markdown_table", "mean_sd", "write_array_csv"]


def csv_text(
    rows: Iterable[Mapping[str, object]], columns: Sequence[str], digits: int = 6
) -> str:
    """CSV text with exactly ``columns``; floats with ``digits`` significant digits."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=list(columns), lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow({c: _fmt(row[c], digits) for c in columns})
    return buf.getvalue()


def write_array_csv(
    f: TextIO,
    columns: Sequence[str],
    data: np.ndarray,
    digits: int = 10,
    nan: str = "nan",
    header: bool = True,
) -> None:
    """Write ``columns`` and the rows of ``data`` (N, len(columns)) to the open file ``f``;
    non-finite values are written as ``nan`` (e.g. ``""`` for an empty field). ``header=False``
    appends rows only (a long table written in chunks)."""
    data = np.asarray(data, dtype=float)
    if data.ndim != 2 or data.shape[1] != len(columns):
        raise ValueError(f"expected an (N, {len(columns)}) array, got shape {data.shape}")
    if header:
        f.write(",".join(columns) + "\n")
    spec = f"{{:.{digits}g}}"
    row_fmt = ",".join([f"%.{digits}g"] * len(columns)) + "\n"  # the same text as ``spec``
    finite = np.isfinite(data).all(axis=1).tolist()
    lines = []
    for row, ok in zip(data.tolist(), finite, strict=True):
        if ok:
            lines.append(row_fmt % tuple(row))
        else:
            lines.append(",".join(spec.format(v) if math.isfinite(v) else nan for v in row) + "\n")
    f.write("".join(lines))


def _fmt(v: object, digits: int) -> object:
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return v


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[object]]) -> str:
    """A GitHub-flavoured Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for r in rows:
        lines.append("| " + " | ".join(str(c) for c in r) + " |")
    return "\n".join(lines)


def mean_sd(values: Sequence[float], digits: int = 1) -> str:
    """``mean±SD`` (sample SD) as the papers print it."""
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return "n/a"
    sd = v.std(ddof=1) if v.size > 1 else 0.0
    return f"{v.mean():.{digits}f}±{sd:.{digits}f}"
