"""User-facing errors.

Every problem with a user's input is raised as :class:`InputError`, which carries the file, the
field and what was expected, and renders as one line. The CLI prints that line (no traceback unless
``--debug``) and exits with a non-zero code.
"""

from __future__ import annotations

from pathlib import Path

__all__ = ["InputError", "QualityError", "RecordingError", "Terminated"]


class InputError(ValueError):
    """Bad user input: names the file, the field and what was expected.

    >>> str(InputError("expected a 3-column array, got shape (10, 2)", file="a.mat", field="REFM"))
    'a.mat: field REFM: expected a 3-column array, got shape (10, 2)'
    """

    def __init__(
        self, message: str, *, file: str | Path | None = None, field: str | None = None
    ) -> None:
        self.file = None if file is None else str(file)
        self.field = field
        self.message = message
        parts = []
        if self.file:
            parts.append(self.file)
        if field:
            parts.append(f"field {field}")
        parts.append(message)
        super().__init__(": ".join(parts))


class QualityError(InputError):
    """A run whose results are implausible (``--strict``): the CLI exits with code 3 and writes
    no outputs. ``flags`` lists what was implausible, each with its likely cause."""

    def __init__(self, flags: list[str], *, file: str | Path | None = None) -> None:
        self.flags = list(flags)
        super().__init__("implausible results (--strict): " + " | ".join(self.flags), file=file)


class Terminated(BaseException):
    """SIGTERM received: unwinds like Ctrl-C (a ``BaseException``, so that no ``except
    Exception`` takes it for a failure) and partial outputs are removed; the CLI exits 143."""


class RecordingError(RuntimeError):
    """The rerun recording could not be written (its writer failed, died or did not finish in
    time): the command ends with this one line and exit code 2, and writes nothing."""
