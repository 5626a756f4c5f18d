"""All-or-nothing output files (pipeline.io.atomic)."""

from __future__ import annotations

import os

import pytest

from pipeline.io import atomic


def test_atomic_write_replaces_and_leaves_no_temp(tmp_path):
    p = tmp_path / "out.csv"
    p.write_text("old")
    with atomic.atomic_write(p) as f:
        f.write("new")
        assert p.read_text() == "old"  # not visible before the end
    assert p.read_text() == "new"
    assert os.listdir(tmp_path) == ["out.csv"]


def test_atomic_write_error_keeps_old_file_and_no_temp(tmp_path):
    p = tmp_path / "out.csv"
    p.write_text("old")
    with pytest.raises(RuntimeError), atomic.atomic_write(p) as f:
        f.write("partial")
        raise RuntimeError("boom")
    assert p.read_text() == "old"
    assert os.listdir(tmp_path) == ["out.csv"]
    q = tmp_path / "new.csv"
    with pytest.raises(RuntimeError), atomic.atomic_write(q) as f:
        raise RuntimeError("boom")
    assert not q.exists()


def test_write_text_and_bytes_atomic(tmp_path):
    atomic.write_text_atomic(tmp_path / "a.txt", "x\ny")
    atomic.write_bytes_atomic(tmp_path / "b.bin", b"\x00\x01")
    assert (tmp_path / "a.txt").read_text() == "x\ny"
    assert (tmp_path / "b.bin").read_bytes() == b"\x00\x01"
    mode = (tmp_path / "a.txt").stat().st_mode & 0o777
    umask = os.umask(0)
    os.umask(umask)
    assert mode == 0o666 & ~umask  # not mkstemp's private 0600


def test_output_set_all_or_nothing(tmp_path):
    keep = tmp_path / "b.csv"
    keep.write_text("old b")
    with pytest.raises(ValueError, match="model failed"), atomic.output_set() as out:
        with out.open(tmp_path / "a.csv") as f:
            f.write("a")
        out.path(tmp_path / "sub" / "c.urdf").write_text("c")
        with out.open(keep) as f:
            f.write("new b")
        raise ValueError("model failed")
    assert sorted(p.name for p in tmp_path.rglob("*") if p.is_file()) == ["b.csv"]
    assert keep.read_text() == "old b"
    with atomic.output_set() as out:
        with out.open(tmp_path / "a.csv") as f:
            f.write("a")
        with out.open(keep) as f:
            f.write("new b")
    assert (tmp_path / "a.csv").read_text() == "a" and keep.read_text() == "new b"
    assert sorted(p.name for p in tmp_path.iterdir() if p.is_file()) == ["a.csv", "b.csv"]


def test_output_set_commit_failure_rolls_back(tmp_path, monkeypatch):
    keep = tmp_path / "b.csv"
    keep.write_text("old b")
    real_replace = os.replace
    calls = {"n": 0}

    def flaky(src, dst):
        calls["n"] += 1
        if calls["n"] == 3:  # a.csv committed, b.csv backed up, then its rename fails
            raise OSError("disk full")
        return real_replace(src, dst)

    with pytest.raises(OSError, match="disk full"), atomic.output_set() as out:
        with out.open(tmp_path / "a.csv") as f:
            f.write("a")
        with out.open(keep) as f:
            f.write("new b")
        monkeypatch.setattr(atomic.os, "replace", flaky)
    monkeypatch.undo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["b.csv"]
    assert keep.read_text() == "old b"


def test_committed_outputs_lists_what_a_set_committed_and_nothing_aborted(tmp_path):
    from pipeline.io.atomic import committed_outputs, output_set

    before = committed_outputs()
    with pytest.raises(RuntimeError), output_set() as out:
        with out.open(tmp_path / "aborted.csv") as f:
            f.write("x")
        raise RuntimeError("stop")
    assert committed_outputs() == before
    with output_set() as out:
        with out.open(tmp_path / "a.csv") as f:
            f.write("x")
    assert committed_outputs() == (*before, tmp_path / "a.csv")
