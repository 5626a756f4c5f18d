"""pipeline.option: an option declared once gives its flag, its file key and its manifest cell."""

import argparse
from dataclasses import dataclass
from pathlib import Path

import pytest

from pipeline.errors import InputError
from pipeline.option import add_flags, from_cell, from_flag, from_toml, option, parse_pairs, specs


@dataclass(frozen=True)
class _Demo:
    mode: str = option("a", "choice", "a mode", choices=("a", "b"))
    fast: bool = option(True, "bool", "go fast")
    loud: bool = option(False, "bool", "be loud")
    axis: tuple | None = option(None, "vec3", "an axis")
    names: dict = option({}, "pairs", "names", section="sensors")
    where: str | None = option(None, "path", "a path")


def test_specs_and_flags_follow_the_declaration():
    s = {x.name: x for x in specs(_Demo)}
    assert [x.name for x in specs(_Demo)] == ["mode", "fast", "loud", "axis", "names", "where"]
    assert s["fast"].flag == "--no-fast" and s["loud"].flag == "--loud"
    assert s["names"].key == "sensors" and s["mode"].key == "ik.mode"
    p = argparse.ArgumentParser()
    add_flags(p, specs(_Demo))
    a = p.parse_args(["--no-fast", "--loud", "--axis", "1", "2", "3", "--names", "x=1", "y=2"])
    got = {x.name: from_flag(x, getattr(a, x.name)) for x in specs(_Demo)}
    assert got == {"mode": None, "fast": False, "loud": True, "axis": (1.0, 2.0, 3.0),
                   "names": {"x": "1", "y": "2"}, "where": None}


def test_a_list_flag_given_twice_adds_to_the_first():
    """``--names x=1 --names y=2`` as ``--names x=1 y=2`` (argparse's default keeps the last)."""
    p = argparse.ArgumentParser()
    add_flags(p, specs(_Demo))
    s = {x.name: x for x in specs(_Demo)}
    a = p.parse_args(["--names", "x=1", "--names", "y=2", "z=3"])
    assert from_flag(s["names"], a.names) == {"x": "1", "y": "2", "z": "3"}
    with pytest.raises(InputError):  # a name given twice across the flags is still refused
        from_flag(s["names"], p.parse_args(["--names", "x=1", "--names", "x=2"]).names)


def test_cells_and_toml_values_parse_alike(tmp_path):
    s = {x.name: x for x in specs(_Demo)}
    f = tmp_path / "m.csv"
    assert from_cell(s["axis"], "1 2 3", tmp_path, f, 2) == (1.0, 2.0, 3.0)
    assert from_toml(s["axis"], [1, 2, 3], tmp_path, f) == (1.0, 2.0, 3.0)
    assert from_cell(s["fast"], "No", tmp_path, f, 2) is False
    assert from_cell(s["where"], "x.sto", tmp_path, f, 2) == str((tmp_path / "x.sto").resolve())
    assert from_toml(s["where"], "x.sto", tmp_path, f) == str((tmp_path / "x.sto").resolve())
    assert from_cell(s["names"], "a=1 b=2", tmp_path, f, 2) == {"a": "1", "b": "2"}
    with pytest.raises(InputError) as exc:
        from_cell(s["axis"], "1 2", tmp_path, f, 7)
    assert exc.value.field == "axis (line 7)" and "three numbers" in exc.value.message
    with pytest.raises(InputError, match="true or false"):
        from_cell(s["fast"], "maybe", tmp_path, f, 2)
    with pytest.raises(InputError, match="three numbers"):
        from_toml(s["axis"], [1, True, 3], tmp_path, Path("c.toml"))


def test_pairs_refuse_malformed_and_repeated_names():
    with pytest.raises(InputError, match="NAME=VALUE"):
        parse_pairs(["a"], "--names")
    with pytest.raises(InputError, match="given twice"):
        parse_pairs("a=1 a=2", "--names")


def test_an_unknown_kind_is_a_programming_error():
    with pytest.raises(ValueError, match="unknown option kind"):
        option(1, "complex", "no")
