"""Atomic output: a file appears complete or not at all, and a set of files all or none.

A single file is written to a temporary file in the destination's directory (same file system),
flushed and fsync'ed, then renamed over the destination with :func:`os.replace` (atomic on POSIX
and Windows). :class:`OutputSet` does the same for several files: each is written to its own
temporary file and nothing is renamed until every one has been written; if anything fails, the
temporaries are deleted and the destinations are as they were (files that already existed are
restored from a backup taken during the commit).
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from pipeline.errors import InputError

__all__ = [
    "committed_outputs",
    "OutputSet",
    "atomic_write",
    "output_dir",
    "output_set",
    "write_bytes_atomic",
    "write_text_atomic",
]


def output_dir(path: str | Path, *, create: bool = True) -> Path:
    """Check (and, with ``create``, create) an output directory, refusing with an
    :class:`InputError` naming the path: an existing file, a parent that is a file, or a folder
    that cannot be written. Without ``create`` a missing folder is checked by its nearest
    existing parent, and :class:`OutputSet` creates it with the first file (and removes it again
    if the set is aborted)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise InputError("expected an output directory, found a file", file=path, field="out")
    existing = path
    for parent in path.parents:
        if parent.exists():
            if not parent.is_dir():
                raise InputError(f"{parent} is a file, not a folder", file=path, field="out")
            existing = parent if not path.exists() else path
            break
    if create:
        try:
            path.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise InputError(f"cannot create the output directory: {exc.strerror}", file=path,
                             field="out") from exc
        existing = path
    if not os.access(existing, os.W_OK | os.X_OK):
        what = "the output directory" if existing == path else f"its parent {existing}"
        raise InputError(f"{what} is not writable", file=path, field="out")
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_FILE_MODE = 0o666 & ~_umask()


def _temp_path(dest: Path) -> Path:
    """Empty temporary file beside ``dest`` with the permissions a plain ``open`` would give."""
    fd, name = tempfile.mkstemp(prefix=f".{dest.name}.", suffix=".tmp", dir=dest.parent)
    os.close(fd)
    os.chmod(name, _FILE_MODE)
    return Path(name)


def _fsync(path: Path) -> None:
    with contextlib.suppress(OSError), open(path, "rb") as f:
        os.fsync(f.fileno())


def _remove(path: Path) -> None:
    with contextlib.suppress(FileNotFoundError):
        path.unlink()


@contextlib.contextmanager
def atomic_write(
    path: str | Path, mode: str = "w", *, encoding: str | None = "utf-8", newline: str | None = None
) -> Iterator[IO[Any]]:
    """Open a temporary file next to ``path``; on success rename it to ``path``.

    >>> with atomic_write("out.csv") as f:   # doctest: +SKIP
    ...     f.write("time\\n")

    If the block raises, the temporary file is removed and ``path`` is untouched.
    """
    dest = Path(path)
    if "w" not in mode:
        raise ValueError(f"atomic_write needs a write mode, got {mode!r}")
    if "b" in mode:
        encoding, newline = None, None
    tmp = _temp_path(dest)
    try:
        with open(tmp, mode, encoding=encoding, newline=newline) as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, dest)
    except BaseException:
        _remove(tmp)
        raise


def write_text_atomic(path: str | Path, text: str, *, encoding: str = "utf-8") -> Path:
    """Write ``text`` to ``path`` atomically; returns the path."""
    with atomic_write(path, "w", encoding=encoding, newline="") as f:
        f.write(text)
    return Path(path)


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically; returns the path."""
    with atomic_write(path, "wb") as f:
        f.write(data)
    return Path(path)


#: Every destination an :class:`OutputSet` committed in this process (what a signal that
#: arrives afterwards, while the command ends, leaves complete).
_COMMITTED: list[Path] = []


def committed_outputs() -> tuple[Path, ...]:
    """The files output sets have committed in this process, in order."""
    return tuple(_COMMITTED)


class OutputSet:
    """Several output files committed together (use through :func:`output_set`).

    ``path(dest)`` returns a temporary path to hand to code that writes a file itself (a URDF
    writer, ``rerun.save``); ``open(dest)`` opens one for writing. Nothing appears at any
    destination until :meth:`commit`; :meth:`abort` deletes everything written.
    """

    def __init__(self) -> None:
        self._pending: dict[Path, Path] = {}  # destination -> temporary
        self._created: list[Path] = []  # folders this set created (removed again on abort)
        self._done = False

    def path(self, dest: str | Path) -> Path:
        """Temporary file (same directory as ``dest``) to write ``dest``'s content to. A
        destination that is a symbolic link is replaced by the file (the link is not followed)."""
        if self._done:
            raise RuntimeError("output set already committed or aborted")
        d = Path(os.path.abspath(dest))
        if d in self._pending:
            raise ValueError(f"{d} is already part of this output set")
        missing = [p for p in (d.parent, *d.parent.parents) if not p.exists()]
        d.parent.mkdir(parents=True, exist_ok=True)
        self._created += reversed(missing)
        tmp = _temp_path(d)
        self._pending[d] = tmp
        return tmp

    def open(self, dest: str | Path, mode: str = "w", **kwargs: Any) -> IO[Any]:
        """``open()`` the temporary file of ``dest`` (the caller closes it)."""
        if "b" not in mode:
            kwargs.setdefault("encoding", "utf-8")
        return open(self.path(dest), mode, **kwargs)

    @property
    def destinations(self) -> tuple[Path, ...]:
        return tuple(self._pending)

    def commit(self) -> tuple[Path, ...]:
        """Rename every temporary onto its destination; all or none.

        Existing destinations are first moved to backups; if a rename fails, the renamed files are
        removed, the backups restored and the error re-raised.
        """
        self._done = True
        for tmp in self._pending.values():
            if not tmp.exists():
                self.abort()
                raise FileNotFoundError(f"output {tmp} was never written")
            _fsync(tmp)
        committed: list[tuple[Path, Path | None]] = []
        try:
            for dest, tmp in self._pending.items():
                backup = None
                if dest.exists():
                    backup = _temp_path(dest)
                    os.replace(dest, backup)
                committed.append((dest, backup))
                os.replace(tmp, dest)
        except BaseException:
            for dest, backup in reversed(committed):
                _remove(dest)
                if backup is not None:
                    os.replace(backup, dest)
            for tmp in self._pending.values():
                _remove(tmp)
            raise
        for _, backup in committed:
            if backup is not None:
                _remove(backup)
        _COMMITTED.extend(self._pending)
        return tuple(self._pending)

    def abort(self) -> None:
        """Delete every temporary file and the folders the set created; destinations stay as
        they were."""
        self._done = True
        for tmp in self._pending.values():
            _remove(tmp)
        for folder in reversed(self._created):
            with contextlib.suppress(OSError):
                folder.rmdir()  # only if empty


@contextlib.contextmanager
def output_set() -> Iterator[OutputSet]:
    """Write several files; they all appear when the block ends normally, none if it raises.

    >>> with output_set() as out:   # doctest: +SKIP
    ...     with out.open("results/a.csv") as f:
    ...         f.write("...")
    ...     write_urdf(out.path("results/model.urdf"))
    """
    outs = OutputSet()
    try:
        yield outs
    except BaseException:
        outs.abort()
        raise
    outs.commit()
