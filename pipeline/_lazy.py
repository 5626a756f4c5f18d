"""Lazy public names of a package (PEP 562): ``pipeline.model.Skeleton`` imports
:mod:`pipeline.model.skeleton` on first use, so that importing a package costs nothing and a
command loads only the modules it uses."""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping


def lazy_exports(
    package: str, exports: Mapping[str, str]
) -> tuple[Callable[[str], object], Callable[[], list[str]]]:
    """``(__getattr__, __dir__)`` for ``package`` whose public name ``n`` lives in the module
    ``exports[n]`` (relative to the package, e.g. ``'skeleton'``)."""

    def __getattr__(name: str) -> object:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        return getattr(importlib.import_module(f"{package}.{module}"), name)

    def __dir__() -> list[str]:
        return sorted(exports)

    return __getattr__, __dir__
