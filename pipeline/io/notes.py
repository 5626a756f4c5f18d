"""What a reader changed or noticed: the :class:`Notes` list every reader returns.

Every repair a reader makes (gap interpolation, quaternion normalisation, ...) is written to a
:class:`Notes` list so that nothing is changed silently; the CLI prints the notes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pipeline.io.text import FileLike

__all__ = ["Notes"]


@dataclass
class Notes:
    """What a reader changed or noticed: a list of one-line, human-readable messages.

    Readers collect notes while checking and store them (as a tuple) on the object they return;
    the CLI prints them. ``Notes`` is a thin wrapper on a list so that checks can add to the same
    list through several calls.
    """

    items: list[str] = field(default_factory=list)

    def add(self, message: str, *, file: FileLike = None, field: str | None = None) -> None:
        """Append a message, prefixed like an :class:`InputError` (``file: field F: ...``)."""
        parts = [str(file)] if file else []
        if field:
            parts.append(f"field {field}")
        parts.append(message)
        self.items.append(": ".join(parts))

    def extend(self, other: Notes | list[str] | tuple[str, ...]) -> None:
        self.items.extend(other.items if isinstance(other, Notes) else other)

    def as_tuple(self) -> tuple[str, ...]:
        return tuple(self.items)

    def __iter__(self):
        return iter(self.items)

    def __len__(self) -> int:
        return len(self.items)
