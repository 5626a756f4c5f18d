"""Orientations from raw signals, and which sensors' headings share one world.

Where a recording's sensors have no orientation (or the user asks for a filter), each one's
gyroscope, accelerometer and, if present and trusted, magnetometer go through an attitude filter
(:func:`pipeline.calibration.attitude.filter_orientations`: VQF by default, Hu's PI filter with
``filter='pi'``). The filters' world is z up (VQF 9-D: east-north-up; 6-D: a heading of each
sensor's own), so the filtered recording is turned to the model's y-up world by the caller
(:data:`Z_UP_TO_Y_UP`); a ``sensor_to_model`` of the user's would then be a mistake and is
refused. A recording whose sensors have orientations for some and not for others is refused
unless a filter is named (mixing a vendor's world with a filter's would put the segments in
different worlds).

**Magnetometers are trusted only where they agree** (:mod:`pipeline.calibration.magnetometer`:
field strength and dip against the other sensors' and over time). A sensor whose field is
disturbed is filtered without it (6-D), and its heading, like every 6-D sensor's, is its own:
:class:`Orientations` says which sensors' headings share one world (``shared``), so that the
joints align the others (:mod:`pipeline.process.heading_alignment`). The same check applies to a
vendor's orientations when the recording has the raw magnetometer: a sensor whose field was
disturbed may carry a wrong heading from the vendor's fusion.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field

import numpy as np

from pipeline.calibration.attitude import MAGNETOMETER_FILTERS, filter_orientations
from pipeline.calibration.conventions import DEFAULT_FILTER
from pipeline.calibration.magnetometer import FieldTrust, field_trust
from pipeline.errors import InputError
from pipeline.io.gaps import true_runs
from pipeline.io.recording import WORLD, Z_UP_WORLDS, Recording
from pipeline.process.sensors import known_segments
from pipeline.rotations import matrix_from_quat

__all__ = ["Z_UP_TO_Y_UP", "Orientations", "filter_own_samples", "gravity_in_world",
           "measured_up", "orientations_from_signals", "world_to_model"]

#: ``sensor_to_model`` of a z-up world (space-fixed XYZ angles, rad), as OpenSense's for Xsens.
Z_UP_TO_Y_UP = (-float(np.pi) / 2, 0.0, 0.0)


@dataclass(frozen=True)
class Orientations:
    """A recording with every model sensor's orientation, and how they were obtained.

    ``filtered``: None for the recording's own orientations, else ``'9-D'`` (every sensor with a
    trusted magnetometer), ``'6-D'`` (none) or ``'9-D and 6-D'``; ``shared``: the sensors whose
    headings are in one world (a vendor's or 9-D orientations with a trusted or no magnetometer);
    ``magnetometers``: sensor -> :class:`~pipeline.calibration.magnetometer.FieldTrust`
    of each sensor with a magnetometer."""

    recording: Recording
    filtered: str | None
    shared: frozenset[str]
    magnetometers: dict[str, FieldTrust] = field(default_factory=dict)

    @property
    def untrusted_fields(self) -> list[str]:
        return sorted(n for n, f in self.magnetometers.items() if not f.trusted)


def filter_own_samples(trial: Recording, name: str, method: str = DEFAULT_FILTER,
                       mag: np.ndarray | None = None) -> np.ndarray:
    """(N, 4) orientations of sensor ``name`` from its raw signals by ``method`` (``mag``: its
    magnetometer, for a 9-D filter); each run of its own samples (:meth:`Recording.present`)
    filtered on its own: a filter's state is not carried across a gap it did not see, it starts
    again after it (NaN over the gap)."""
    s = trial.sensors[name]
    q = np.full((trial.n_samples, 4), np.nan)
    for a, b in true_runs(trial.present(name)):
        if b - a >= 2:
            q[a:b] = filter_orientations(trial.time[a:b], s.gyr[a:b], s.acc[a:b],
                                         None if mag is None else mag[a:b], method=method)
    return q


def check_fields(trial: Recording, names: list[str]) -> dict[str, FieldTrust]:
    """:func:`~pipeline.calibration.magnetometer.field_trust` of the sensors ``names`` that have
    a magnetometer and raw gyroscope and accelerometer signals, over each one's own samples."""
    fields = {}
    for n in names:
        s = trial.sensors[n]
        if s.mag is not None and s.gyr is not None and s.acc is not None:
            own = trial.present(n)  # the world's z (up) in the sensor frame: R^T e_z
            up = matrix_from_quat(filter_own_samples(trial, n)[own])[:, 2, :]
            fields[n] = (s.mag[own], up)
    return field_trust(fields) if fields else {}


def orientations_from_signals(
    trial: Recording, method: str | None, notes: list[str], *, every_sensor: bool = False,
    rejected: frozenset[str] = frozenset(),
) -> Orientations:
    """Every model sensor's orientation (module docstring): by ``method`` (None: only if no
    sensor has one, then :data:`DEFAULT_FILTER`). ``every_sensor``: all sensors, not only those
    with a segment in the model. ``rejected``: the sensors whose own orientations a check left
    out (:mod:`pipeline.process.sensor_checks`, ``orientations``): in a vendor's z-up world they
    alone are filtered (6-D, their headings their own, aligned by the joints)."""
    names = list(trial.sensor_names) if every_sensor else list(known_segments(trial))
    have = [n for n in names if trial.sensors[n].quat is not None]
    if method is None and have and len(have) < len(names):
        missing = sorted(set(names) - set(have))
        if set(missing) <= rejected and trial.header.get(WORLD) in Z_UP_WORLDS:
            return _filtered_alone(trial, names, missing, notes)
        raise InputError(f"sensors {have} have orientations and {missing} do not: give --filter "
                         "vqf|pi to estimate all of them from their raw signals",
                         file=trial.source, field="filter")
    fields = check_fields(trial, names)
    for n, f in sorted(fields.items()):
        if not f.trusted:
            notes.append(f"{n}: magnetometer not trusted for its heading: {f.evidence}")
    if method is None and len(have) == len(names):
        shared = frozenset(n for n in names if n not in fields or fields[n].trusted)
        return Orientations(trial, None, shared, fields)
    method = method or DEFAULT_FILTER
    sensors = dict(trial.sensors)
    dims: dict[str, str] = {}
    for n in names:
        s = trial.sensors[n]
        if s.gyr is None or s.acc is None:
            raise InputError(f"sensor {n} has no gyroscope and accelerometer signals to estimate "
                             "its orientation from", file=trial.source, field=n)
        use_mag = method in MAGNETOMETER_FILTERS and n in fields and fields[n].trusted
        mag = s.mag if use_mag else None
        sensors[n] = s.replace(quat=filter_own_samples(trial, n, method, mag))
        dims[n] = "9-D" if use_mag else "6-D"
    kinds = sorted(set(dims.values()), reverse=True)
    filtered = " and ".join(kinds)
    six = sorted(n for n, d in dims.items() if d == "6-D")
    what = f"{method.upper()}, {filtered}" + (f" (6-D: {six})" if len(kinds) > 1 else "")
    notes.append(f"orientations estimated from the raw signals by {what}"
                 + (f", replacing the recording's own for {have}" if have else ""))
    shared = frozenset(n for n, d in dims.items() if d == "9-D")
    out = _restarted(trial.with_sensors(sensors), [n for n, d in dims.items() if d == "6-D"])
    return Orientations(out, filtered, shared, fields)


def _filtered_alone(trial: Recording, names: list[str], missing: list[str],
                    notes: list[str]) -> Orientations:
    """The recording's own orientations, and the ``missing`` sensors' from their raw signals
    (:data:`DEFAULT_FILTER`, 6-D: a z-up world whose heading is each one's own, beside the
    vendor's z-up world)."""
    fields = check_fields(trial, names)
    sensors = dict(trial.sensors)
    for n in missing:
        s = trial.sensors[n]
        if s.gyr is None or s.acc is None:
            raise InputError(f"sensor {n} has no gyroscope and accelerometer signals to estimate "
                             "its orientation from", file=trial.source, field=n)
        sensors[n] = s.replace(quat=filter_own_samples(trial, n))
    notes.append(f"orientations of {missing} estimated from their raw signals by "
                 f"{DEFAULT_FILTER.upper()}, 6-D (their own were rejected); the others' are the "
                 "recording's")
    shared = frozenset(n for n in names if n not in missing
                       and (n not in fields or fields[n].trusted))
    return Orientations(_restarted(trial.with_sensors(sensors), missing), None, shared, fields)


def _restarted(trial: Recording, six_d: list[str]) -> Recording:
    """``trial`` whose :attr:`~pipeline.io.gaps.Missing.restarted` names the ``six_d`` sensors
    with a gap: filtered here run by run (:func:`filter_own_samples`), each has after a gap a
    heading of its own."""
    restarted = frozenset(n for n in six_d if n in trial.missing.spans)
    if not restarted:
        return trial
    return dataclasses.replace(trial, missing=dataclasses.replace(trial.missing,
                                                                  restarted=restarted))


#: A measured up axis is accepted within this angle (deg) of a world axis.
UP_TOLERANCE_DEG = 20.0


def gravity_in_world(quat: np.ndarray, acc: np.ndarray) -> np.ndarray | None:
    """``R(q) a / |a|`` (M, 3) over the samples whose specific force is within 15 % of 1 g (at
    rest and on average in motion it points up in the orientations' world); None with fewer
    than 10 such samples."""
    a = np.nan_to_num(np.asarray(acc, float))
    norm = np.linalg.norm(a, axis=1)
    calm = np.abs(norm - 9.81) < 0.15 * 9.81
    if np.sum(calm) < 10:
        return None
    return np.einsum("nij,nj->ni", matrix_from_quat(quat[calm]), a[calm] / norm[calm, None])


def measured_up(rec: Recording) -> np.ndarray | None:
    """The world's up axis measured from the recording's own orientations and accelerometers:
    the median over every sensor of its :func:`gravity_in_world`, normalised; None without both
    signals."""
    ups = []
    for s in rec.sensors.values():
        up = None if s.quat is None or s.acc is None else gravity_in_world(s.quat, s.acc)
        if up is not None:
            ups.append(np.median(up, axis=0))
    if not ups:
        return None
    up = np.median(ups, axis=0)
    return up / max(float(np.linalg.norm(up)), 1e-12)


def world_to_model(rec: Recording) -> tuple[tuple[float, float, float] | None, str | None]:
    """How a recording's own orientations reach the model's y-up world without a
    ``sensor_to_model`` of the user's: ``(sensor_to_model, note)``. A vendor's world the reader
    named (``header[WORLD]``, :data:`~pipeline.io.recording.Z_UP_WORLDS`) is turned to y up; else
    the up axis measured by the accelerometers (:func:`measured_up`) decides: z up is turned, y up
    kept; anything else (or no accelerometer) is left as it is (``(None, None)``) for the vertical
    check to refuse with a hint."""
    vendor = rec.header.get(WORLD)
    if vendor in Z_UP_WORLDS:
        return Z_UP_TO_Y_UP, (f"the orientations' world: {Z_UP_WORLDS[vendor]} (the vendor's "
                              "format), turned to y up (no --sensor-to-model needed)")
    up = measured_up(rec)
    if up is None:
        return None, None
    close = np.cos(np.radians(UP_TOLERANCE_DEG))
    if up[2] > close:
        return Z_UP_TO_Y_UP, ("the orientations' world: z up, measured by the accelerometers "
                              f"(up {np.round(up, 2).tolist()}), turned to y up (no "
                              "--sensor-to-model needed)")
    return None, None
