"""``pipeline live``'s own options, defined once (:mod:`pipeline.option`: a flag each); the others
are ``pipeline ik``'s (:mod:`pipeline.process.options`), but the recording's and the static
trial's, which the source replaces."""

from __future__ import annotations

from dataclasses import dataclass

from pipeline.errors import InputError
from pipeline.option import option, specs
from pipeline.process.options import all_specs

__all__ = ["VIEWERS", "LiveOptions", "live_specs"]

#: Where the capture is shown: a spawned rerun viewer, the web viewer, or nowhere (``auto``: a
#: spawned one where a display is, else nowhere, said).
VIEWERS = ("auto", "spawn", "web", "none")


@dataclass(frozen=True)
class LiveOptions:
    """The source of a live capture, how long, and where it is shown."""

    replay: str | None = option(None, "path", "a recording (any that pipeline ik reads) played as "
                                "if live (default: none; --lsl or this)", section="live",
                                metavar="RECORDING")
    lsl: bool = option(False, "bool", "read the Lab Streaming Layer streams of type IMU, one per "
                       "sensor, channels labelled as our IMU CSV's columns", section="live")
    speed: str = option("1", "text", "the replay's speed: a factor of real time, or max (as fast "
                        "as it is processed)", section="live", metavar="X")
    duration_s: float | None = option(None, "float", "stop after this many seconds of capture "
                                      "(default: at the replay's end, or Ctrl-C)", section="live",
                                      metavar="S")
    viewer: str = option("auto", "choice", "where the capture is shown as it comes: a spawned "
                         "rerun viewer, the web viewer, none, or auto (spawned where a display "
                         "is)", choices=VIEWERS, section="live")

    def __post_init__(self) -> None:
        if (self.replay is None) == (not self.lsl):
            raise InputError("give one source: --replay RECORDING or --lsl", field="replay")
        if self.speed != "max":
            try:
                ok = float(self.speed) > 0
            except ValueError:
                ok = False
            if not ok:
                raise InputError(f"expected a positive factor or max, got {self.speed!r}",
                                 field="speed")
        if self.duration_s is not None and not self.duration_s > 0:
            raise InputError(f"expected a positive duration, got {self.duration_s}",
                             field="duration_s")

    @property
    def speed_factor(self) -> float:
        return float("inf") if self.speed == "max" else float(self.speed)


def live_specs() -> list:
    """``pipeline live``'s options: its own and ``pipeline ik``'s but the recording's."""
    return specs(LiveOptions) + [s for s in all_specs()
                                 if s.name not in ("orientations", "static_trial")]
