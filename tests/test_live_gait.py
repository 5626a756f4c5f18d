"""pipeline.live.gait: strides said as each completes, the same as the offline run's on the whole
capture; in the viewer with the landmarks."""

import numpy as np

from pipeline.io.formats import read_recording
from pipeline.live.capture import LiveCapture
from pipeline.live.gait import SETTLE_S, LiveGait
from pipeline.live.sources import ReplaySource
from pipeline.model.measures import Measures
from pipeline.process.gait import gait_of
from pipeline.process.options import IKOptions


def _replayed(viewer=None):
    rec = read_recording("example:ximu3_lower_body")
    source = ReplaySource(rec, np.inf)
    source.header = dict(rec.header)
    return LiveCapture(source, Measures("m", 1.8), IKOptions(), in_line=True, viewer=viewer,
                       say=lambda line: None).run()


def test_each_stride_is_said_once_as_offline_finds_it():
    """The shipped walk replayed: every stride the offline run finds on the whole capture that
    ended a settling time before the capture did is said live, once, its contacts within 15 ms
    (measured: 12 ms at most, the window's events placed on fewer samples); one more is said
    live (a contact the window's own thresholds find after a pause, the whole walk's not)."""
    result = _replayed()
    offline = gait_of(result.recording, []).strides
    end = result.recording.time[-1]
    expected = [s for s in offline if s.end_s <= end - SETTLE_S]

    def match(a, strides):
        return [b for b in strides if a.side == b.side and abs(a.start_s - b.start_s) < 0.015
                and abs(a.end_s - b.end_s) < 0.015]

    assert len(expected) >= 10
    assert all(len(match(b, result.strides)) == 1 for b in expected)
    assert sum(not match(a, expected) for a in result.strides) <= 1


def test_a_stride_not_yet_settled_waits_for_the_next_look():
    rec = read_recording("example:ximu3_lower_body")
    gait = LiveGait()
    first = gait.update(rec)  # the whole walk at once: all but its last strides
    assert first and max(s.end_s for s in first) <= rec.time[-1] - SETTLE_S
    assert gait.update(rec) == []  # nothing new: none said twice
    assert gait.due == rec.time[-1] + 2.0


def test_the_viewer_shows_the_landmarks_and_the_strides(tmp_path):
    from pipeline.live.viewer import LiveViewer
    from pipeline.viz.recording import read_entities

    viewer = LiveViewer("walk", "save", path=tmp_path / "live.rrd")
    _replayed(viewer)
    viewer.close()
    entities = read_entities(tmp_path / "live.rrd")
    assert {"/world/landmarks/right_MM", "/gait/right", "/gait/left",
            "/gait/right/stride_time_s", "/world/model/right_tibia/mesh"} <= set(entities)
