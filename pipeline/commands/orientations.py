"""``pipeline orientations``: raw IMU signals in, an OpenSense-compatible orientation ``.sto`` out.

OpenSense's IMU inverse kinematics assumes that the vendor did the sensor fusion; this command
does it for recordings without (or with untrusted) orientations: every sensor of a folder (or one
file) through an attitude filter (:func:`pipeline.calibration.attitude.filter_orientations`: VQF
or Hu's PI filter), written as ``.sto`` quaternions (``w,x,y,z``) with OpenSense's sensor names.
The world is the filter's, z up, so OpenSense (and ``pipeline ik``) need the usual
``sensor_to_opensim_rotations`` of ``-pi/2 0 0``, as for Xsens; the header says so.
"""

from __future__ import annotations

from pathlib import Path

from pipeline.calibration.conventions import DEFAULT_FILTER
from pipeline.errors import InputError
from pipeline.io.formats import read_recording
from pipeline.io.opensim import write_orientations_sto
from pipeline.process.signals import orientations_from_signals

__all__ = ["run_orientations"]


def run_orientations(
    imu: str | Path,
    out: str | Path,
    *,
    filter: str = DEFAULT_FILTER,  # noqa: A002 (the CLI's name)
    sensor_map: dict[str, str] | None = None,
    ignore: tuple[str, ...] = (),
) -> str:
    """Filter every sensor of ``imu`` (any recording :func:`read_recording` reads: a folder of
    raw recordings, one IMU file) and write ``out`` (``.sto``); return the lines to print."""
    imu, out = Path(imu), Path(out)
    if out.suffix.lower() != ".sto":
        raise InputError("expected an output file ending in .sto", file=out)
    rec = read_recording(imu, sensor_map, ignore=ignore)
    notes: list[str] = []
    rec = orientations_from_signals(rec, filter, notes, every_sensor=True).recording
    rec = rec.with_sensors({n: s for n, s in rec.sensors.items() if s.quat is not None})
    write_orientations_sto(out, rec, header={"WorldUp": "z", "SensorToOpenSimRotations":
                                             "-1.5708 0 0"})
    lines = [f"wrote {out}: {len(rec.sensors)} sensors ({', '.join(rec.sensor_names)}), "
             f"{rec.n_samples} samples at {rec.rate_hz:.4g} Hz",
             *notes, *rec.notes,
             "world z up: give OpenSense sensor_to_opensim_rotations -1.5708 0 0 (pipeline ik: "
             "--sensor-to-model -1.5708 0 0)"]
    return "\n".join(lines)
