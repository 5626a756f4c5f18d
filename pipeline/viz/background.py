"""A rerun recording written by a forked child, so that its imports and logging overlap the work.

A recording's imports (NumPy, pyarrow and rerun's native writer, :mod:`pipeline.viz.rrd`: ~0.15 s)
and its logging (~0.07 s for a 1,400-frame trial) are a large part of a short
``pipeline ik`` (the IK of a 1,400-frame trial takes ~0.1 s). :class:`BackgroundRecording` forks
the command early (the program before its parser, :func:`pipeline.cli.main`; else ``run_ik``
once it has read a short input): the child imports them on the machine's second core while the
parent reads, calibrates, solves and writes; the parent then hands it the job
(:meth:`~BackgroundRecording.submit`: a module-level function and its arguments, pickled through
a pipe) and waits for it (:meth:`~BackgroundRecording.wait`) before its outputs are committed.
The recording is the one the same function writes in the process itself: only where the work
runs differs.

Where ``os.fork`` is missing or unsafe (Windows; macOS, whose system libraries do not survive
``fork``; a process running other Python threads, such as a notebook kernel or a Dask worker, whose
locks the child could inherit held) :meth:`BackgroundRecording.start` returns None and the caller
logs in its own process.
The child never returns into the caller's code: it ends by ``os._exit``, on success, on error
(its message is sent back and raised in the parent as
:class:`~pipeline.errors.RecordingError`) and when the parent
goes away (the pipe's end of file). :meth:`~BackgroundRecording.close` kills and reaps a child
that is still running: call it before removing the files the child may be writing.
"""

from __future__ import annotations

import os
import pickle
import select
import signal
import sys
import threading
from collections.abc import Callable
from typing import Any

from pipeline.errors import RecordingError, Terminated

__all__ = ["WAIT_TIMEOUT_S", "BackgroundRecording"]

#: How long (s) the parent waits for the child's job once it needs it: the child logs at most
#: ``pipeline.commands.ik.BACKGROUND_FRAMES`` frames, ~1-2 s.
WAIT_TIMEOUT_S = 60.0


def _read_all(fd: int) -> bytes:
    chunks = []
    while True:
        b = os.read(fd, 1 << 20)
        if not b:
            return b"".join(chunks)
        chunks.append(b)


def _write_all(fd: int, data: bytes) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view) :]


class BackgroundRecording:
    """A forked child that imports the recording's modules now and runs one logging job later
    (module doc)."""

    def __init__(self, pid: int, job_fd: int, status_fd: int) -> None:
        self.pid, self._job_fd, self._status_fd = pid, job_fd, status_fd
        self._done = False
        self._feeder: threading.Thread | None = None

    @classmethod
    def start(cls, warm: Callable[[], Any] | None = None) -> BackgroundRecording | None:
        """Fork the child (None where fork is unavailable); it calls ``warm`` (e.g. the imports
        the job needs) while the parent goes on."""
        if not hasattr(os, "fork") or sys.platform == "darwin" or threading.active_count() > 1:
            return None
        job_r, job_w = os.pipe()
        status_r, status_w = os.pipe()
        try:
            pid = os.fork()
        except OSError:  # no process to spare (a limit reached): log in the caller's process
            for fd in (job_r, job_w, status_r, status_w):
                os.close(fd)
            return None
        if pid == 0:  # the child: never returns
            code = 1
            try:
                os.close(job_w)
                os.close(status_r)
                signal.signal(signal.SIGTERM, signal.SIG_DFL)
                signal.signal(signal.SIGINT, signal.SIG_DFL)
                if warm is not None:
                    warm()
                data = _read_all(job_r)
                if data:  # empty: the parent closed the pipe without a job (or went away)
                    fn, args, kwargs = pickle.loads(data)
                    fn(*args, **kwargs)
                    _write_all(status_w, b"ok")
                code = 0
            except BaseException as exc:  # noqa: BLE001 - reported to the parent
                try:
                    _write_all(status_w, f"{type(exc).__name__}: {exc}".encode())
                except BaseException:  # noqa: BLE001, S110 - nothing left to tell
                    pass
            finally:
                os._exit(code)
        os.close(job_r)
        os.close(status_w)
        return cls(pid, job_w, status_r)

    def submit(self, fn: Callable[..., Any], *args: Any, **kwargs: Any) -> None:
        """Hand the child its job: ``fn(*args, **kwargs)`` (``fn`` importable by name). The
        pickle is fed to the pipe by a thread: the child reads it only once warm, and a pipe
        holds 64 KiB, so writing it here would hold the caller up until then."""
        data = pickle.dumps((fn, args, kwargs), protocol=pickle.HIGHEST_PROTOCOL)
        fd, self._job_fd = self._job_fd, -1

        def feed() -> None:
            try:
                _write_all(fd, data)
            except OSError:  # the child is gone (killed): wait() or close() says so
                pass
            finally:
                os.close(fd)

        self._feeder = threading.Thread(target=feed, name="recording-job", daemon=True)
        self._feeder.start()

    def wait(self, timeout_s: float = WAIT_TIMEOUT_S) -> None:
        """Wait for the job; raise :class:`~pipeline.errors.RecordingError` with the child's
        error if it failed, or if it has not finished after ``timeout_s`` (the child is killed:
        a writer stuck on a full or hung disk never holds the command). A writer stopped by
        Ctrl-C or SIGTERM (sent to the whole process group, it may die before this process sees
        its own) is the command's interruption: ``KeyboardInterrupt`` or
        :class:`~pipeline.errors.Terminated` (exit 130 or 143), never a failed recording."""
        if self._job_fd >= 0:  # no job was submitted: let the child end
            os.close(self._job_fd)
            self._job_fd = -1
        ready, _, _ = select.select([self._status_fd], [], [], timeout_s)
        if not ready:
            self.close()
            raise RecordingError(f"the rerun recording did not finish within {timeout_s:g} s "
                                 "(its writer was stopped)")
        status = _read_all(self._status_fd)
        if self._feeder is not None:
            self._feeder.join()
        os.close(self._status_fd)
        self._status_fd = -1
        _, raw = os.waitpid(self.pid, 0)
        self._done = True
        code = os.waitstatus_to_exitcode(raw)
        if status != b"ok" and (status or code != 0):
            if code == -signal.SIGINT:  # Ctrl-C reached the whole group, the writer first
                raise KeyboardInterrupt
            if code == -signal.SIGTERM:
                raise Terminated
            why = (f"its writer was killed (signal {-code})" if code < 0
                   else f"its writer exited with code {code}")
            raise RecordingError(f"the rerun recording failed: {status.decode() or why}")

    def close(self) -> None:
        """Kill and reap the child if it is still running; close the pipes (idempotent)."""
        for name in ("_job_fd", "_status_fd"):
            fd = getattr(self, name)
            if fd >= 0:
                os.close(fd)
                setattr(self, name, -1)
        if not self._done:
            try:
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            os.waitpid(self.pid, 0)
            self._done = True
        if self._feeder is not None:
            self._feeder.join()  # the pipe broke with the child
            self._feeder = None
