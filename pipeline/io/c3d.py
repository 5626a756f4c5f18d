"""C3D motion-capture files (markers, optional analog channels), read with ``ezc3d``.

Marker positions are converted to metres from the file's ``POINT:UNITS`` (``mm``, ``cm``, ``m``);
samples that ezc3d marks invalid (negative residual) are NaN. The result's extent is checked for
plausibility (millimetres labelled as metres are refused). The dataset's Xsens MVN exports
(``xsens*.c3d``: 64 virtual landmarks such as ``pRightKneeLatEpicondyle``) and the optical
``OMC*.c3d`` files (``REFM``, ``REFL``, ``RMM``, ``RLM``) are both read by :func:`read_c3d`.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.checks import check_position_units
from pipeline.io.notes import Notes

__all__ = ["UNIT_TO_METRES", "C3dMarkers", "read_c3d"]

UNIT_TO_METRES = {"mm": 1e-3, "cm": 1e-2, "dm": 1e-1, "m": 1.0}


@dataclass(frozen=True)
class C3dMarkers:
    """Markers of one C3D file.

    ``points``: ``(N, M, 3)`` metres (NaN where the marker is missing), one column per label;
    ``time``: ``(N,)`` seconds from the first frame; ``analog``: label -> ``(K,)`` samples at
    ``analog_rate_hz`` (values as stored, after the file's scale factors), empty if none.
    """

    labels: tuple[str, ...]
    points: np.ndarray
    rate_hz: float
    time: np.ndarray
    units_in_file: str
    analog: dict[str, np.ndarray] = field(default_factory=dict)
    analog_rate_hz: float | None = None
    notes: tuple[str, ...] = ()
    source: Path | None = None

    def marker(self, label: str) -> np.ndarray:
        """``(N, 3)`` trajectory of one marker (metres); refuses an unknown label."""
        if label not in self.labels:
            raise InputError(
                f"no marker {label!r}; available: {', '.join(self.labels)}",
                file=self.source,
                field="POINT:LABELS",
            )
        return self.points[:, self.labels.index(label)]


def _declared_frames(path: Path) -> int | None:
    """Frame count from the raw C3D header (words 4-5: first and last frame, 16-bit).

    ezc3d reads a truncated file without complaint (it shortens the data); comparing with the
    header catches that. Byte order from the processor type in the parameter section (86: MIPS,
    big-endian; 84 Intel and 85 DEC: little-endian).
    """
    with open(path, "rb") as f:
        head = f.read(512)
        if len(head) < 512 or head[0] < 1:
            return None
        f.seek((head[0] - 1) * 512)
        phead = f.read(4)
    endian = ">" if len(phead) == 4 and phead[3] == 86 else "<"
    first, last = struct.unpack(endian + "HH", head[6:10])
    return last - first + 1 if last >= first else None


def _param(params: dict, group: str, name: str):
    return params.get(group, {}).get(name, {}).get("value")


def read_c3d(path: str | Path, *, max_extent_m: float = 20.0) -> C3dMarkers:
    """Read markers (and analog channels) of a C3D file; positions in metres.

    Refuses: missing/unreadable files, files without markers, unknown or inconsistent
    ``POINT:UNITS``, a non-positive rate, and positions whose extent exceeds ``max_extent_m``
    after conversion. A missing ``POINT:UNITS`` is taken as ``mm`` (the C3D default) and noted.
    """
    from pipeline.optional import need

    ezc3d = need("ezc3d", "reading C3D files")

    path = Path(path)
    if not path.is_file():
        raise InputError("file not found", file=path)
    if path.stat().st_size == 0:
        raise InputError("file is empty", file=path)
    try:
        c = ezc3d.c3d(str(path), extract_forceplat_data=False)
    except Exception as e:  # ezc3d raises RuntimeError/IOError/ValueError on corrupt files
        raise InputError(f"not a readable C3D file ({e})", file=path) from None
    params = c["parameters"]
    notes = Notes()
    labels = tuple(str(s).strip() for s in (_param(params, "POINT", "LABELS") or []))
    pts = np.asarray(c["data"]["points"], dtype=float)  # (4, M, N)
    if pts.ndim != 3 or pts.shape[1] == 0 or pts.shape[2] == 0:
        raise InputError("no marker data (POINT:USED is 0 or no frames)", file=path, field="POINT")
    if len(labels) < pts.shape[1]:
        labels = labels + tuple(f"marker_{k}" for k in range(len(labels), pts.shape[1]))
        notes.add("some markers have no label; named marker_<index>", file=path)
    labels = labels[: pts.shape[1]]
    units = [str(u).strip().lower() for u in (_param(params, "POINT", "UNITS") or [])]
    units = [u for u in units if u]
    if not units:
        unit = "mm"
        notes.add("POINT:UNITS missing; assuming mm (the C3D default)", file=path)
    elif len(set(units)) > 1:
        raise InputError(
            f"mixed point units {sorted(set(units))}; expected one unit",
            file=path,
            field="POINT:UNITS",
        )
    else:
        unit = units[0]
    if unit not in UNIT_TO_METRES:
        raise InputError(
            f"unknown unit {unit!r}; expected one of {', '.join(UNIT_TO_METRES)}",
            file=path,
            field="POINT:UNITS",
        )
    rate_v = _param(params, "POINT", "RATE")
    rate = (
        float(np.ravel(rate_v)[0])
        if rate_v is not None and np.size(rate_v)
        else float(c["header"]["points"]["frame_rate"])
    )
    if not np.isfinite(rate) or rate <= 0:
        raise InputError(
            f"point rate must be positive, found {rate}", file=path, field="POINT:RATE"
        )
    declared = _declared_frames(path)
    if declared is not None and declared < 65535 and pts.shape[2] < declared:
        raise InputError(
            f"header declares {declared} frames but the data hold only {pts.shape[2]} "
            "(file truncated?)",
            file=path,
        )
    points = np.transpose(pts[:3], (2, 1, 0)) * UNIT_TO_METRES[unit]  # (N, M, 3)
    check_position_units(points, max_extent_m=max_extent_m, file=path, field="POINT")
    missing = np.isnan(points[..., 0])
    if missing.any():
        worst = int(np.argmax(missing.sum(0)))
        notes.add(
            f"{int(missing.sum())} missing marker samples (left as NaN); most in "
            f"{labels[worst]} ({int(missing[:, worst].sum())} of {points.shape[0]} frames)",
            file=path,
        )
    analog: dict[str, np.ndarray] = {}
    an = np.asarray(c["data"]["analogs"], dtype=float)
    a_rate = None
    if an.ndim == 3 and an.shape[1] > 0 and an.shape[2] > 0:
        a_labels = [str(s).strip() for s in (_param(params, "ANALOG", "LABELS") or [])]
        a_labels += [f"analog_{k}" for k in range(len(a_labels), an.shape[1])]
        analog = {a_labels[k]: an[0, k] for k in range(an.shape[1])}
        a_rate = float(np.ravel(_param(params, "ANALOG", "RATE"))[0])
    n = points.shape[0]
    return C3dMarkers(
        labels=labels,
        points=points,
        rate_hz=rate,
        time=np.arange(n) / rate,
        units_in_file=unit,
        analog=analog,
        analog_rate_hz=a_rate,
        notes=notes.as_tuple(),
        source=path,
    )
