"""Each sensor's orientation frame by frame, in the model's y-up world.

A stream that carries its own orientations (the vendor's fusion, ``quat``) is used as it comes,
turned into the model's world as offline (:func:`pipeline.process.prepare.model_world`). Raw
signals go through VQF's online filter (Laidig & Seel 2023, the ``vqf`` package's ``VQF``: the
same filter as offline without its backward pass), one per sensor, fed block by block; its 9-D
output (the magnetometer's heading) is used for the sensors whose magnetometer the calibration
trusted, its 6-D output for the others, whose heading the joints' alignment turns (the
calibration's turn held from then on, :mod:`pipeline.live.calibration`). With ``--filter pi``,
Hu 2021's PI filter (:class:`~pipeline.calibration.attitude.PIState`, the offline filter's
gains) steps instead, 6-D, seeded as offline by the sensor's still start once it moves
(:class:`StillStart`). A frame a sensor misses gives NaN, and its
filter is not fed (it goes on from its last sample when the stream is back).
"""

from __future__ import annotations

import numpy as np

from pipeline.io.opensim import sensor_to_opensim_matrix
from pipeline.io.recording import SensorSignals
from pipeline.process.signals import Z_UP_TO_Y_UP
from pipeline.rotations import matrix_from_quat

__all__ = ["LiveOrientations"]


class LiveOrientations:
    """Sensor -> (m, 3, 3) orientations of each block (module docstring). ``own``: the streams
    carry their orientations (used as they are, turned by ``world``); else ``method``'s filter
    (``'vqf'`` online, or ``'pi'``) at ``rate_hz``."""

    def __init__(self, names, rate_hz: float, own: bool, world: np.ndarray | None = None,
                 method: str = "vqf") -> None:
        self.names, self.own, self.method = list(names), bool(own), method
        self.world = np.eye(3) if world is None else np.asarray(world, float)
        if not self.own:
            self.world = sensor_to_opensim_matrix(Z_UP_TO_Y_UP)
        self.period = 1.0 / rate_hz
        self._filters = {} if self.own or method == "pi" else {n: _vqf(rate_hz)
                                                               for n in self.names}
        self.nine_d: frozenset[str] = frozenset()  # the sensors whose 9-D output is used

    def update(self, sensors: dict[str, SensorSignals]) -> dict[str, dict[str, np.ndarray]]:
        """One block's orientations, NaN where a sensor misses a frame: ``'own'`` (the
        streams'), or ``'6-D'`` and ``'9-D'`` (the filter's, 9-D for sensors with a
        magnetometer), each sensor -> (m, 3, 3); :meth:`chosen` picks each sensor's."""
        quats: dict[tuple[str, str], np.ndarray] = {}
        for name in self.names:
            s = sensors.get(name)
            for kind, q in (self._quats(name, s) if s is not None else {}).items():
                quats[(kind, name)] = q
        if not quats:
            return {}
        q = np.concatenate(list(quats.values()))  # one conversion for every sensor
        R = np.full((len(q), 3, 3), np.nan)
        ok = np.all(np.isfinite(q), axis=1)
        R[ok] = self.world @ matrix_from_quat(q[ok])
        m = len(next(iter(quats.values())))
        out: dict[str, dict[str, np.ndarray]] = {}
        for i, (kind, name) in enumerate(quats):
            out.setdefault(kind, {})[name] = R[i * m:(i + 1) * m]
        return out

    def chosen(self, kinds: dict[str, dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
        """Sensor -> the orientations the frames use: its own, else 9-D where trusted, 6-D."""
        if "own" in kinds:
            return kinds["own"]
        six, nine = kinds.get("6-D", {}), kinds.get("9-D", {})
        return {n: nine[n] if n in self.nine_d and n in nine else R for n, R in six.items()}

    def _quats(self, name: str, s: SensorSignals) -> dict[str, np.ndarray]:
        if self.own:
            return {} if s.quat is None else {"own": s.quat}
        if s.gyr is None or s.acc is None:
            return {}
        ok = np.all(np.isfinite(s.gyr), axis=1) & np.all(np.isfinite(s.acc), axis=1)
        six, nine = np.full((len(ok), 4), np.nan), np.full((len(ok), 4), np.nan)
        if ok.any() and self.method == "pi":
            six[ok] = self._pi(name, s.gyr[ok], s.acc[ok])
            return {"6-D": six}
        if ok.any():
            f = self._filters[name]
            gyr, acc = np.ascontiguousarray(s.gyr[ok]), np.ascontiguousarray(s.acc[ok])
            mag = None if s.mag is None else np.ascontiguousarray(np.nan_to_num(s.mag[ok]))
            out = f.updateBatch(gyr, acc, mag) if mag is not None else f.updateBatch(gyr, acc)
            six[ok] = out["quat6D"]
            if mag is not None:
                nine[ok] = out["quat9D"]
        return {"6-D": six, **({"9-D": nine} if s.mag is not None else {})}

    def _pi(self, name: str, gyr: np.ndarray, acc: np.ndarray) -> np.ndarray:
        """The PI filter's attitudes (m, 4) over a sensor's samples, its state kept; seeded by
        its still start once it moves (:class:`StillStart`)."""
        from pipeline.calibration.attitude import TUNED, PIState, upright

        if name not in self._filters:
            self._filters[name] = (PIState(upright(acc[0]), TUNED["lambda_p"], TUNED["lambda_i"],
                                           TUNED["acc_lowpass_s"]), StillStart(self.period))
        state, start = self._filters[name]
        k = start.feed(gyr, acc)  # the block's samples still from the sensor's first one
        out = np.empty((len(gyr), 4))
        out[:k] = state.run(gyr[:k], acc[:k], np.full(k, self.period))[0]
        if k < len(gyr) and not start.moved:
            start.seed(state)
        out[k:] = state.run(gyr[k:], acc[k:], np.full(len(gyr) - k, self.period))[0]
        return out


class StillStart:
    """A sensor's still start, as the offline PI filter's ``rest_start`` reads it
    (:func:`pipeline.calibration.attitude.still_start`): the mean gyro and specific force of the
    samples still from its first one; when it first moves, a long enough start seeds the
    filter (:meth:`seed`): upright by the mean force, its integral minus the mean gyro (the
    bias, whose vertical part no later sample corrects: unseeded, S02's pelvis turned 7 deg
    from the offline filter's within 6 s of the calibration)."""

    def __init__(self, period: float) -> None:
        self.period, self.n, self.moved = period, 0, False
        self.gyr, self.acc = np.zeros(3), np.zeros(3)

    def feed(self, gyr: np.ndarray, acc: np.ndarray) -> int:
        """How many of the block's first samples continue the still start."""
        if self.moved:
            return 0
        from pipeline.calibration.attitude import still_start

        k = still_start(gyr, acc)
        self.gyr, self.acc = self.gyr + gyr[:k].sum(axis=0), self.acc + acc[:k].sum(axis=0)
        self.n += k
        return k

    def seed(self, state) -> None:
        """At the first movement: the state seeded from a long enough still start
        (:meth:`~pipeline.calibration.attitude.PIState.seed_at_rest`)."""
        from pipeline.calibration.attitude import REST_START_S

        self.moved = True
        if self.n * self.period >= REST_START_S:
            state.seed_at_rest(self.gyr / self.n, self.acc / self.n)


def _vqf(rate_hz: float):
    from vqf import VQF  # the compiled filter

    return VQF(1.0 / rate_hz)
