"""Tests of pipeline.io.stl against trimesh (the reader it replaced) and by hand."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from pipeline.errors import InputError
from pipeline.io.stl import read_stl, vertex_normals
from pipeline.model.meshes import resolve_package_uri

FOOT = "package://example-robot-data/robots/human_description/meshes/foot_mesh.STL"


def test_binary_stl_matches_trimesh():
    path = resolve_package_uri(FOOT)
    v, f = read_stl(path)
    ref = trimesh.load(path, force="mesh")
    assert v.shape == ref.vertices.shape and f.shape == ref.faces.shape
    # the same triangles as point triples, whatever the vertex numbering
    ours = np.sort(v[f].reshape(len(f), -1), axis=0)
    theirs = np.sort(np.asarray(ref.vertices)[ref.faces].reshape(len(f), -1), axis=0)
    np.testing.assert_allclose(ours, theirs, atol=1e-9)
    n = vertex_normals(v, f)
    tm = trimesh.Trimesh(v, f, process=False)
    cos = np.einsum("ij,ij->i", n, tm.vertex_normals)
    assert np.percentile(cos, 1) > 0.999  # the same angle-weighted normals


def test_ascii_stl_and_merging_by_hand(tmp_path):
    path = tmp_path / "two.stl"
    path.write_text(
        "solid two\n"
        " facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n"
        "  endloop\n endfacet\n"
        " facet normal 0 0 1\n  outer loop\n   vertex 1 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n"
        "  endloop\n endfacet\nendsolid two\n"
    )
    v, f = read_stl(path)
    np.testing.assert_array_equal(v, [[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]])
    np.testing.assert_array_equal(f, [[0, 1, 2], [1, 3, 2]])
    np.testing.assert_allclose(vertex_normals(v, f), np.tile([0.0, 0.0, 1.0], (4, 1)))


def test_binary_round_trip_through_trimesh_export(tmp_path):
    tri = trimesh.Trimesh([[0, 0, 0], [2, 0, 0], [0, 3, 0], [0, 0, 1]], [[0, 2, 1], [0, 1, 3]],
                          process=False)
    tri.export(tmp_path / "t.stl")
    v, f = read_stl(tmp_path / "t.stl")
    np.testing.assert_allclose(v[f], tri.vertices[tri.faces])


@pytest.mark.parametrize("content", [b"not a mesh at all", b"\0" * 84 + b"\1" * 10])
def test_bad_files_name_the_file(tmp_path, content):
    path = tmp_path / "bad.stl"
    path.write_bytes(content)
    with pytest.raises(InputError, match="bad.stl"):
        read_stl(path)
    with pytest.raises(InputError, match="missing.stl"):
        read_stl(tmp_path / "missing.stl")


def test_merge_equal_is_unique_rows_in_first_occurrence_order():
    """The lexsort merge gives what np.unique(axis=0) reordered by first occurrence gives (the
    former implementation), on corners with many repeats."""
    from pipeline.io.stl import _merge_equal

    rng = np.random.default_rng(3)
    pool = rng.integers(-3, 4, (40, 3)).astype(float) * 0.25
    corners = pool[rng.integers(0, 40, 300)]
    v, f = _merge_equal(corners)
    unique, first, inverse = np.unique(corners, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    np.testing.assert_array_equal(v, unique[order])
    np.testing.assert_array_equal(f, rank[inverse.reshape(-1)].reshape(-1, 3))
    np.testing.assert_array_equal(v[f].reshape(-1, 3), corners)  # every corner kept
