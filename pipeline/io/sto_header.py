"""The header of OpenSim's text tables (``.sto``, ``.mot``): name line, ``key=value`` pairs,
``endheader``, then tab-separated column labels with ``time`` first."""

from __future__ import annotations

from pathlib import Path

from pipeline.errors import InputError

__all__ = ["declared_rate", "labels_and_rows", "split_header"]


def split_header(lines: list[str], path: Path) -> tuple[str, dict[str, str], int]:
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


def labels_and_rows(lines: list[str], end: int, path: Path) -> tuple[list[str], list[str], int]:
    """Column labels (``time`` first, unique), the data rows and the 1-based line of the first."""
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


def declared_rate(header: dict[str, str], path: Path) -> float | None:
    """The header's ``DataRate`` (Hz), or None when absent."""
    raw = header.get("DataRate")
    if raw is None:
        return None
    try:
        return float(raw)
    except ValueError:
        raise InputError(f"DataRate={raw!r} is not a number", file=path, field="DataRate") from None
