"""pipeline.live.path: the pelvis carried by the stance foot during a live capture, its settled
path continued look by look, on at its last velocity between looks; S02 replayed against the
offline path."""

from pathlib import Path

import numpy as np
import pytest

from pipeline.live.path import LivePath

S02 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "gaittoolbox_s02"


def test_between_looks_the_pelvis_goes_on_at_its_last_velocity():
    path = LivePath()
    assert path.at(1.0) is None  # no path yet: the body stays at the pelvis
    t = np.arange(0, 3.0, 0.01)
    path._known = (t, np.column_stack([1.2 * t, 0.9 + 0.02 * np.sin(t), 0 * t]))
    np.testing.assert_allclose(path.at(1.5), [1.8, 0.9 + 0.02 * np.sin(1.5), 0.0])
    ahead = path.at(3.99 + 0.5)  # 0.5 s after the settled end: on at 1.2 m/s, at its height
    np.testing.assert_allclose(ahead[[0, 2]], [1.2 * 2.99 + 1.2 * 1.5, 0.0], atol=1e-9)
    assert ahead[1] == pytest.approx(path.position[-1, 1])


@pytest.mark.dataset
def test_s02_replayed_walks_the_room_as_offline(tmp_path):
    """S02 replayed: the live path spans the walk; against the offline path (the whole capture's,
    start aligned) it is off by 0.45 m at most over 7.2 m walked (measured: the walk's first
    strides integrated with the calibrations before the final one, whose headings it keeps)."""
    if not S02.exists():
        pytest.skip("../shared/data/gaittoolbox_s02 not present")
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_gait import S02_MAP

    from pipeline.io.formats import read_recording
    from pipeline.live.capture import LiveCapture
    from pipeline.live.sources import ReplaySource
    from pipeline.live.viewer import LiveViewer
    from pipeline.model.measures import Measures
    from pipeline.process import process_recording
    from pipeline.process.options import IKOptions
    from pipeline.viz.recording import read_entities

    rec = read_recording(S02 / "imu", S02_MAP)
    source = ReplaySource(rec, np.inf)
    source.header = dict(rec.header)
    viewer = LiveViewer("s02", "save", path=tmp_path / "live.rrd")
    capture = LiveCapture(source, Measures("m", 1.72), IKOptions(), in_line=True, viewer=viewer,
                          say=lambda line: None)
    result = capture.run()
    viewer.close()
    live = capture.path
    offline = process_recording(result.recording, Measures("m", 1.72)).gait.pelvis_path
    k = np.searchsorted(result.recording.time, live.time)
    off = offline[k] - offline[k[0]] + live.position[0]
    walked = np.sum(np.linalg.norm(np.diff(off[:, [0, 2]], axis=0), axis=1))
    apart = np.linalg.norm((live.position - off)[:, [0, 2]], axis=1)
    assert walked > 7.0 and apart.max() < 0.08 * walked
    assert "/world/walk/path" in read_entities(tmp_path / "live.rrd")
