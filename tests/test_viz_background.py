"""pipeline.viz.background: a job run by a forked child, its errors raised in the parent, a
child still running killed and reaped, and nothing forked where it is unsafe."""

from __future__ import annotations

import os
import sys
import threading
import time
from pathlib import Path

import pytest

from pipeline.viz.background import BackgroundRecording

pytestmark = pytest.mark.skipif(not hasattr(os, "fork") or sys.platform == "darwin",
                                reason="forks only where fork is safe")


@pytest.fixture(autouse=True)
def _single_threaded(monkeypatch, request):
    """The test suite runs threads of its own (Dask's, earlier tests'), which start() refuses to
    fork beside; these jobs take no lock, so the tests pretend to be alone, except the one that
    checks the refusal."""
    if request.node.name != "test_nothing_is_forked_while_other_threads_run":
        monkeypatch.setattr(threading, "active_count", lambda: 1)


def _write(path: str, text: str) -> None:
    Path(path).write_text(f"{text} from {os.getpid()}")


def _fail(message: str) -> None:
    raise ValueError(message)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return True


def test_the_job_runs_in_the_child(tmp_path):
    warmed = tmp_path / "warm"
    worker = BackgroundRecording.start(warm=lambda: warmed.write_text("x"))
    assert worker is not None and worker.pid != os.getpid()
    worker.submit(_write, str(tmp_path / "out.txt"), "written")
    worker.wait()
    assert (tmp_path / "out.txt").read_text() == f"written from {worker.pid}"
    assert warmed.read_text() == "x"
    worker.close()  # after wait: nothing left to do
    assert not _alive(worker.pid)


def test_the_childs_error_is_raised_in_the_parent(tmp_path):
    worker = BackgroundRecording.start()
    worker.submit(_fail, "no such entity")
    with pytest.raises(RuntimeError, match="ValueError: no such entity"):
        worker.wait()
    assert not _alive(worker.pid)


def test_without_a_job_the_child_just_ends():
    worker = BackgroundRecording.start()
    worker.wait()
    assert not _alive(worker.pid)


def test_close_kills_and_reaps_a_running_child(tmp_path):
    worker = BackgroundRecording.start(warm=lambda: time.sleep(60))
    t0 = time.monotonic()
    worker.close()
    assert time.monotonic() - t0 < 10
    assert not _alive(worker.pid)  # reaped: no zombie either
    worker.close()  # idempotent


def test_nothing_is_forked_while_other_threads_run():
    stop = threading.Event()
    t = threading.Thread(target=stop.wait)
    t.start()
    try:
        assert BackgroundRecording.start() is None
    finally:
        stop.set()
        t.join()


def test_a_fork_that_fails_falls_back_to_the_callers_process(monkeypatch):
    def no_fork():
        raise BlockingIOError(11, "Resource temporarily unavailable")

    monkeypatch.setattr(os, "fork", no_fork)
    before = len(os.listdir("/proc/self/fd"))
    assert BackgroundRecording.start() is None
    assert len(os.listdir("/proc/self/fd")) == before  # its pipes closed


def _sleep(seconds: float) -> None:
    time.sleep(seconds)


def test_a_child_that_hangs_or_dies_ends_the_wait_in_one_line():
    """A writer stuck (e.g. on a hung disk) is stopped after the timeout; a writer killed (the
    OOM killer, a full tmpfs's SIGBUS) is reported at once: a RecordingError, never a hang."""
    from pipeline.errors import RecordingError

    for _ in range(3):  # repeated: no race between the child's end and the wait
        worker = BackgroundRecording.start()
        worker.submit(_sleep, 60)
        t0 = time.monotonic()
        with pytest.raises(RecordingError, match="did not finish within 1 s"):
            worker.wait(timeout_s=1.0)
        assert time.monotonic() - t0 < 5 and not _alive(worker.pid)
        worker = BackgroundRecording.start()
        worker.submit(_sleep, 60)
        time.sleep(0.2)
        os.kill(worker.pid, 9)
        t0 = time.monotonic()
        with pytest.raises(RecordingError, match=r"its writer was killed \(signal 9"):
            worker.wait()
        assert time.monotonic() - t0 < 5


def test_a_writer_stopped_by_ctrl_c_or_sigterm_is_the_commands_interruption():
    """Ctrl-C and SIGTERM reach the whole process group, the writer sometimes first: its death
    by them is the command's interruption (exit 130 or 143), not a failed recording (exit 2 in
    5 of 30 tries before)."""
    import signal

    from pipeline.errors import Terminated

    for sig, raised in ((signal.SIGINT, KeyboardInterrupt), (signal.SIGTERM, Terminated)):
        worker = BackgroundRecording.start()
        worker.submit(_sleep, 60)
        time.sleep(0.2)
        os.kill(worker.pid, sig)
        with pytest.raises(raised):
            worker.wait()
        assert not _alive(worker.pid)
