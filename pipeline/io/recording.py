"""The one type of an IMU recording: :class:`Recording`, what every reader and the simulators
return.

A recording is one time base (``time`` (N,) s, strictly increasing; ``rate_hz``) and named
sensors, each with any of: the orientation ``quat`` (N, 4) unit ``[w, x, y, z]`` (sensor frame in
the IMU world, ``p_world = R(q) p_sensor``), the angular velocity ``gyr`` (N, 3) rad/s, the
specific force ``acc`` (N, 3) m/s^2 and the magnetic field ``mag`` (N, 3) (arbitrary units), all
in the sensor frame and in SI units (readers convert). ``header`` keeps the file's metadata,
``notes`` what the reader repaired or noticed, ``source`` the file or folder it came from, and
``sensor_notes`` (sensor -> its own file's notes, for a folder of one-sensor files) which sensor
a repair concerns (dropped samples filled, an irregular clock: the sensor check names them).
``missing`` (:class:`~pipeline.io.gaps.Missing`) says which samples of a sensor were bridged
after reading (:mod:`pipeline.process.missing`): a statistic or a fit takes
:meth:`Recording.present` rows only.

``header[WORLD]`` names the world frame of the orientations when the reader knows it from the
vendor (:data:`Z_UP_WORLDS`: a vendor's earth frame with z up, which ``pipeline ik`` turns to its
y-up world itself); a recording without it (OpenSim ``.sto``, our IMU CSV) needs the user's
``--sensor-to-model`` unless its world is y up.

A one-sensor recording (one IMU CSV, one Xsens ``.txt``, a simulated sensor) gives its signals
directly: ``rec.gyr`` is ``rec.sensors[name].gyr`` when there is exactly one sensor.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.filtering import lowpass
from pipeline.io.gaps import Missing
from pipeline.rotations import matrix_from_quat, quat_from_matrix

__all__ = ["WORLD", "Z_UP_WORLDS", "Recording", "SensorSignals", "world_of"]

#: The header key naming the orientations' world frame (module docstring).
WORLD = "world"
#: The vendors' worlds with z up: the value of ``header[WORLD]`` -> what it is.
Z_UP_WORLDS = {
    "movella-dot": "Movella DOT: east-north-up, z up",
    "xsens": "Xsens MT: the local earth frame (x north or east), z up",
    "ximu3": "x-IMU3: the earth frame, z up",
}


def world_of(recordings) -> str | None:
    """The world the recordings share (``header[WORLD]``), None when one has none or they
    differ."""
    worlds = {r.header.get(WORLD) for r in recordings}
    return worlds.pop() if len(worlds) == 1 else None


@dataclass(frozen=True)
class SensorSignals:
    """One sensor's signals on its recording's time base; ``None`` where not recorded."""

    quat: np.ndarray | None = None
    gyr: np.ndarray | None = None
    acc: np.ndarray | None = None
    mag: np.ndarray | None = None

    def replace(self, **changes: np.ndarray | None) -> SensorSignals:
        return dataclasses.replace(self, **changes)

    def rows(self, rows: slice) -> SensorSignals:
        """The signals of samples ``rows``."""
        return SensorSignals(*(None if v is None else v[rows]
                               for v in (self.quat, self.gyr, self.acc, self.mag)))

    @property
    def complete(self) -> bool:
        """Whether the gyroscope's and the accelerometer's signals are there, every sample
        finite (what a joint's fit or a stride's view needs)."""
        return (self.gyr is not None and self.acc is not None
                and bool(np.isfinite(self.gyr).all() and np.isfinite(self.acc).all()))

    def low_passed(self, rate_hz: float, cutoff_hz: float) -> SensorSignals:
        """The gyroscope's and the accelerometer's signals low-passed
        (:func:`pipeline.filtering.lowpass`); the orientations and the magnetometer as they are."""
        return self.replace(**{k: lowpass(getattr(self, k), rate_hz, cutoff_hz)
                               for k in ("gyr", "acc") if getattr(self, k) is not None})

    def turned(self, R: np.ndarray) -> SensorSignals:
        """The same sensor mounted turned by ``R`` (3, 3) on its segment, its new axes ``R``'s
        columns in the old frame: every vector it measures ``x' = R^T x`` (rows: ``x @ R``), its
        orientation ``q' = q R``."""
        R = np.asarray(R, dtype=float)
        vectors = {k: getattr(self, k) @ R for k in ("gyr", "acc", "mag")
                   if getattr(self, k) is not None}
        if self.quat is not None:
            vectors["quat"] = quat_from_matrix(matrix_from_quat(self.quat) @ R)
        return self.replace(**vectors)


@dataclass(frozen=True)
class Recording:
    """Named sensors on one time base (module docstring)."""

    time: np.ndarray
    rate_hz: float
    sensors: dict[str, SensorSignals]
    header: dict[str, str] = field(default_factory=dict)
    notes: tuple[str, ...] = ()
    source: Path | None = None
    sensor_notes: dict[str, tuple[str, ...]] = field(default_factory=dict)
    missing: Missing = field(default_factory=Missing)

    # ---- construction -------------------------------------------------------------------------
    @classmethod
    def single(
        cls,
        name: str,
        time: np.ndarray,
        *,
        quat: np.ndarray | None = None,
        gyr: np.ndarray | None = None,
        acc: np.ndarray | None = None,
        mag: np.ndarray | None = None,
        rate_hz: float | None = None,
        header: Mapping[str, str] | None = None,
        notes: tuple[str, ...] = (),
        source: Path | None = None,
    ) -> Recording:
        """A one-sensor recording; ``rate_hz`` defaults to ``1 / median(diff(time))``."""
        time = np.asarray(time, dtype=float)
        if rate_hz is None:
            rate_hz = float(1.0 / np.median(np.diff(time))) if time.size > 1 else float("nan")
        signals = SensorSignals(quat, gyr, acc, mag)
        return cls(time, float(rate_hz), {name: signals}, dict(header or {}), tuple(notes), source)

    @classmethod
    def from_orientations(
        cls,
        time: np.ndarray,
        rate_hz: float,
        quats: Mapping[str, np.ndarray],
        *,
        header: Mapping[str, str] | None = None,
        notes: tuple[str, ...] = (),
        source: Path | None = None,
    ) -> Recording:
        """Orientations only: sensor name -> (N, 4) ``[w, x, y, z]``."""
        sensors = {name: SensorSignals(quat=np.asarray(q, float)) for name, q in quats.items()}
        return cls(np.asarray(time, float), float(rate_hz), sensors, dict(header or {}),
                   tuple(notes), source)

    def with_sensors(self, sensors: Mapping[str, SensorSignals]) -> Recording:
        """The same recording with other sensors (same time base)."""
        return dataclasses.replace(self, sensors=dict(sensors))

    def cropped(self, start: int, stop: int | None = None) -> Recording:
        """Samples ``start:stop`` as a recording that starts there (its time from 0, its missing
        spans with it): a trimmed file, a sensor started late."""
        rows = slice(start, stop)
        time = self.time[rows]
        return dataclasses.replace(
            self, time=time - self.time[start],
            sensors={n: s.rows(rows) for n, s in self.sensors.items()},
            missing=self.missing.cropped(start, len(time)))

    def with_notes(self, *notes: str) -> Recording:
        """The same recording with more notes."""
        return dataclasses.replace(self, notes=(*self.notes, *notes))

    # ---- names and views ----------------------------------------------------------------------
    @property
    def n_samples(self) -> int:
        return int(self.time.size)

    @property
    def sensor_names(self) -> tuple[str, ...]:
        return tuple(self.sensors)

    def present(self, *names: str) -> np.ndarray:
        """(N,) bool: the samples each of the sensors ``names`` (default: all) has of its own,
        not bridged over a gap (:attr:`missing`)."""
        out = np.ones(self.n_samples, dtype=bool)
        for name in names or self.sensor_names:
            out &= ~self.missing.mask(name, self.n_samples)
        return out

    def orientations(self) -> dict[str, np.ndarray]:
        """Sensor name -> (N, 4) quaternions, for the sensors that have them."""
        return {n: s.quat for n, s in self.sensors.items() if s.quat is not None}

    # ---- a one-sensor recording ---------------------------------------------------------------
    @property
    def sensor(self) -> SensorSignals:
        """The signals of a one-sensor recording (an error names the sensors otherwise)."""
        if len(self.sensors) != 1:
            raise InputError(
                f"expected a one-sensor recording, found sensors {list(self.sensors)}",
                file=self.source,
            )
        return next(iter(self.sensors.values()))

    @property
    def name(self) -> str:
        """The sensor name of a one-sensor recording."""
        self.sensor  # noqa: B018  (raises for several sensors)
        return next(iter(self.sensors))

    @property
    def quat(self) -> np.ndarray | None:
        return self.sensor.quat

    @property
    def gyr(self) -> np.ndarray | None:
        return self.sensor.gyr

    @property
    def acc(self) -> np.ndarray | None:
        return self.sensor.acc

    @property
    def mag(self) -> np.ndarray | None:
        return self.sensor.mag
