"""pipeline.process.findings: one enumeration of actions, applied to the recording in one place."""

import numpy as np

from pipeline.io.recording import Recording, SensorSignals
from pipeline.process.findings import Action, Finding, apply_findings


def test_actions_are_applied_in_one_place_and_only_some_are_flags():
    s = SensorSignals(gyr=np.zeros((3, 3)), mag=np.ones((3, 3)))
    rec = Recording(np.arange(3.0), 100.0, {"a": s, "b": s, "c": s})
    found = [Finding("a", "dead", Action.EXCLUDED, "x"),
             Finding("b", "dead", Action.MAGNETOMETER_NOT_USED, "y"),
             Finding("c", "read", Action.LISTED, "z")]
    out = apply_findings(rec, found)
    assert set(out.sensors) == {"b", "c"} and out.sensors["b"].mag is None
    assert out.sensors["c"] is s
    assert [f.flagged for f in found] == [True, True, False]
    assert found[0].line() == "sensor a: dead: x (excluded)"
    assert apply_findings(rec, found[2:]) is rec  # nothing to change: the same recording
    assert {a.value for a in Action} == {"excluded", "magnetometer not used",
                                         "read as swapped back", "noted", "listed",
                                         "orientation from its raw signals"}
    q = SensorSignals(quat=np.tile([1.0, 0, 0, 0], (3, 1)), gyr=np.zeros((3, 3)))
    rec = Recording(np.arange(3.0), 100.0, {"a": q})
    out = apply_findings(rec, [Finding("a", "orientations", Action.ORIENTATION_FROM_SIGNALS, "")])
    assert out.sensors["a"].quat is None and out.sensors["a"].gyr is q.gyr
