"""STL meshes (binary and ASCII) as shared vertices and triangles, and their vertex normals.

Hand-written instead of trimesh (which read them before): importing trimesh costs a command
~0.7 s, and an STL file is a list of triangles (binary: an 80-byte header, a ``uint32`` count and
50-byte records of a normal, three vertices as ``float32`` and a ``uint16``; ASCII: ``vertex x y
z`` lines). As trimesh's loader does, equal vertices are merged (first occurrence order) so that
the normals are smooth; ``tests/test_io_stl.py`` checks both against trimesh.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.rotations import cross

__all__ = ["read_stl", "vertex_normals"]

_RECORD = np.dtype([("normal", "<f4", 3), ("v", "<f4", (3, 3)), ("attr", "<u2")])


def read_stl(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V, 3) float, triangles (F, 3) int64)`` of an STL file, equal vertices merged.

    Raises ``InputError`` naming the file when it is neither a complete binary STL nor an ASCII
    one with whole triangles.
    """
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise InputError(f"cannot read the mesh: {exc.strerror or exc}", file=path) from exc
    corners = None
    if len(data) >= 84:
        n = int(np.frombuffer(data, "<u4", 1, 80)[0])
        if len(data) == 84 + 50 * n:
            corners = np.frombuffer(data, _RECORD, n, 84)["v"].astype(float).reshape(-1, 3)
    if corners is None:
        corners = _ascii_corners(data, path)
    if not np.all(np.isfinite(corners)):
        raise InputError("the mesh has non-finite vertex coordinates", file=path)
    return _merge_equal(corners)


def _merge_equal(corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equal rows of ``corners`` (M, 3) merged, in first-occurrence order: ``(vertices, index of
    each corner's vertex)`` reshaped to triangles. A stable sort on the three coordinates
    (``np.lexsort``, ~10x faster than ``np.unique(axis=0)``'s sort of structured rows): in each
    run of equal rows the first is the earliest corner."""
    if not len(corners):
        return corners.reshape(0, 3), np.zeros((0, 3), dtype=np.int64)
    order = np.lexsort(corners.T[::-1])
    srt = corners[order]
    starts = np.ones(len(srt), dtype=bool)
    starts[1:] = np.any(srt[1:] != srt[:-1], axis=1)
    group = np.cumsum(starts) - 1  # run of each sorted corner
    first = order[starts]  # earliest corner of each run
    rank = np.empty(first.size, dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(first.size)
    index = np.empty(len(corners), dtype=np.int64)
    index[order] = rank[group]
    return corners[np.sort(first)], index.reshape(-1, 3)


def _ascii_corners(data: bytes, path: Path) -> np.ndarray:
    text = data.decode("ascii", errors="replace")
    if not text.lstrip().lower().startswith("solid"):
        raise InputError("not an STL file (neither a binary STL of the right size nor ASCII "
                         "'solid ...')", file=path)
    rows = [line.split()[1:4] for line in text.splitlines() if line.strip().startswith("vertex")]
    try:
        corners = np.array(rows, dtype=float).reshape(-1, 3)
    except ValueError as exc:
        raise InputError(f"unreadable ASCII STL vertex: {exc}", file=path) from exc
    if len(corners) == 0 or len(corners) % 3:
        raise InputError(f"ASCII STL with {len(corners)} vertices: expected whole triangles",
                         file=path)
    return corners


def vertex_normals(vertices: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Unit vertex normals (V, 3): the face normals of the triangles around each vertex weighted
    by their angle at it (Thürmer & Wüthrich 1998, as trimesh); a vertex of only degenerate
    triangles gets a zero vector."""
    v = np.asarray(vertices, dtype=float)
    f = np.asarray(triangles, dtype=np.int64)
    p = v[f]  # (F, 3 corners, 3)
    n = cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    length = np.linalg.norm(n, axis=1, keepdims=True)
    n = np.divide(n, length, out=np.zeros_like(n), where=length > 0)
    out = np.zeros_like(v)
    for c in range(3):
        a, b = p[:, (c + 1) % 3] - p[:, c], p[:, (c + 2) % 3] - p[:, c]
        angle = np.arctan2(np.linalg.norm(cross(a, b), axis=1), np.einsum("ij,ij->i", a, b))
        for k in range(3):  # sums per vertex (np.bincount: ~10x faster than np.add.at)
            out[:, k] += np.bincount(f[:, c], weights=n[:, k] * angle, minlength=len(v))
    norm = np.linalg.norm(out, axis=1, keepdims=True)
    return np.divide(out, norm, out=np.zeros_like(out), where=norm > 0)
