"""Each sensor's orientation frame by frame, in the model's y-up world.

A stream that carries its own orientations (the vendor's fusion, ``quat``) is used as it comes,
turned into the model's world as offline (:func:`pipeline.process.prepare.model_world`). Raw
signals go through VQF's online filter (Laidig & Seel 2023, the ``vqf`` package's ``VQF``: the
same filter as offline without its backward pass), one per sensor, fed block by block; its 9-D
output (the magnetometer's heading) is used for the sensors whose magnetometer the calibration
trusted, its 6-D output for the others, whose heading the joints' alignment turns (the
calibration's turn held from then on, :mod:`pipeline.live.calibration`). A frame a sensor misses
gives NaN, and its filter is not fed (it goes on from its last sample when the stream is back).
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
    carry their orientations (used as they are, turned by ``world``); else VQF online at
    ``rate_hz``."""

    def __init__(self, names, rate_hz: float, own: bool, world: np.ndarray | None = None) -> None:
        self.names, self.own = list(names), bool(own)
        self.world = np.eye(3) if world is None else np.asarray(world, float)
        if not self.own:
            self.world = sensor_to_opensim_matrix(Z_UP_TO_Y_UP)
        self._filters = {} if self.own else {n: _vqf(rate_hz) for n in self.names}
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
        if ok.any():
            f = self._filters[name]
            gyr, acc = np.ascontiguousarray(s.gyr[ok]), np.ascontiguousarray(s.acc[ok])
            mag = None if s.mag is None else np.ascontiguousarray(np.nan_to_num(s.mag[ok]))
            out = f.updateBatch(gyr, acc, mag) if mag is not None else f.updateBatch(gyr, acc)
            six[ok] = out["quat6D"]
            if mag is not None:
                nine[ok] = out["quat9D"]
        return {"6-D": six, **({"9-D": nine} if s.mag is not None else {})}


def _vqf(rate_hz: float):
    from vqf import VQF  # the compiled filter

    return VQF(1.0 / rate_hz)
