"""One recording's evidence, computed once and shared by the sensor checks and the run: its gait
(each leg's events and strides, :func:`pipeline.process.gait.gait_of`), its still windows
(:mod:`pipeline.process.still`) and its legs' slip views (:mod:`pipeline.process.slip`).

A check that changes the recording (a sensor excluded, two read back) hands on the context of the
changed recording (:meth:`CheckContext.of`); an unchanged recording keeps its context, so that the
strides a check found are the ones the run uses.
"""

from __future__ import annotations

from functools import cached_property

from pipeline.io.recording import Recording

__all__ = ["CheckContext"]


class CheckContext:
    """The evidence of ``rec`` (module docstring), each piece computed on first use."""

    def __init__(self, rec: Recording) -> None:
        self.rec = rec
        self.gait_notes: list[str] = []

    def of(self, rec: Recording) -> CheckContext:
        """This context for ``rec`` itself, else a new one."""
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
