"""A live stream's channels: one sensor per stream, its channels labelled as our IMU CSV's columns.

An LSL stream of type ``IMU`` (:mod:`pipeline.live.sources`) carries one sensor; its
``desc/channels/channel/label`` name each channel: ``gyr_x gyr_y gyr_z`` (rad/s) and ``acc_x
acc_y acc_z`` (m/s^2), and optionally ``mag_x mag_y mag_z`` (any unit) and ``quat_w quat_x quat_y
quat_z`` (sensor -> world, scalar first), in any order (:mod:`pipeline.io.imu_csv`'s columns).
:func:`layout_of` reads the labels once when the stream is opened and refuses, in one line naming
the stream, a stream whose labels are not these; :func:`split` turns a chunk of samples into the
signals of :class:`~pipeline.io.recording.SensorSignals`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.errors import InputError
from pipeline.io.imu_csv import ACC_COLUMNS, GYR_COLUMNS, MAG_COLUMNS, QUAT_COLUMNS

__all__ = ["GROUPS", "Layout", "layout_of", "split"]

#: Signal -> its channels' labels, in the order of its vector.
GROUPS = {"gyr": GYR_COLUMNS, "acc": ACC_COLUMNS, "mag": MAG_COLUMNS, "quat": QUAT_COLUMNS}
_REQUIRED = ("gyr", "acc")


@dataclass(frozen=True)
class Layout:
    """Signal -> the channel indices of its components (the signals a stream carries)."""

    columns: dict[str, tuple[int, ...]]
    n_channels: int

    @property
    def labels(self) -> list[str]:
        out = [""] * self.n_channels
        for signal, idx in self.columns.items():
            for label, k in zip(GROUPS[signal], idx, strict=True):
                out[k] = label
        return out


def _expected() -> str:
    return ("expected channels labelled gyr_x gyr_y gyr_z acc_x acc_y acc_z, optionally "
            "mag_x mag_y mag_z and quat_w quat_x quat_y quat_z (our IMU CSV's columns)")


def layout_of(labels: list[str], stream: str, n_channels: int | None = None) -> Layout:
    """The :class:`Layout` of a stream whose channels are ``labels`` (refused, naming
    ``stream``, when a label is unknown or repeated, a signal incomplete, or the labels do not
    match the stream's ``n_channels``)."""
    labels = [str(x).strip().lower() for x in labels]
    if n_channels is not None and len(labels) != n_channels:
        raise InputError(f"stream {stream!r} has {n_channels} channels but {len(labels)} labels: "
                         f"{_expected()}", field="channels")
    where = {label: k for k, label in enumerate(labels)}
    known = {label for group in GROUPS.values() for label in group}
    unknown = [x for x in labels if x not in known]
    if unknown or len(where) != len(labels):
        what = f"unknown labels {unknown}" if unknown else "a label repeated"
        raise InputError(f"stream {stream!r}: {what} in {labels}: {_expected()}",
                         field="channels")
    columns = {}
    for signal, group in GROUPS.items():
        have = [x in where for x in group]
        if any(have) and not all(have) or signal in _REQUIRED and not all(have):
            raise InputError(f"stream {stream!r}: {signal} incomplete in {labels}: "
                             f"{_expected()}", field="channels")
        if all(have):
            columns[signal] = tuple(where[x] for x in group)
    return Layout(columns, len(labels))


def split(values: np.ndarray, layout: Layout) -> dict[str, np.ndarray]:
    """Signal -> (n, 3 or 4) float array of a chunk ``values`` (n, channels)."""
    values = np.asarray(values, dtype=float).reshape(-1, layout.n_channels)
    return {signal: values[:, list(idx)] for signal, idx in layout.columns.items()}
