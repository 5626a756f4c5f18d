"""Every recording format, recognised once: :func:`read_recording` (a file or a folder in, one
:class:`~pipeline.io.recording.Recording` with our sensor names out) is what every command that
reads recordings calls, so ``pipeline ik``, ``pipeline orientations`` and ``pipeline batch``
accept the same inputs.

Formats (:data:`FORMATS`), each recognised by its content, not only its name:

* ``sto``: an OpenSim ``.sto`` of quaternions (OpenSense): an ``endheader`` line;
* ``xsens_mt``: an Xsens MT Manager ``.txt`` export, one sensor: ``//`` comment lines, or
  ``Quat_q0``/``Mat[1][1]``/``Roll`` columns;
* ``dot``: a Movella DOT ``.csv`` export, one sensor: a ``PacketCounter`` header, no ``//``;
* ``imu_csv``: our IMU CSV, one sensor: a ``time`` column in the header;
* ``ximu3``: an x-IMU3 device folder, one sensor: a folder holding ``Inertial.csv``.

A folder (not an x-IMU3 device folder) holds one sensor per entry, in any of the one-sensor formats;
every entry is either read or named: an entry that is none of them, or a sensor that gets no name,
is refused naming it (``ignore`` patterns, e.g. ``notes.txt``, leave entries out with a note; so are
hidden files and documents that cannot be recordings, :data:`DOCUMENTS`). The sensors' clocks are
aligned by time stamp (:func:`pipeline.io.clocks.align_clocks`).

**Names** (:func:`apply_sensor_map`, the one place the sensor map is applied): a sensor named with
one of our names, an alias or a known label (:func:`pipeline.io.sensor_names.our_name`) is that
sensor; ``sensor_map`` (our name -> the recording's name or a unique part of it, e.g. an Xsens
device id) names the others. Every entry of the map must match exactly one sensor.
"""

from __future__ import annotations

import fnmatch
import os
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from pipeline.errors import InputError
from pipeline.io.clocks import align_clocks
from pipeline.io.imu_csv import read_imu_csv
from pipeline.io.opensim import read_orientations_sto
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SENSOR_NAMES, our_name
from pipeline.io.vendor_imu import read_movella_dot_csv, read_ximu3_folder
from pipeline.io.xsens import read_xsens_txt

__all__ = ["DOCUMENTS", "FORMATS", "Format", "apply_sensor_map", "read_recording", "recognise",
           "recording_name"]

_HEAD_LINES = 40
#: Entries of a folder that are documents, never recordings: left out with a note.
DOCUMENTS = ("README*", "LICENSE*", "LICENCE*", "COPYING*", "*.md", "*.pdf", "*.docx", "*.png",
             "*.jpg")


@dataclass(frozen=True)
class Format:
    """A recording format: its ``name``, a ``description`` for messages, whether it holds
    ``one_sensor``, ``matches(path, head)`` (``head``: the first lines of a file, empty for a
    folder) and ``read(path)``."""

    name: str
    description: str
    one_sensor: bool
    matches: Callable[[Path, list[str]], bool]
    read: Callable[[Path], Recording]


def _is_sto(path: Path, head: list[str]) -> bool:
    return any(line.strip().lower() == "endheader" for line in head)


def _header_line(head: list[str]) -> str:
    return next((ln for ln in head if ln.strip() and not ln.startswith("//")), "")


def _is_xsens_mt(path: Path, head: list[str]) -> bool:
    if not head or _is_sto(path, head):
        return False
    header = _header_line(head)
    orient = any(c in header for c in ("Quat_q0", "Mat[1][1]", "Roll"))
    return head[0].startswith("//") or orient or (path.suffix.lower() == ".txt"
                                                  and "PacketCounter" in header)


def _is_dot(path: Path, head: list[str]) -> bool:
    return (not _is_xsens_mt(path, head) and not _is_sto(path, head)
            and any(ln.startswith("PacketCounter") for ln in head))


def _is_imu_csv(path: Path, head: list[str]) -> bool:
    if not head or _is_sto(path, head) or _is_xsens_mt(path, head) or _is_dot(path, head):
        return False
    first = head[0].lower().replace(";", ",").replace("\t", ",")
    return "time" in [c.strip() for c in first.split(",")]


def _is_ximu3(path: Path, head: list[str]) -> bool:
    return path.is_dir() and (path / "Inertial.csv").is_file()


#: The formats, in the order they are tried (the first that matches reads the entry).
FORMATS: tuple[Format, ...] = (
    Format("ximu3", "an x-IMU3 device folder (Inertial.csv)", True, _is_ximu3, read_ximu3_folder),
    Format("sto", "an OpenSim .sto of quaternions", False, _is_sto, read_orientations_sto),
    Format("xsens_mt", "an Xsens MT Manager .txt export", True, _is_xsens_mt, read_xsens_txt),
    Format("dot", "a Movella DOT .csv export", True, _is_dot, read_movella_dot_csv),
    Format("imu_csv", "an IMU CSV (time,gyr_x,...)", True, _is_imu_csv, read_imu_csv),
)
#: A file whose content matches no format is read by the reader its suffix names, which says what
#: is wrong with it (an empty .sto, a truncated export).
_BY_SUFFIX = {".sto": "sto", ".mot": "sto", ".txt": "xsens_mt", ".csv": "imu_csv"}
_EXPECTED = ("expected " + ", ".join(f.description for f in FORMATS[1:])
             + " (one sensor per file), or " + FORMATS[0].description)


def _head(path: Path) -> list[str]:
    if path.is_dir() or not path.is_file():
        return []
    try:
        with open(path, encoding="utf-8", errors="replace", newline="") as fh:
            return [fh.readline().lstrip("\ufeff") for _ in range(_HEAD_LINES)]
    except OSError as exc:
        raise InputError(f"cannot read it: {exc.strerror}", file=path) from None


def recognise(path: str | Path) -> Format | None:
    """The format of a file or folder, from its content; None when it is none of them."""
    path = Path(path)
    head = [ln for ln in _head(path) if ln]
    return next((f for f in FORMATS if f.matches(path, head)), None)


def read_recording(
    path: str | Path,
    sensor_map: Mapping[str, str] | None = None,
    *,
    ignore: Sequence[str] = (),
) -> Recording:
    """A recording (module docstring): one file, an x-IMU3 device folder, or a folder of
    one-sensor files, with our sensor names; time from 0. ``example:<name>`` reads an example
    installed with the package (:mod:`pipeline.examples`)."""
    from pipeline.examples import resolve

    if sensor_map is not None and not isinstance(sensor_map, Mapping):
        raise InputError(f"expected a mapping of our sensor names to the recording's, e.g. "
                         f"{{'pelvis_imu': '00B40B91'}}, got {type(sensor_map).__name__} "
                         f"{sensor_map!r:.60}", field="sensor_map")
    path = resolve(path)
    if not path.exists():
        raise InputError("no such file or folder", file=path)
    fmt = recognise(path)
    if fmt is None and path.is_file():  # its reader says what is wrong with a file of its kind
        fmt = next((f for f in FORMATS if f.name == _BY_SUFFIX.get(path.suffix.lower())), None)
    if fmt is not None:
        rec = fmt.read(path)
        if fmt.one_sensor:
            rec = rec.with_sensors({_entry_name(path): rec.sensor})
        rec = _from_zero(rec)
        return apply_sensor_map(rec, sensor_map or {}, folder=False)
    if not path.is_dir():
        raise InputError(f"not a recording this program reads: {_EXPECTED}", file=path)
    return _read_folder(path, sensor_map or {}, ignore)


def _entry_name(path: Path) -> str:
    """A one-sensor entry's sensor name: an x-IMU3 device folder's label (``Right Upper Leg``
    of ``Right Upper Leg 64F61C2E (UDP)``), else the file's stem."""
    if path.is_dir():
        words = path.name.split(" (")[0].split()
        return " ".join(words[:-1]) if len(words) > 1 else path.name
    return path.stem


def _from_zero(rec: Recording) -> Recording:
    import dataclasses

    if rec.time.size and rec.time[0] != 0.0:
        return dataclasses.replace(rec, time=rec.time - rec.time[0])
    return rec


def _read_folder(folder: Path, sensor_map: Mapping[str, str], ignore: Sequence[str]) -> Recording:
    recs: dict[str, Recording] = {}
    left_out: list[str] = []
    for entry in sorted(folder.iterdir()):
        patterns = (*DOCUMENTS, *ignore)
        if entry.name.startswith(".") or any(fnmatch.fnmatch(entry.name, p) for p in patterns):
            left_out.append(entry.name)
            continue
        fmt = recognise(entry)
        if fmt is None or not fmt.one_sensor:
            what = "holds several sensors" if fmt is not None else "is not a recording"
            raise InputError(f"{what}: in a folder, {_EXPECTED}; leave it out with --ignore "
                             f"{entry.name!r}", file=entry)
        rec = fmt.read(entry)
        recs[entry.name] = rec.with_sensors({_entry_name(entry): rec.sensor})
    if not recs:
        raise InputError(f"no recordings in the folder: {_EXPECTED}", file=folder)
    named = apply_sensor_map(_merge_names(recs, folder), sensor_map, folder=True)
    out = align_clocks({n: named[n] for n in named.sensor_names}, source=folder)
    if left_out:
        out = out.with_notes(f"left out of {folder.name}: {left_out}")
    return out


class _Named(dict):
    """Sensor name -> one-sensor recording, with the entry each came from (for messages)."""

    source: Path
    entries: dict[str, str]

    @property
    def sensor_names(self) -> tuple[str, ...]:
        return tuple(self)


def _merge_names(recs: dict[str, Recording], folder: Path) -> _Named:
    named = _Named()
    named.source, named.entries = folder, {}
    for entry, rec in recs.items():
        name = rec.name
        if name in named:
            raise InputError(f"two entries give sensor {name!r}: {named.entries[name]} and "
                             f"{entry}", file=folder)
        named[name], named.entries[name] = rec, entry
    return named


def apply_sensor_map(rec, sensor_map: Mapping[str, str], *, folder: bool = False):
    """The recording (or, for a folder, the :class:`_Named` one-sensor recordings) with our sensor
    names (module docstring). ``sensor_map``: our name -> the recording's sensor name or a unique
    part of it (in a folder, of its entry's name too: an x-IMU3 device id). In a folder every
    sensor must get a name; elsewhere a sensor with another name keeps it (it is reported as not
    in the model)."""
    names = list(rec.sensor_names) if isinstance(rec, _Named) else list(rec.sensors)
    # a folder's sensor is also known by its entry's name (an x-IMU3 device folder's id)
    known = {n: (n, rec.entries[n]) if isinstance(rec, _Named) else (n,) for n in names}
    source = rec.source
    renamed: dict[str, str] = {}  # the recording's name -> ours
    for ours, theirs in sensor_map.items():
        if ours not in SENSOR_NAMES:
            raise InputError(f"expected a sensor name among {list(SENSOR_NAMES)}, got {ours!r}",
                             file=source, field=f"sensors.{ours}")
        hits = [n for n in names if n == theirs] or [n for n in names
                                                     if any(theirs in k for k in known[n])]
        if len(hits) != 1:
            what = "no sensor" if not hits else f"several sensors ({hits})"
            raise InputError(f"{what} of the recording matches {theirs!r}; its sensors: {names}",
                             file=source, field=f"sensors.{ours}")
        if hits[0] in renamed:
            raise InputError(f"sensor {hits[0]!r} is mapped twice", file=source,
                             field=f"sensors.{ours}")
        renamed[hits[0]] = our_name(ours) or ours
    unnamed = []
    for n in names:
        if n not in renamed:
            ours = our_name(n)
            if ours is None and folder:
                unnamed.append(n)
            renamed[n] = ours or n
    if unnamed:
        where = [rec.entries[n] for n in unnamed]
        raise InputError(f"no sensor name for {where}: name each file after a sensor "
                         "(pelvis_imu.csv, femur_r_imu.csv, ...) or give --sensor-map "
                         "NAME=<part of its name>, or leave it out with --ignore",
                         file=source, field="sensor_map")
    taken: dict[str, str] = {}
    for theirs, ours in renamed.items():
        if ours in taken:
            raise InputError(f"two sensors for {ours}: {taken[ours]!r} and {theirs!r}",
                             file=source, field=f"sensors.{ours}")
        taken[ours] = theirs
    if isinstance(rec, _Named):
        out = _Named({renamed[n]: rec[n] for n in names})
        out.source, out.entries = rec.source, {renamed[n]: rec.entries[n] for n in names}
        return out
    if all(renamed[n] == n for n in names):
        return rec
    return rec.with_sensors({renamed[n]: rec.sensors[n] for n in names})


#: Folder names that say what a folder holds, not which recording it is: a recording in one is
#: named after the folder above (``S02/imu`` -> ``S02``).
GENERIC_NAMES = frozenset({"imu", "imus", "data", "raw", "sensors", "recording", "recordings",
                           "export", "exports", "csv", "trial", "files", "input", "inputs"})


def recording_name(path: str | Path) -> str:
    """The name a recording's outputs take: the file's stem, or the folder's name (an
    ``example:<name>``'s); a folder with a generic name (:data:`GENERIC_NAMES`) takes its parent
    folder's."""
    from pipeline.examples import resolve

    path = resolve(path)
    if path.suffix and not path.is_dir():
        return path.stem
    if path.name.lower() in GENERIC_NAMES:
        parent = Path(os.path.abspath(path)).parent.name
        return parent or path.name
    return path.name
