"""Orientations from raw signals: where a recording's sensors have no orientation (or the user
asks for a filter), each one's gyroscope, accelerometer and, if present, magnetometer go through an
attitude filter (:func:`pipeline.calibration.attitude.filter_orientations`: VQF by default, Hu's
PI filter with ``filter='pi'``).

The filters' world is z up (VQF 9-D: east-north-up; 6-D: a heading of each sensor's own), so the
filtered recording is turned to the model's y-up world here (``sensor_to_model`` of an Xsens-style
z-up world, ``-pi/2 0 0``); a ``sensor_to_model`` of the user's would then be a mistake and is
refused. A recording whose sensors have orientations for some and not for others is refused unless
a filter is named (mixing a vendor's world with a filter's would put the segments in different
worlds).
"""

from __future__ import annotations

import numpy as np

from pipeline.calibration.attitude import filter_orientations
from pipeline.calibration.conventions import DEFAULT_FILTER
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.process.sensors import known_segments

__all__ = ["Z_UP_TO_Y_UP", "orientations_from_signals"]

#: ``sensor_to_model`` of a z-up world (space-fixed XYZ angles, rad), as OpenSense's for Xsens.
Z_UP_TO_Y_UP = (-float(np.pi) / 2, 0.0, 0.0)


def orientations_from_signals(
    trial: Recording, method: str | None, notes: list[str], *, every_sensor: bool = False
) -> tuple[Recording, str | None]:
    """``(recording, filtered)``: the recording with every model sensor's orientation estimated by
    ``method`` (None: only if no sensor has one, then :data:`DEFAULT_FILTER`); ``filtered`` is
    None for the recording's own orientations, else ``'9-D'`` (every sensor with a magnetometer)
    or ``'6-D'`` (world z up either way). ``every_sensor``: all sensors, not only those with a
    segment in the model."""
    names = list(trial.sensor_names) if every_sensor else list(known_segments(trial))
    have = [n for n in names if trial.sensors[n].quat is not None]
    if method is None and len(have) == len(names):
        return trial, None
    if method is None and have:
        missing = sorted(set(names) - set(have))
        raise InputError(f"sensors {have} have orientations and {missing} do not: give --filter "
                         "vqf|pi to estimate all of them from their raw signals",
                         file=trial.source, field="filter")  # fmt: skip
    method = method or DEFAULT_FILTER
    sensors = dict(trial.sensors)
    dims = set()
    for n in names:
        s = trial.sensors[n]
        if s.gyr is None or s.acc is None:
            raise InputError(f"sensor {n} has no gyroscope and accelerometer signals to estimate "
                             "its orientation from", file=trial.source, field=n)  # fmt: skip
        mag = s.mag if method == "vqf" else None
        sensors[n] = s.replace(quat=filter_orientations(trial.time, s.gyr, s.acc, mag,
                                                        method=method))  # fmt: skip
        dims.add("9-D (magnetometer)" if mag is not None else "6-D (no magnetometer)")
    notes.append(f"orientations estimated from the raw signals by {method.upper()}, "
                 f"{' and '.join(sorted(dims))}"
                 + (f", replacing the recording's own for {have}" if have else ""))  # fmt: skip
    return trial.with_sensors(sensors), ("9-D" if dims == {"9-D (magnetometer)"} else "6-D")
