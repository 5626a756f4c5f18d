"""Optional dependencies: a command that needs an extra says which, in one line.

The core install (``pip install imu-skeleton-pipeline``) is what ``pipeline ik`` and ``pipeline
demo`` need; ``[batch]`` adds Dask for ``pipeline batch``, ``[reproduce]`` the MATLAB and C3D
readers and matplotlib for ``pipeline reproduce``, ``[report]`` matplotlib for the reports
(``<name>_report.html``), ``[live]`` Lab Streaming Layer for ``pipeline live --lsl``, ``[all]``
every one (:data:`EXTRAS`).
"""

from __future__ import annotations

import importlib
from types import ModuleType

from pipeline.errors import InputError

__all__ = ["EXTRAS", "need"]

#: Module -> the extra that installs it.
EXTRAS = {"distributed": "batch", "dask": "batch", "matio": "reproduce", "ezc3d": "reproduce",
          "matplotlib": "report", "pylsl": "live"}


def need(module: str, what: str) -> ModuleType:
    """Import ``module`` for ``what`` (e.g. ``'pipeline batch'``), or refuse naming the extra."""
    try:
        return importlib.import_module(module)
    except ImportError:
        extra = EXTRAS.get(module.split(".")[0], "all")
        raise InputError(f"{what} needs {module}, which the '{extra}' extra installs: pip install "
                         f"'imu-skeleton-pipeline[{extra}]'") from None
