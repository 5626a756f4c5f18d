"""A folder of raw IMU recordings, one per sensor, as one :class:`Recording` on one clock.

Formats, detected per entry of the folder:

* our IMU CSV (``time,gyr_x,...``, :mod:`pipeline.io.imu_csv`; what ``pipeline simulate``
  writes), one ``<sensor>.csv`` per sensor;
* Movella DOT ``.csv`` exports (:func:`pipeline.io.vendor_imu.read_movella_dot_csv`);
* x-IMU3 device folders (:func:`pipeline.io.vendor_imu.read_ximu3_folder`), whose labels
  (``pelvis``, ``Right Upper Leg``, ``Left Foot``, ...) name the segment.

Sensor names: a file named after one of our sensors (``femur_r_imu.csv``, or the model's frame
name ``right_femur_imu.csv`` that ``pipeline simulate`` writes) is that sensor; the
x-IMU3 body-part labels map to ours (:data:`XIMU3_LABELS`); ``sensor_map`` (our name -> a part of
the file name, e.g. a device id) maps anything else, and every entry of it must match exactly one
file. Files that map to no sensor are left out, with a note.

Clocks: each sensor's time stamps are its own (devices start a few ms apart). The recording keeps
the span all sensors cover, on the grid ``t0 + k / rate`` with ``rate`` the sensors' common rate
(refused if they differ by more than 1 %); every signal is interpolated onto it (linear; the
quaternions by normalised linear interpolation between sign-aligned neighbours). The summary
notes say how far the devices' clocks were apart and what was cropped.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.io.checks import check_same_rate
from pipeline.io.imu_csv import read_imu_csv
from pipeline.io.opensim import SENSOR_TO_SEGMENT
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.vendor_imu import read_movella_dot_csv, read_ximu3_folder

__all__ = [
    "MODEL_FRAME_NAMES",
    "XIMU3_LABELS",
    "align_clocks",
    "imu_format",
    "read_imu_file",
    "read_imu_folder",
]

#: x-IMU3 example labels (lower case) -> our sensor names.
XIMU3_LABELS = {
    "pelvis": "pelvis_imu",
    "right upper leg": "femur_r_imu", "right lower leg": "tibia_r_imu", "right foot": "calcn_r_imu",
    "left upper leg": "femur_l_imu", "left lower leg": "tibia_l_imu", "left foot": "calcn_l_imu",
}  # fmt: skip
#: The model's IMU frame names (what ``pipeline simulate`` names its files) -> our sensor names.
MODEL_FRAME_NAMES = {f"{seg}_imu": name for name, seg in SENSOR_TO_SEGMENT.items()
                     if seg != "torso"}  # fmt: skip


def imu_format(path: str | Path) -> str | None:
    """``'ximu3'`` (a device folder), ``'dot'`` (a Movella DOT export), ``'imu_csv'`` (ours), or
    None: what the entry looks like, from its name and first lines."""
    path = Path(path)
    if path.is_dir():
        return "ximu3" if (path / "Inertial.csv").is_file() else None
    if path.suffix.lower() != ".csv" or not path.is_file():
        return None
    with open(path, encoding="utf-8", errors="replace") as fh:
        head = [fh.readline() for _ in range(12)]
    if any(line.startswith("PacketCounter") for line in head):
        return "dot"
    first = head[0].strip().lower().split(",") if head else []
    return "imu_csv" if first[:1] == ["time"] and "gyr_x" in first else None


def read_imu_file(path: str | Path) -> Recording:
    """One sensor's recording in any of the module's formats; anything else is read as our IMU
    CSV, whose reader says what is missing."""
    kind = imu_format(path)
    if kind == "ximu3":
        return read_ximu3_folder(path)
    return read_movella_dot_csv(path) if kind == "dot" else read_imu_csv(path)


def _read_entry(path: Path) -> Recording | None:
    return read_imu_file(path) if imu_format(path) is not None else None


def _name_of(path: Path, sensor_map: Mapping[str, str]) -> str | None:
    hits = [ours for ours, part in sensor_map.items() if part in path.name]
    if len(hits) > 1:
        raise InputError(f"matches several sensors of the map: {hits}", file=path,
                         field="sensor_map")  # fmt: skip
    if hits:
        return hits[0]
    if path.stem in SENSOR_TO_SEGMENT:
        return path.stem
    if path.stem in MODEL_FRAME_NAMES:
        return MODEL_FRAME_NAMES[path.stem]
    label = path.name.split(" (")[0].rsplit(" ", 1)[0].lower() if path.is_dir() else ""
    return XIMU3_LABELS.get(label)


def read_imu_folder(folder: str | Path, sensor_map: Mapping[str, str] | None = None) -> Recording:
    """Every sensor of ``folder`` (module docstring) on one time base starting at 0."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError("not a folder", file=folder)
    sensor_map = dict(sensor_map or {})
    recs: dict[str, Recording] = {}
    skipped = []
    for entry in sorted(folder.iterdir()):
        rec = _read_entry(entry)
        if rec is None:
            continue
        name = _name_of(entry, sensor_map)
        if name is None:
            skipped.append(entry.name)
            continue
        if name in recs:
            raise InputError(f"two files for {name}: {recs[name].source.name} and {entry.name}",
                             file=folder)  # fmt: skip
        recs[name] = rec
    unmatched = sorted(set(sensor_map) - set(recs))
    if unmatched:
        raise InputError(f"no file for {', '.join(f'{k}={sensor_map[k]!r}' for k in unmatched)}",
                         file=folder, field=f"sensors.{unmatched[0]}")  # fmt: skip
    if not recs:
        raise InputError(
            "no IMU recording with a sensor name: expected <sensor>.csv files (pelvis_imu.csv, "
            "femur_r_imu.csv, ...), Movella DOT .csv exports or x-IMU3 device folders, or a "
            "--sensor-map NAME=ID", file=folder)  # fmt: skip
    out = align_clocks(recs, source=folder)
    if skipped:
        out = Recording(out.time, out.rate_hz, out.sensors, out.header,
                        out.notes + (f"files with no sensor name, left out: {skipped}",),
                        folder)  # fmt: skip
    return out


def _nlerp(t_src: np.ndarray, q: np.ndarray, t: np.ndarray) -> np.ndarray:
    i = np.clip(np.searchsorted(t_src, t, side="right") - 1, 0, len(t_src) - 2)
    a = ((t - t_src[i]) / (t_src[i + 1] - t_src[i]))[:, None]
    q0, q1 = q[i], q[i + 1]
    q1 = np.where(np.sum(q0 * q1, axis=1, keepdims=True) < 0, -q1, q1)
    out = (1 - a) * q0 + a * q1
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def align_clocks(recs: Mapping[str, Recording], *, source: Path | None = None) -> Recording:
    """One-sensor recordings on their own clocks -> one recording on the common span and rate
    (module docstring)."""
    rate = check_same_rate({n: r.rate_hz for n, r in recs.items()}, file=source)
    starts = {n: float(r.time[0]) for n, r in recs.items()}
    ends = {n: float(r.time[-1]) for n, r in recs.items()}
    t0, t1 = max(starts.values()), min(ends.values())
    if t1 - t0 < 10.0 / rate:
        raise InputError(f"the sensors' time stamps do not overlap (starts {starts}, ends {ends})",
                         file=source)  # fmt: skip
    n = int(np.floor((t1 - t0) * rate + 1e-9)) + 1
    t = t0 + np.arange(n) / rate
    same = all(r.time.size == n and np.allclose(r.time, t, atol=1e-9, rtol=0)
               for r in recs.values())  # fmt: skip
    sensors: dict[str, SensorSignals] = {}
    notes: list[str] = [m for r in recs.values() for m in r.notes]
    for name, r in recs.items():
        s = r.sensor
        if same:
            sensors[name] = s
            continue
        fields = {}
        for key in ("gyr", "acc", "mag"):
            v = getattr(s, key)
            fields[key] = None if v is None else np.stack(
                [np.interp(t, r.time, v[:, k]) for k in range(3)], axis=1)  # fmt: skip
        fields["quat"] = None if s.quat is None else _nlerp(r.time, s.quat, t)
        sensors[name] = SensorSignals(**fields)
    if not same:
        spread = 1e3 * (max(starts.values()) - min(starts.values()))
        notes.append(f"clocks aligned by time stamp: devices started up to {spread:.1f} ms apart; "
                     f"kept the {t1 - t0:.2f} s all cover, resampled to {rate:.4g} Hz")  # fmt: skip
    return Recording(t - t0, float(rate), sensors, {"DataRate": f"{rate:.6f}"}, tuple(notes),
                     source)  # fmt: skip
