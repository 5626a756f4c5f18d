"""One recording's evidence, computed once and shared by the sensor checks and the run: its gait
(each leg's events and strides, :func:`pipeline.process.gait.gait_of`), its still windows
(:mod:`pipeline.process.still`) and its legs' slip views (:mod:`pipeline.process.slip`).

A check that changes the recording (a sensor excluded, two read back) hands on the context of the
changed recording (:meth:`CheckContext.of`); an unchanged recording keeps its context, so that the
strides a check found are the ones the run uses. A context starts from a recording as read
(:meth:`CheckContext.of_recording`): its sensors' missing samples found and bridged
(:mod:`pipeline.process.missing`), so that every check sees finite signals and the dropout
check sees the spans.
"""

from __future__ import annotations

from functools import cached_property

import numpy as np

from pipeline.io.gaps import Missing
from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.missing import bridged, missing_of

__all__ = ["CheckContext"]


class CheckContext:
    """The evidence of ``rec`` (module docstring), each piece computed on first use."""

    def __init__(self, rec: Recording) -> None:
        self.rec = rec
        self.gait_notes: list[str] = []

    @classmethod
    def of_recording(cls, rec: Recording) -> CheckContext:
        """The context of a recording as read: its missing samples found and bridged."""
        return cls(bridged(rec, missing_of(rec)))

    def own(self, name: str) -> SensorSignals:
        """Sensor ``name``'s signals with its missing samples NaN again (bridged in :attr:`rec`
        for the estimators): a check judges the samples the sensor has."""
        s = self.rec.sensors[name]
        gone = self.missing.mask(name, self.rec.n_samples)
        if not gone.any():
            return s
        return s.replace(**{k: np.where(gone[:, None], np.nan, v) for k in ("quat", "gyr", "acc",
                            "mag") if (v := getattr(s, k)) is not None})

    @property
    def missing(self) -> Missing:
        """The recording's missing samples (bridged in :attr:`rec`)."""
        return self.rec.missing

    def of(self, rec: Recording) -> CheckContext:
        """This context for ``rec`` itself, else a new one (the same missing samples)."""
        return self if rec is self.rec else CheckContext(rec)

    @cached_property
    def gait(self):
        """Each leg's events and strides (:class:`~pipeline.process.gait.Gait`); what was used
        and why not goes to :attr:`gait_notes`."""
        from pipeline.process.gait import gait_of

        return gait_of(self.rec, self.gait_notes)

    @cached_property
    def windows(self):
        """The still windows (:func:`~pipeline.process.still.still_windows`)."""
        from pipeline.process.still import still_windows

        return still_windows(self.rec)

    @cached_property
    def slips(self):
        """Side -> (sensor -> its :class:`~pipeline.process.slip.Slip`, the leg's stride count),
        the pelvis's on each leg's strides (:func:`~pipeline.process.slip.legs_slips`)."""
        from pipeline.process.slip import legs_slips

        return legs_slips(self)
