"""A live capture's frames, kept on disk as they come: the memory stays flat however long it runs.

:class:`Spool` appends rows of a fixed width to a temporary file (deleted when closed) and reads
them back whole. :class:`CaptureStore` spools every frame's samples (one row: the time, then each
stream's signals in a layout fixed by the first frame, NaN where a stream misses it) and, in
memory, each sensor's live orientations only while the calibration still needs them (until it is
final: :meth:`CaptureStore.forget_orientations`). The live angles and the frames' processing
times are spooled alike (:class:`ColumnSpool`).
"""

from __future__ import annotations

import tempfile

import numpy as np

from pipeline.io.recording import Recording, SensorSignals
from pipeline.live.aligner import Block
from pipeline.live.channels import GROUPS

__all__ = ["CaptureStore", "ColumnSpool", "Spool"]


class Spool:
    """Rows of ``width`` floats appended to a temporary file, read back whole."""

    def __init__(self, width: int) -> None:
        self.width, self.n = int(width), 0
        self._file = tempfile.TemporaryFile()

    def append(self, rows: np.ndarray) -> None:
        rows = np.ascontiguousarray(rows, dtype=np.float64).reshape(-1, self.width)
        self._file.write(rows.tobytes())
        self.n += len(rows)

    def read(self, last: int | None = None) -> np.ndarray:
        """Every row, or the ``last`` rows."""
        first = 0 if last is None else max(self.n - int(last), 0)
        self._file.flush()
        self._file.seek(first * self.width * 8)
        out = np.fromfile(self._file, dtype=np.float64, count=(self.n - first) * self.width)
        self._file.seek(0, 2)
        return out.reshape(self.n - first, self.width)

    def close(self) -> None:
        self._file.close()


class ColumnSpool:
    """Named columns (e.g. the live angles) spooled a block at a time; a column a block lacks
    is NaN there."""

    def __init__(self, names) -> None:
        self.names = list(names)
        self._spool = Spool(len(self.names))

    def append(self, columns: dict[str, np.ndarray], m: int) -> None:
        rows = np.full((m, len(self.names)), np.nan)
        for j, name in enumerate(self.names):
            if name in columns:
                rows[:, j] = columns[name]
        self._spool.append(rows)

    def read(self) -> dict[str, np.ndarray]:
        data = self._spool.read()
        return {name: data[:, j] for j, name in enumerate(self.names)}

    def close(self) -> None:
        self._spool.close()


class CaptureStore:
    """The capture's frames (module docstring): ``names`` the streams."""

    def __init__(self, names) -> None:
        self.names = list(names)
        self._layout: list[tuple[str, str, int]] | None = None  # (stream, signal, width)
        self._spool: Spool | None = None
        self._rotations: dict[tuple[str, str], list[np.ndarray]] | None = {}

    @property
    def n(self) -> int:
        return 0 if self._spool is None else self._spool.n

    def add(self, block: Block, kinds: dict[str, dict[str, np.ndarray]]) -> None:
        if self._layout is None:
            self._layout = [(n, g, len(GROUPS[g])) for n in self.names
                            for g in GROUPS if getattr(block.sensors.get(n, SensorSignals()), g)
                            is not None]
            self._spool = Spool(1 + sum(w for *_, w in self._layout))
        m = len(block.time)
        parts = [block.time[:, None]]
        for n, g, w in self._layout:
            v = getattr(block.sensors.get(n, SensorSignals()), g)
            parts.append(v if v is not None else np.full((m, w), np.nan))
        self._spool.append(np.hstack(parts))
        if self._rotations is not None:
            for kind, rotations in kinds.items():
                for name, R in rotations.items():
                    self._rotations.setdefault((kind, name), []).append(R)

    def recording(self, rate_hz: float, header: dict, last: int | None = None) -> Recording:
        """Every frame so far, or the ``last`` frames, as one recording (read back from the
        disk)."""
        if self._spool is None:
            return Recording(np.zeros(0), rate_hz, {}, dict(header))
        data, k = self._spool.read(last), 1
        sensors: dict[str, dict[str, np.ndarray]] = {}
        for n, g, w in self._layout:
            sensors.setdefault(n, {})[g] = data[:, k:k + w]
            k += w
        return Recording(data[:, 0].copy(), rate_hz,
                         {n: SensorSignals(**sig) for n, sig in sensors.items()},
                         dict(header))

    def live_rotations(self) -> dict[str, dict[str, np.ndarray]]:
        """Kind (``own``, ``6-D``, ``9-D``) -> sensor -> (N, 3, 3) the live orientations."""
        out: dict[str, dict[str, np.ndarray]] = {}
        for (kind, name), v in (self._rotations or {}).items():
            out.setdefault(kind, {})[name] = np.concatenate(v)
        return out

    def forget_orientations(self) -> None:
        """No calibration will need them again: from now on the memory stays flat."""
        self._rotations = None

    def close(self) -> None:
        if self._spool is not None:
            self._spool.close()
