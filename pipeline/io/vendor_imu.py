"""Raw IMU files as vendors' software writes them, one sensor per file (or folder), SI units out.

* **Movella DOT** ``.csv`` export (Movella DOT app / SDK): optional metadata lines, then the header
  ``PacketCounter,SampleTimeFine,Quat_W,Quat_X,Quat_Y,Quat_Z,Acc_X,Acc_Y,Acc_Z,Gyr_X,Gyr_Y,Gyr_Z,
  Mag_X,Mag_Y,Mag_Z,Status`` (column order free; orientation columns optional; the app ends every
  line, the header included, with a comma, and separates a row's cells by ``", "``; the SDK
  writes ``Euler_X/Y/Z`` (roll, pitch, yaw in degrees, ``R = Rz Ry Rx``) where the app writes
  ``Quat``, and may add ``FreeAcc_*``, ``dq_*``, ``dv_*`` and ``UTC_*`` columns, noted as not
  used; any other column is refused). Units (Movella
  DOT user manual): ``SampleTimeFine`` µs (32-bit, wraps at 2^32), ``Acc`` m/s², ``Gyr`` deg/s,
  ``Mag`` arbitrary units (normalised to the calibration field); ``Quat`` scalar first, sensor ->
  local earth frame, ENU (z up). Typically 120 Hz (also 60, 30, ...).
* **x-io x-IMU3** device folder (what x-IMU3 GUI logs, one folder per device named
  ``<label> <device id> (<interface>)``): ``Inertial.csv`` with ``Timestamp (us)``,
  ``Gyroscope X/Y/Z (deg/s)``, ``Accelerometer X/Y/Z (g)``; optional ``Quaternion.csv``
  (``Timestamp (us),W,X,Y,Z``, the device's own fusion, earth frame z up) and
  ``Magnetometer.csv`` (``X/Y/Z (a.u.)``, a lower rate: interpolated onto the inertial time
  stamps).

Both return a one-sensor :class:`~pipeline.io.recording.Recording` on the device's own clock
(seconds from its own zero); :func:`pipeline.io.imu_folder.read_imu_folder` aligns devices.
"""

from __future__ import annotations

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
from pipeline.rotations import matrix_from_euler_zyx, quat_from_matrix

__all__ = ["DOT_COLUMNS", "G", "read_movella_dot_csv", "read_ximu3_folder"]

G = 9.80665  # standard gravity: x-IMU3 accelerometers report g
DOT_COLUMNS = ("PacketCounter", "SampleTimeFine", "Quat_W", "Quat_X", "Quat_Y", "Quat_Z",
               "Acc_X", "Acc_Y", "Acc_Z", "Gyr_X", "Gyr_Y", "Gyr_Z", "Mag_X", "Mag_Y", "Mag_Z",
               "Status")


def _columns(rows, labels, path, first_line, names, field):
    data = parse_table(rows, labels, sep=",", file=path, first_line=first_line)
    idx = {c: k for k, c in enumerate(labels)}
    missing = [c for c in names if c not in idx]
    if missing:
        raise InputError(f"missing column(s) {', '.join(missing)}; found {labels}", file=path,
                         field=field)
    return data, idx


def _unwrap_ticks(ticks: np.ndarray, modulus: float) -> np.ndarray:
    """A wrapping counter made monotonic (each backwards step is one wrap)."""
    steps = np.diff(ticks)
    wraps = np.concatenate([[0.0], np.cumsum(np.where(steps < -modulus / 2, modulus, 0.0))])
    return ticks + wraps


#: Columns of DOT exports (app and SDK) that are read when present, and those known and not used.
DOT_READ = {"SampleTimeFine", *(f"{k}_{a}" for k in ("Acc", "Gyr", "Mag", "Euler") for a in "XYZ"),
            *(f"Quat_{a}" for a in "WXYZ")}
DOT_NOT_USED = ("PacketCounter", "Status", "FreeAcc_", "dq_", "dv_", "UTC_", "Timestamp")


def _check_dot_columns(labels: list[str], path: Path, notes: Notes) -> None:
    """Every column a DOT column: known but not used ones noted, any other refused."""
    unknown = [c for c in labels if c not in DOT_READ and not c.startswith(DOT_NOT_USED)]
    if unknown:
        raise InputError(f"column(s) {unknown} are not Movella DOT export columns (expected "
                         f"{sorted(DOT_READ)} and the app's {list(DOT_NOT_USED)})", file=path,
                         field="header")
    unused = [c for c in labels if c not in DOT_READ and c not in ("PacketCounter", "Status")]
    if unused:
        notes.add(f"DOT columns not used: {unused}", file=path)


def _dot_line(line: str, semicolons: bool = False) -> str:
    """One line of a DOT export without the comma the DOT app ends every line with (the header
    ``...,Status,``; rows ``0, 3629233986, ..., 0, ``: comma and space). ``semicolons``: a
    file saved in a decimal-comma locale (``0;4294000000;0,999;...``): its commas made points,
    its semicolons commas."""
    if semicolons:
        line = line.rstrip().rstrip(";").replace(",", ".").replace(";", ",")
    return line.rstrip().rstrip(",")


def read_movella_dot_csv(path: str | Path, *, max_gap_s: float = DEFAULT_MAX_GAP_S) -> Recording:
    """Read one Movella DOT ``.csv`` export (module docstring) into SI units."""
    path = Path(path)
    lines = read_text_lines(path)
    start = next((i for i, ln in enumerate(lines) if ln.startswith("PacketCounter")), None)
    if start is None:
        raise InputError("no header line starting with 'PacketCounter' (a Movella DOT export)",
                         file=path)
    semicolons = ";" in lines[start] and "," not in lines[start]  # a decimal-comma locale
    labels = [s.strip() for s in _dot_line(lines[start], semicolons).split(",")]
    rows = [_dot_line(ln, semicolons) for ln in lines[start + 1 :] if ln.strip()]
    if not rows:
        raise InputError("no data rows after the header", file=path)
    required = ("SampleTimeFine", "Acc_X", "Acc_Y", "Acc_Z", "Gyr_X", "Gyr_Y", "Gyr_Z")
    data, idx = _columns(rows, labels, path, start + 2, required, "header")
    notes = Notes()
    if semicolons:
        notes.add("separated by semicolons with decimal commas (a decimal-comma locale): read so",
                  file=path)
    _check_dot_columns(labels, path, notes)
    time = _unwrap_ticks(data[:, idx["SampleTimeFine"]], 2.0**32) * 1e-6
    clock = {"clock_start_s": repr(float(time[0])), "clock_wrap_s": repr(2.0**32 * 1e-6),
             WORLD: "movella-dot"}
    time = check_time(time - time[0], file=path, field="SampleTimeFine", first_line=start + 2)
    check_rate(time, notes=notes, file=path, field="SampleTimeFine")

    def cols(names, field, kind="vector"):
        return fill_gaps(time, data[:, [idx[c] for c in names]], kind=kind, max_gap_s=max_gap_s,
                         notes=notes, file=path, field=field, keep_long=True)

    gyr = np.radians(cols(("Gyr_X", "Gyr_Y", "Gyr_Z"), "Gyr"))  # deg/s in the file
    acc = cols(("Acc_X", "Acc_Y", "Acc_Z"), "Acc")
    check_gyro_units(gyr, file=path, field="Gyr")
    check_acc_units(acc, file=path, field="Acc")
    mag = cols(("Mag_X", "Mag_Y", "Mag_Z"), "Mag") if "Mag_X" in idx else None
    quat = None
    if "Quat_W" in idx:
        quat = check_quaternions(cols(("Quat_W", "Quat_X", "Quat_Y", "Quat_Z"), "Quat",
                                      "quaternion"), notes=notes, file=path,
                                 field="Quat", allow_missing=True)
    elif "Euler_X" in idx:  # roll, pitch, yaw in degrees; R = Rz(yaw) Ry(pitch) Rx(roll)
        eul = np.radians(cols(("Euler_Z", "Euler_Y", "Euler_X"), "Euler"))
        quat = quat_from_matrix(matrix_from_euler_zyx(eul))
    return Recording.single(path.stem, time, quat=quat, gyr=gyr, acc=acc, mag=mag, source=path,
                            header=clock, notes=notes.as_tuple())


def _ximu3_csv(path: Path, names: tuple[str, ...]):
    lines = read_text_lines(path)
    labels = [s.strip() for s in lines[0].rstrip("\r\n").split(",")]
    rows = [ln.rstrip("\r\n") for ln in lines[1:] if ln.strip()]
    if not rows:
        raise InputError("no data rows after the header", file=path)
    data, idx = _columns(rows, labels, path, 2, ("Timestamp (us)", *names), "header")
    t = data[:, idx["Timestamp (us)"]] * 1e-6
    return t, data[:, [idx[c] for c in names]]


def read_ximu3_folder(folder: str | Path, *, max_gap_s: float = DEFAULT_MAX_GAP_S) -> Recording:
    """Read one x-IMU3 device folder (module docstring); the time stays the device's clock (s),
    so that devices can be aligned by time stamp."""
    folder = Path(folder)
    inertial = folder / "Inertial.csv"
    if not inertial.is_file():
        raise InputError("no Inertial.csv (an x-IMU3 device folder)", file=folder)
    gyr_cols = tuple(f"Gyroscope {a} (deg/s)" for a in "XYZ")
    acc_cols = tuple(f"Accelerometer {a} (g)" for a in "XYZ")
    t, v = _ximu3_csv(inertial, gyr_cols + acc_cols)
    notes = Notes()
    t = check_time(t, file=inertial, field="Timestamp (us)", first_line=2)
    check_rate(t, notes=notes, file=inertial, field="Timestamp (us)")
    v = fill_gaps(t, v, kind="vector", max_gap_s=max_gap_s, notes=notes, file=inertial,
                  field="Inertial", keep_long=True)
    gyr, acc = np.radians(v[:, :3]), v[:, 3:] * G
    check_gyro_units(gyr, file=inertial, field="Gyroscope")
    check_acc_units(acc, file=inertial, field="Accelerometer")
    quat = mag = None
    qpath, mpath = folder / "Quaternion.csv", folder / "Magnetometer.csv"
    if qpath.is_file():
        tq, q = _ximu3_csv(qpath, ("W", "X", "Y", "Z"))
        if tq.shape != t.shape or np.abs(tq - t).max() > 1e-6:
            raise InputError("expected the Inertial.csv time stamps", file=qpath,
                             field="Timestamp (us)")
        quat = check_quaternions(q, notes=notes, file=qpath, field="W,X,Y,Z", first_line=2,
                                 allow_missing=True)
    if mpath.is_file():
        tm, m = _ximu3_csv(mpath, tuple(f"{a} (a.u.)" for a in "XYZ"))
        tm = check_time(tm, file=mpath, field="Timestamp (us)", first_line=2)
        mag = np.stack([np.interp(t, tm, m[:, k]) for k in range(3)], axis=1)
        notes.add(f"magnetometer at {1 / np.median(np.diff(tm)):.0f} Hz interpolated onto the "
                  f"inertial time stamps", file=mpath)
    return Recording.single(folder.name, t, quat=quat, gyr=gyr, acc=acc, mag=mag, source=folder,
                            header={WORLD: "ximu3"}, notes=notes.as_tuple())
