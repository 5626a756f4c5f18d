"""pipeline.live.aligner: streams on their own clocks, in chunks, put on one grid; a stalled
stream shown missing, not held, and back with its next sample; dropped samples missing."""

import numpy as np

from pipeline.live.aligner import STALL_S, Aligner


def _signal(t):
    return {"gyr": np.stack([np.sin(t), np.cos(t), t], axis=1)}


class _Clock:
    """The reader's clock: the replayed time (the samples arrive as they are stamped)."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def _feed(aligner, streams, chunk_s=0.03):
    """Push the streams' samples as they would arrive: every stream's samples of each
    ``chunk_s`` of time together (the aligner's clock at their time); every block pulled."""
    blocks = []
    start = min(t[0] for t in streams.values())
    end = max(t[-1] for t in streams.values())
    for a in np.arange(start, end + chunk_s, chunk_s):
        aligner.clock.now = a + chunk_s
        for name, t in streams.items():
            part = t[(t >= a) & (t < a + chunk_s)]
            if len(part):
                aligner.push(name, part, _signal(part))
        if (b := aligner.pull()) is not None:
            blocks.append(b)
    return blocks


def _cat(blocks, name):
    return np.concatenate([b.time for b in blocks]), np.concatenate(
        [b.sensors[name].gyr for b in blocks])


def test_streams_a_few_ms_apart_are_resampled_onto_the_last_starters_grid():
    t = np.arange(500) / 100.0
    a = Aligner(["femur", "tibia"], 100.0, clock=_Clock())
    blocks = _feed(a, {"femur": t + 100.0, "tibia": t + 100.004})
    assert a.t0 == 100.004
    time, femur = _cat(blocks, "femur")
    _, tibia = _cat(blocks, "tibia")
    np.testing.assert_allclose(np.diff(time), 0.01)
    np.testing.assert_allclose(tibia[:, 0], np.sin(time + 100.004), atol=1e-12)
    np.testing.assert_allclose(femur[:, 0], np.sin(time + 100.004), atol=2e-4)  # resampled


def test_a_stalled_stream_is_missing_meanwhile_and_back_after():
    t = np.arange(600) / 100.0
    holed = np.r_[t[:200], t[350:]]  # the tibia's stream stops for 1.5 s
    a = Aligner(["femur", "tibia"], 100.0, clock=_Clock())
    blocks = _feed(a, {"femur": t, "tibia": holed})
    time, tibia = _cat(blocks, "tibia")
    gone = np.isnan(tibia[:, 0])
    assert gone[(time > 2.0 + 0.02) & (time < 3.5 - 0.02)].all()  # missing, not frozen
    assert not gone[time < 1.98].any() and not gone[time > 3.52].any()  # back with the samples
    _, femur = _cat(blocks, "femur")
    assert np.isfinite(femur).all() and time[-1] > 5.9  # the other stream never held up


def test_dropped_samples_beyond_a_short_gap_are_missing_and_repeats_dropped():
    t = np.arange(300) / 100.0
    a = Aligner(["s"], 100.0, stall_s=STALL_S)
    a.push("s", t[:100], _signal(t[:100]))
    a.push("s", t[95:100], _signal(t[95:100]))  # repeated stamps: dropped
    a.push("s", t[105:120], _signal(t[105:120]))  # 5 samples (0.05 s) missing: interpolated
    a.push("s", t[140:300], _signal(t[140:300]))  # 20 missing (0.2 s): missing
    b = a.pull()
    gyr = b.sensors["s"].gyr[:, 0]
    assert np.isfinite(gyr[:120]).all()
    np.testing.assert_allclose(gyr[100:105], np.sin(t[100:105]), atol=1e-3)
    assert np.isnan(gyr[120:140]).all() and np.isfinite(gyr[140:]).all()


def test_a_stream_delivering_a_backlog_is_waited_for_not_cut():
    """A reader catching up: the tibia's first 2 s arrive in two bursts, the second after the
    femur's (the same moment by the clock): nothing missing, the frames wait for it."""
    t = np.arange(200) / 100.0
    clock = _Clock()
    a = Aligner(["femur", "tibia"], 100.0, clock=clock)
    a.push("femur", t, _signal(t))
    a.push("tibia", t[:30], _signal(t[:30]))
    first = a.pull()
    a.push("tibia", t[30:], _signal(t[30:]))
    second = a.pull()
    time, tibia = _cat([first, second], "tibia")
    assert np.isfinite(tibia).all() and time[-1] == t[-1]
    clock.now = 1.0  # the tibia silent for a second while the femur goes on: stalled
    a.push("femur", t + 2.0, _signal(t + 2.0))
    third = a.pull()
    assert third is not None and np.isnan(third.sensors["tibia"].gyr).all()
