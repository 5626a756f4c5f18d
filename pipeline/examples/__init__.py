"""Example recordings installed with the package (``README.md`` here: what, source, licence).

``path(name)`` gives one's location; every command that reads a recording also takes
``example:<name>`` (:func:`pipeline.io.formats.read_recording`), so the README's examples run from
a clone or a wheel without other data.
"""

from __future__ import annotations

from pathlib import Path

from pipeline.errors import InputError

__all__ = ["EXAMPLES", "PREFIX", "path", "resolve"]

_HERE = Path(__file__).resolve().parent
#: Example name -> its file or folder here.
EXAMPLES = {"opensense_imu_ik_test": "opensense_imu_ik_test.sto",
            "ximu3_lower_body": "ximu3_lower_body",
            "batch_manifest.csv": "batch_manifest.csv"}
#: How a command's path names an example.
PREFIX = "example:"


def path(name: str) -> Path:
    """The installed example ``name`` (:data:`EXAMPLES`)."""
    if name not in EXAMPLES:
        raise InputError(f"no example {name!r}; expected one of {sorted(EXAMPLES)}",
                         field="example")
    return _HERE / EXAMPLES[name]


def resolve(given: str | Path) -> Path:
    """``example:<name>`` as the example's path; any other path unchanged."""
    text = str(given)
    return path(text[len(PREFIX):]) if text.startswith(PREFIX) else Path(given)
