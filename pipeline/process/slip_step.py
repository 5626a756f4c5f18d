"""What a step of a sensor's own view of its segment says (:mod:`pipeline.process.slip`): a slip
(certain, or a flag), or a change of the movement that a slip would not be told from; its limits
and the finding's evidence.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ALONE_DEG", "CERTAIN_SLIP_DEG", "MAX_STRIDE_S", "ROCKING_AXIS", "SLIP_DEG", "Slip",
           "larger"]

#: A step beyond this (deg) is a slip: half as much again as the largest step measured without
#: one (9.8, :mod:`pipeline.process.slip`), under the 19-35 deg a 30 deg slip gives.
SLIP_DEG = 15.0
#: Beyond this step of its flexion axis (eq 1, deg) a leg sensor's slip is certain and the sensor
#: excluded (below, and for a step of gravity alone, a flag that keeps it): half as much again as
#: the largest axis step a leg sensor alone on its leg made on a faultless recording (S02 7.1,
#: cut to start mid-walk; qmt 10.0; the simulated walks, cut short, 11.5), under the 24-30 deg of
#: a 30 deg slip (S02, the simulated walk). Gravity at mid-stance steps with the movement itself
#: (qmt's 10-30 s windows: 17-40 deg as its walk turns to a run, the axis 1-3 deg), and a slip
#: about the flexion axis turns gravity alone: a flag. The pelvis's slip is never certain
#: (:mod:`pipeline.process.slip`).
CERTAIN_SLIP_DEG = 18.0
#: A step counts as a slip only while the leg's other sensors step less than this (deg) at the
#: same split: a change of the walk itself (stairs, a slope, a turn) turns them all.
ALONE_DEG = 0.5 * SLIP_DEG
#: A longer interval between initial contacts is a pause, not a stride (up to this, a missed
#: contact joins two strides into one bin).
MAX_STRIDE_S = 4.0
#: What the pelvis's axis (eq 3) is called in a finding.
ROCKING_AXIS = "the axis it rocks about once a stride"


@dataclass(frozen=True)
class Slip:
    """The largest step of one sensor's view of its segment: ``axis_deg`` (eq 1) and
    ``gravity_deg`` (eq 2, NaN without foot rests) at the split ``time_s`` (the first stride
    after it starts there), with ``before`` and ``after`` strides; ``others_deg``: the largest
    step of the leg's other sensors at that split (0 without any), ``others_min_deg`` their
    smallest; ``mirror_deg``: the step of the other leg's sensor on the same segment at its split
    nearest in time (NaN without)."""

    axis_deg: float
    gravity_deg: float
    time_s: float
    before: int
    after: int
    others_deg: float = 0.0
    mirror_deg: float = float("nan")
    others_min_deg: float = 0.0
    axis_name: str = "its segment's flexion axis"
    pause_s: float = 0.0

    @property
    def deg(self) -> float:
        return larger(self.axis_deg, self.gravity_deg)

    @property
    def slipped(self) -> bool:
        """Beyond :data:`SLIP_DEG`, alone on its leg or on its side of the body
        (:data:`ALONE_DEG`; :mod:`pipeline.process.slip`; on its side: with a strap's other
        sensor, while one of the leg's sensors stays: a whole leg stepping, and the other leg
        not, is a turn pivoting on it), and within a walk (the split not across
        a pause longer than :data:`MAX_STRIDE_S`: two walks apart, the subject may stand, walk or
        run differently, or have strapped the sensor again)."""
        together = self.mirror_deg < ALONE_DEG and self.others_min_deg < ALONE_DEG
        return (self.deg > SLIP_DEG and self.pause_s <= MAX_STRIDE_S
                and (self.others_deg < ALONE_DEG or together))

    @property
    def certain(self) -> bool:
        """A slip whose flexion axis (eq 1) turned beyond :data:`CERTAIN_SLIP_DEG`, of a leg
        sensor: gravity at mid-stance turns with the movement, and the pelvis's rocking axis as
        much where a walk starts, stops or turns (:mod:`pipeline.process.slip`)."""
        return (self.slipped and self.axis_name != ROCKING_AXIS
                and self.axis_deg > CERTAIN_SLIP_DEG)

    @property
    def inconclusive(self) -> bool:
        """Beyond :data:`SLIP_DEG` with the leg's other sensors and the other leg's stepping as
        well: the movement changed (turns, shuffles), and a slip there would not be told apart."""
        return self.deg > SLIP_DEG and not self.slipped

    def evidence(self) -> str:
        """What turned, where, for a finding: a slip, or a step that cannot be told from a change
        of the movement (:attr:`inconclusive`)."""
        turned = " and ".join(
            f"{what} by {deg:.0f} deg" for what, deg in
            ((f"{self.axis_name} turned", self.axis_deg),
             ("gravity at mid-stance turned", self.gravity_deg)) if np.isfinite(deg))
        mirror = (f", the other leg's by {self.mirror_deg:.0f}" if np.isfinite(self.mirror_deg)
                  else "")
        seen = (f"in its own frame {turned} between the {self.before} strides before t = "
                f"{self.time_s:.1f} s and the {self.after} after (limit {SLIP_DEG:g}), the leg's "
                f"other sensors by {self.others_deg:.0f} at most{mirror}")
        if self.inconclusive and self.pause_s > MAX_STRIDE_S:
            return ("not checked for a slip: " + seen + f", across a pause of "
                    f"{self.pause_s:.0f} s: two walks, which a subject may walk or run "
                    "differently")
        if self.inconclusive:
            return ("not checked for a slip: " + seen + ": the movement itself changed (turns, "
                    "shuffles?), and a slip would not be told from it")
        if self.certain:
            return seen + ": it slipped on its segment (a loose strap?)"
        return seen + (f": it may have slipped on its segment (a loose strap?; certain beyond "
                       f"{CERTAIN_SLIP_DEG:g} deg of a leg sensor's axis, never for the "
                       "pelvis's, which a walk's start, stop or turn turns as much)")



def larger(*steps: float) -> float:
    """The larger of a sensor's steps (eq 1, 2) that were seen; NaN when neither was."""
    return max((d for d in steps if np.isfinite(d)), default=float("nan"))
