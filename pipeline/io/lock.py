"""One run per output folder: a lock file in ``--out`` while a command writes there.

Two runs into one folder at once would interleave their files (one run's ``.osim`` beside the
other's ``.mot``), whatever each writes all or nothing (:mod:`pipeline.io.atomic`). A run takes
:data:`LOCK_NAME` in its output folder before it looks at what is there and holds it until its
outputs are committed or removed: created exclusively (``O_CREAT | O_EXCL``, atomic on a local
file system), it holds the run's process id, host, start time and recording. A second run finds it
and is refused with one line naming the first. A lock whose process no longer runs on this host (a
run killed without unwinding) is stale: it is taken over, and the run says so. The lock is removed
on any exit that unwinds (an error, Ctrl-C, SIGTERM).
"""

from __future__ import annotations

import contextlib
import json
import os
import socket
import time
from collections.abc import Iterator
from pathlib import Path

from pipeline.errors import InputError

__all__ = ["LOCK_NAME", "output_lock"]

#: The lock file's name in the output folder.
LOCK_NAME = ".pipeline.lock"


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process: it runs
        return True
    return True


def _holder(path: Path) -> dict | None:
    """The lock's content, or None where it is unreadable (being written: treated as held)."""
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def _stale(holder: dict | None) -> bool:
    return (holder is not None and holder.get("host") == socket.gethostname()
            and not _alive(int(holder.get("pid", -1))))


def _take(path: Path, what: str) -> None:
    fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    with os.fdopen(fd, "w") as f:
        json.dump({"pid": os.getpid(), "host": socket.gethostname(),
                   "started": time.strftime("%Y-%m-%d %H:%M:%S"), "what": what}, f)


@contextlib.contextmanager
def output_lock(out_dir: str | Path, what: str, notes: list[str] | None = None) -> Iterator[Path]:
    """Hold the lock of ``out_dir`` (module docstring) while the block runs; ``what`` names the
    run for a second one's message; a stale lock taken over is said in ``notes``. The folder is
    created if missing (and removed again, if left empty, when the block fails)."""
    out = Path(out_dir)
    created = not out.exists()
    out.mkdir(parents=True, exist_ok=True)
    path = out / LOCK_NAME
    try:
        _take(path, what)
    except FileExistsError:
        holder = _holder(path)
        if not _stale(holder):
            by = ("another run" if holder is None else
                  f"another run (pid {holder.get('pid')} on {holder.get('host')}, started "
                  f"{holder.get('started')}: {holder.get('what')})")
            raise InputError(f"{by} is writing into this folder: wait for it, or give another "
                             "--out", file=out, field="out") from None
        path.unlink(missing_ok=True)
        _take(path, what)
        if notes is not None:
            notes.append(f"{out}: a stale lock of a run that no longer runs (pid "
                         f"{holder.get('pid')}, started {holder.get('started')}) was taken over")
    ok = False
    try:
        yield path
        ok = True
    finally:
        path.unlink(missing_ok=True)
        if created and not ok:
            with contextlib.suppress(OSError):
                out.rmdir()  # only if empty
