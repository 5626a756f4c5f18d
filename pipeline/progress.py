"""A progress line on stderr for the steps that can take more than a few seconds.

A command opens one with :func:`shown` (``pipeline ik``: its steps; ``pipeline simulate``: the
frames solved); the domain code says where it is with :func:`step`, which does
nothing when no line is open (the Python API, the tests, a batch's workers). The line appears
only on a terminal and only once the work has taken :data:`DELAY_S`, so short runs and logs stay
as they were; it is cleared when the command ends.
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Iterator
from contextvars import ContextVar
from dataclasses import dataclass, field

__all__ = ["DELAY_S", "shown", "step"]

#: Seconds of work before the line appears.
DELAY_S = 2.0


@dataclass
class _Line:
    what: str
    start: float = field(default_factory=time.monotonic)
    drawn: bool = False

    def draw(self, name: str) -> None:
        elapsed = time.monotonic() - self.start
        if elapsed < DELAY_S or not sys.stderr.isatty():
            return
        sys.stderr.write(f"\r\033[K{self.what}: {name} ({elapsed:.0f} s)")
        sys.stderr.flush()
        self.drawn = True

    def clear(self) -> None:
        if self.drawn:
            sys.stderr.write("\r\033[K")
            sys.stderr.flush()


_LINE: ContextVar[_Line | None] = ContextVar("progress_line", default=None)


@contextlib.contextmanager
def shown(what: str) -> Iterator[None]:
    """A progress line for ``what`` while the block runs (module docstring), cleared at its end."""
    line = _Line(what)
    token = _LINE.set(line)
    try:
        yield
    finally:
        _LINE.reset(token)
        line.clear()


def step(name: str) -> None:
    """The open line now shows ``name`` (the step being worked on) and the time so far."""
    line = _LINE.get()
    if line is not None:
        line.draw(name)
