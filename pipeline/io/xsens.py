"""Xsens MT Manager ``.txt`` exports (one file per sensor), the format OpenSense's
``XsensDataReader`` reads.

Layout (facts from OpenSim's reader and its test files)::

    // Start Time: Unknown
    // Update Rate: 100.0Hz
    // Filter Profile: human (46.1)
    // Firmware Version: 4.0.2
    PacketCounter<TAB>SampleTimeFine<TAB>...<TAB>Acc_X<TAB>Acc_Y<TAB>Acc_Z<TAB>Gyr_X ... Mag_Z
        <TAB>Quat_q0<TAB>Quat_q1<TAB>Quat_q2<TAB>Quat_q3   and/or   Mat[1][1] ... Mat[3][3]
        and/or Roll<TAB>Pitch<TAB>Yaw
    03583<TAB><TAB>...<TAB>3.030769<TAB>...

Comment lines start with ``//`` (``key: value``); the first other line is the header; cells may be
empty or ``NaN`` for unused columns. A file without orientation columns but with ``Acc_*`` and
``Gyr_*`` (an export of the raw signals) is read as raw signals: its orientations come from an
attitude filter (:mod:`pipeline.process.signals`). Newer exports may use ``,``, ``;`` or spaces as
delimiter (detected from the header). Units: ``Acc`` m/s^2, ``Gyr`` rad/s, ``Mag`` arbitrary units
(sensor frame). Orientation of the sensor in the Xsens world frame (z up): ``Quat_q0..q3`` =
``[w, x, y, z]``; ``Mat[r][c]`` = element (r, c) of the same rotation matrix
(``p_world = R p_sensor``); ``Roll, Pitch, Yaw`` in degrees with ``R = Rz(yaw) Ry(pitch)
Rx(roll)``. The three agree on the test files (checked: gravity ``R^T [0, 0, 9.81]`` equals the
accelerometer at rest).

Time: ``SampleTimeFine`` (10 kHz ticks, 32-bit) when present; else ``PacketCounter`` (16-bit,
wraps at 65536) divided by the update rate, with dropped packets becoming missing samples (filled
up to ``max_gap_s`` and reported, refused beyond); else the row index divided by the rate.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.checks import (
    check_acc_units,
    check_gyro_units,
    check_quaternions,
    check_rate,
    check_time,
)
from pipeline.io.gaps import DEFAULT_MAX_GAP_S, fill_gaps
from pipeline.io.notes import Notes
from pipeline.io.recording import WORLD, Recording
from pipeline.io.text import parse_table, read_text_lines
from pipeline.rotations import matrix_from_euler_zyx, project_to_so3, quat_from_matrix

__all__ = ["read_xsens_txt"]

QUAT_COLUMNS = ("Quat_q0", "Quat_q1", "Quat_q2", "Quat_q3")
MAT_COLUMNS = tuple(f"Mat[{r}][{c}]" for c in (1, 2, 3) for r in (1, 2, 3))
EULER_COLUMNS = ("Roll", "Pitch", "Yaw")
SAMPLE_TIME_FINE_HZ = 10_000.0


def _detect_delimiter(line: str) -> str | None:
    best, n = None, 1
    for d in ("\t", ",", ";"):
        k = len(line.split(d))
        if k > n:
            best, n = d, k
    return best  # None: whitespace


def _split(line: str, delim: str | None) -> list[str]:
    return line.split() if delim is None else line.rstrip("\r\n").split(delim)


def _rate_from_comment(text: str, path: Path) -> float:
    m = re.search(r"[-+]?\d+(\.\d*)?([eE][-+]?\d+)?", text)
    if not m or float(m.group(0)) <= 0:
        raise InputError(f"cannot read a rate from {text!r}", file=path, field="Update Rate")
    return float(m.group(0))


def _sensor_id(path: Path) -> str:
    stem = path.stem
    return stem.rsplit("_", 1)[-1] if "_" in stem else stem


def _counter_steps(pc: np.ndarray, path: Path, first_line: int) -> np.ndarray:
    """Sample index from a 16-bit packet counter (wraps at 65536); refuses repeats/backsteps."""
    d = np.mod(np.diff(pc), 65536)
    bad = np.flatnonzero((d == 0) | (d > 32768))
    if bad.size:
        r = int(bad[0]) + 1
        what = "repeated" if d[bad[0]] == 0 else "not increasing"
        raise InputError(
            f"packet counter {what}: {int(pc[r])} at row {r} (line {first_line + r}) after "
            f"{int(pc[r - 1])}",
            file=path,
            field="PacketCounter",
        )
    return np.concatenate([[0], np.cumsum(d)]).astype(np.int64)


def read_xsens_txt(
    path: str | Path,
    *,
    rate_hz: float | None = None,
    max_gap_s: float = DEFAULT_MAX_GAP_S,
) -> Recording:
    """Read one MT Manager ``.txt`` export; see the module docstring for the format and checks.

    ``rate_hz`` declares the rate when the file has no ``// Update Rate`` comment; if both are
    given they must agree.
    """
    path = Path(path)
    lines = read_text_lines(path)
    comments: dict[str, str] = {}
    i = 0
    while i < len(lines) and (lines[i].startswith("//") or not lines[i].strip()):
        body = lines[i][2:].strip()
        if ":" in body:
            k, v = body.split(":", 1)
            comments.setdefault(k.strip(), v.strip())
        i += 1
    if i >= len(lines):
        raise InputError("no header line after the '//' comments", file=path)
    delim = _detect_delimiter(lines[i])
    header_line = lines[i].rstrip("\r\n")
    trailing = delim is not None and header_line.endswith(delim)
    labels = [s.strip() for s in _split(header_line.rstrip(delim or None), delim)]
    first_line = i + 2
    rows = [ln.rstrip("\r\n") for ln in lines[i + 1 :]]
    while rows and not rows[-1].strip():
        rows.pop()
    if not rows:
        raise InputError("no data rows after the header", file=path)
    if trailing:
        rows = [r[: -len(delim)] if r.endswith(delim) else r for r in rows]
    if delim is None:
        rows = ["\t".join(r.split()) for r in rows]
    col = {name: k for k, name in enumerate(labels)}
    orient = next(
        (
            (kind, cols)
            for kind, cols in (
                ("quaternion", QUAT_COLUMNS),
                ("matrix", MAT_COLUMNS),
                ("euler", EULER_COLUMNS),
            )
            if all(c in col for c in cols)
        ),
        None,
    )
    raw_only = all(f"{p}_{a}" in col for p in ("Acc", "Gyr") for a in "XYZ")
    if orient is None and not raw_only:
        raise InputError(
            "no orientation columns (Quat_q0..Quat_q3, Mat[1][1]..Mat[3][3] or Roll/Pitch/Yaw) "
            f"and no raw Acc_X..Z and Gyr_X..Z columns; found {', '.join(labels)}",
            file=path,
            field="header",
        )
    data = parse_table(
        rows, labels, sep="\t" if delim is None else delim, file=path, first_line=first_line
    )
    notes = Notes()

    # declared rate
    declared = None
    if "Update Rate" in comments:
        declared = _rate_from_comment(comments["Update Rate"], path)
    if rate_hz is not None:
        if declared is not None and abs(declared - rate_hz) > 0.01 * declared:
            raise InputError(
                f"rate_hz={rate_hz:g} but the file says Update Rate {declared:g} Hz",
                file=path,
                field="Update Rate",
            )
        declared = float(rate_hz)

    # time
    stf = data[:, col["SampleTimeFine"]] if "SampleTimeFine" in col else None
    pc = data[:, col["PacketCounter"]] if "PacketCounter" in col else None
    index = np.arange(len(rows))
    clock: dict[str, str] = {}  # the device clock at the first sample (pipeline.io.clocks)
    if stf is not None and np.all(np.isfinite(stf)):
        clock = {"clock_start_s": repr(float(stf[0]) / SAMPLE_TIME_FINE_HZ),
                 "clock_wrap_s": repr(2.0**32 / SAMPLE_TIME_FINE_HZ)}
        ticks = np.concatenate([[0.0], np.cumsum(np.mod(np.diff(stf), 2.0**32))])
        time = check_time(
            ticks / SAMPLE_TIME_FINE_HZ, file=path, field="SampleTimeFine", first_line=first_line
        )
        info = check_rate(time, declared, file=path, field="SampleTimeFine")
        rate = declared or info.rate_hz
        k = np.rint(time * rate).astype(np.int64)
        if np.all(np.diff(k) >= 1) and np.max(np.abs(time - k / rate)) < 0.25 / rate:
            index = k  # on the sampling grid: dropped samples become missing rows
            n_drop = int(k[-1] + 1 - k.size)
            if n_drop:
                notes.add(f"{n_drop} dropped sample(s) (SampleTimeFine jumps)", file=path)
            time = np.arange(int(k[-1]) + 1) / rate
        else:
            notes.add(
                f"irregular SampleTimeFine (jitter {info.jitter_s * 1e3:.3g} ms); time kept as "
                "recorded",
                file=path,
            )
    else:
        if declared is None:
            raise InputError(
                "no sampling rate: the '// Update Rate:' comment is missing and there is no "
                "SampleTimeFine column; pass rate_hz",
                file=path,
            )
        rate = declared
        if pc is not None and np.all(np.isfinite(pc)):
            index = _counter_steps(pc, path, first_line)
            clock = {"clock_start_s": repr(float(pc[0]) / rate),
                     "clock_wrap_s": repr(65536.0 / rate)}
            n_drop = int(index[-1] + 1 - index.size)
            if n_drop:
                notes.add(f"{n_drop} dropped packet(s) (PacketCounter jumps)", file=path)
        time = np.arange(int(index[-1]) + 1) / rate

    def block(names: tuple[str, ...]) -> np.ndarray:
        full = np.full((time.size, len(names)), np.nan)
        full[index] = data[:, [col[n] for n in names]]
        return full

    def vectors(prefix: str) -> np.ndarray | None:
        names = tuple(f"{prefix}_{a}" for a in "XYZ")
        if not all(n in col for n in names):
            return None
        v = block(names)
        if np.all(np.isnan(v)):
            return None
        return fill_gaps(time, v, max_gap_s=max_gap_s, notes=notes, file=path, field=prefix,
                         keep_long=True)

    acc, gyr, mag = vectors("Acc"), vectors("Gyr"), vectors("Mag")
    if acc is not None:
        check_acc_units(acc, file=path, field="Acc")
    if gyr is not None:
        check_gyro_units(gyr, file=path, field="Gyr")
    if orient is not None and not np.isfinite(block(orient[1])).any():
        orient = None  # the orientation columns are there but empty: a raw-signal export
        notes.add("the orientation columns are empty: read as raw signals", file=path,
                  field="orientation")
    if orient is None:  # raw signals only: the orientations come from an attitude filter
        if acc is None or gyr is None:
            raise InputError("the Acc and Gyr columns are empty and there are no orientation "
                             "columns", file=path, field="header")
        header = {**comments, **clock, "orientation_from": "none", WORLD: "xsens"}
        return Recording.single(_sensor_id(path), time, gyr=gyr, acc=acc, mag=mag,
                                rate_hz=float(rate), header=header, notes=notes.as_tuple(),
                                source=path)
    kind, cols = orient
    raw = block(cols)
    if kind != "quaternion":
        ok = np.all(np.isfinite(raw), axis=1)
        q = np.full((time.size, 4), np.nan)
        if kind == "matrix":
            R = raw[ok].reshape(-1, 3, 3).transpose(0, 2, 1)  # columns listed column-major
            dev = np.abs(np.linalg.det(R) - 1) if R.size else np.zeros(0)
            if dev.size and dev.max() > 0.1:
                r = int(np.flatnonzero(ok)[np.argmax(dev)])
                raise InputError(
                    f"orientation matrix is not a rotation (det {np.linalg.det(R).flat[0]:.3g}"
                    f" at row {r})",
                    file=path,
                    field="Mat",
                )
            q[ok] = quat_from_matrix(project_to_so3(R)) if R.size else q[ok]
        else:
            eul = np.radians(raw[ok][:, ::-1])  # (yaw, pitch, roll)
            q[ok] = quat_from_matrix(matrix_from_euler_zyx(eul)) if eul.size else q[ok]
        raw = q
    quat = fill_gaps(
        time,
        raw,
        kind="quaternion",
        max_gap_s=max_gap_s,
        notes=notes,
        file=path,
        field="orientation",
        keep_long=True,
    )
    quat = check_quaternions(quat, notes=notes, file=path, field="orientation",
                             allow_missing=True)
    header = {**comments, **clock, "orientation_from": kind, WORLD: "xsens"}
    return Recording.single(_sensor_id(path), time, quat=quat, gyr=gyr, acc=acc, mag=mag,
                            rate_hz=float(rate), header=header, notes=notes.as_tuple(),
                            source=path)
