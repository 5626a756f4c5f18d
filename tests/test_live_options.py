"""pipeline.live.options: pipeline live's own options, checked, and pipeline ik's that apply."""

import pytest

from pipeline.errors import InputError
from pipeline.live.options import LiveOptions, live_specs


def test_one_source_a_speed_and_a_duration():
    assert LiveOptions(replay="a.sto", speed="max").speed_factor == float("inf")
    assert LiveOptions(lsl=True, speed="2.5").speed_factor == 2.5
    for bad, match in (({}, "give one source"), ({"replay": "a", "lsl": True}, "give one source"),
                       ({"lsl": True, "speed": "fast"}, "positive factor or max"),
                       ({"lsl": True, "speed": "0"}, "positive factor or max"),
                       ({"lsl": True, "duration_s": -1.0}, "positive duration")):
        with pytest.raises(InputError, match=match):
            LiveOptions(**bad)


def test_pipeline_iks_options_apply_but_the_recordings():
    names = [s.name for s in live_specs()]
    assert {"replay", "lsl", "speed", "duration_s", "viewer", "sex", "height_m", "knee", "filter",
            "sensor_map", "out"} <= set(names)
    assert "orientations" not in names and "static_trial" not in names
    assert len(names) == len(set(names))  # each defined once
