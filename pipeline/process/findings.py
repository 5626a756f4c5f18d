"""What a sensor check found and what is done about it: one :class:`Finding` per fault, its
:class:`Action` from one enumeration, applied to the recording in one place
(:func:`apply_findings`).

An exclusion must be certain: a check excludes a sensor only where its statistic lies beyond a
margin above what every faultless recording here shows; between the two it flags the sensor and
keeps it (``results/bench_faults.txt`` lists each check's statistic against its limits on every
faultless recording).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from pipeline.io.recording import Recording

__all__ = ["Action", "Finding", "apply_findings"]


class Action(str, Enum):
    """What is done about a finding (its value is what the summary prints)."""

    #: The sensor is left out: its joints are not written.
    EXCLUDED = "excluded"
    #: The sensor's magnetometer is left out (filtered 6-D, its heading from the joints).
    MAGNETOMETER_NOT_USED = "magnetometer not used"
    #: Sensors named for each other's places are read under their right names.
    SWAPPED_BACK = "read as swapped back"
    #: The sensor's own orientations are left out: its orientation comes from its raw signals.
    ORIENTATION_FROM_SIGNALS = "orientation from its raw signals"
    #: A fault the run works around or cannot be sure of; the sensor is kept (a flag).
    NOTED = "noted"
    #: Said in the sensor table only (the reader's repairs, a check that could not run): not a
    #: flag.
    LISTED = "listed"

    def __str__(self) -> str:
        return self.value


@dataclass(frozen=True)
class Finding:
    """One fault of one sensor: ``check`` (a check's registered name), ``action`` and the
    ``evidence`` a summary prints. Every action but :attr:`Action.LISTED` is also a flag
    (:attr:`flagged`)."""

    sensor: str
    check: str
    action: Action
    evidence: str

    @property
    def flagged(self) -> bool:
        return self.action != Action.LISTED

    def line(self) -> str:
        return f"sensor {self.sensor}: {self.check}: {self.evidence} ({self.action})"


def apply_findings(rec: Recording, findings: list[Finding]) -> Recording:
    """The recording without its excluded sensors, the magnetometers not used and the
    orientations rejected removed (the other actions change no signal: a swap is read back by
    its own check)."""
    sensors, changed = dict(rec.sensors), False
    for f in findings:
        if f.action == Action.EXCLUDED and f.sensor in sensors:
            sensors.pop(f.sensor)
            changed = True
        elif f.action == Action.MAGNETOMETER_NOT_USED and f.sensor in sensors:
            sensors[f.sensor] = sensors[f.sensor].replace(mag=None)
            changed = True
        elif f.action == Action.ORIENTATION_FROM_SIGNALS and f.sensor in sensors:
            sensors[f.sensor] = sensors[f.sensor].replace(quat=None)
            changed = True
    return rec.with_sensors(sensors) if changed else rec
