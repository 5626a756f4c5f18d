"""JSON output: NumPy values made JSON-serialisable (the one converter)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["jsonable"]


def jsonable(x: object) -> object:
    """Nested dicts/lists/arrays -> JSON types; non-finite floats -> None."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    if isinstance(x, (bool, np.bool_)):
        return bool(x)
    if isinstance(x, (int, np.integer)):
        return int(x)
    if isinstance(x, (float, np.floating)):
        return float(x) if np.isfinite(x) else None
    if isinstance(x, Path):
        return str(x)
    return x
