"""A Griffe extension for the API reference: the docstrings' Sphinx roles (``:func:`x```,
``:class:`~a.b.C```, ``:mod:``, ``:data:``, ``:meth:``, ``:attr:``, ``:exc:``) rendered as code,
linked (mkdocs-autorefs) where the target is an object the reference documents (a ``:::`` line of
``docs/api.md``); the Sphinx ``:math:`` role as code too."""

from __future__ import annotations

import re
from pathlib import Path

import griffe

API = Path(__file__).resolve().parents[1] / "api.md"
ROLE = re.compile(r":(?:py:)?(func|class|mod|data|meth|attr|exc|obj|math):`(~?)([^`]+)`")


def documented() -> set[str]:
    """The identifiers of the reference's ``:::`` lines."""
    lines = API.read_text(encoding="utf-8").splitlines()
    return {ln.split(":::", 1)[1].strip() for ln in lines if ln.startswith(":::")}


def rendered(text: str, known: set[str], module: str = "") -> str:
    """``text`` with its roles as Markdown code, linked where the target (as written, or in the
    docstring's ``module``) is documented."""

    def one(m: re.Match) -> str:
        role, short, target = m.groups()
        target = target.strip()
        shown = target.rsplit(".", 1)[-1] if short else target
        for full in (target, f"{module}.{target}"):
            if role != "math" and full in known:
                return f"[`{shown}`][{full}]"
        return f"`{shown}`"

    return ROLE.sub(one, text)


class SphinxRoles(griffe.Extension):
    """Rewrites each object's docstring (module docstring)."""

    def __init__(self) -> None:
        self.known = documented()

    def on_instance(self, *, obj, **kwargs) -> None:  # noqa: ARG002 (Griffe's hook)
        if obj.docstring is not None:
            obj.docstring.value = rendered(obj.docstring.value, self.known, obj.module.path)
