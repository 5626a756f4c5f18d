"""Text files and delimited tables (pipeline.io.text), also reachable through pipeline.io.checks."""

from __future__ import annotations

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io import text


def test_parse_table_empty_cells_are_nan_and_bad_cells_named():
    out = text.parse_table(["1\t2", "3\t"], ["a", "b"])
    assert out[0].tolist() == [1.0, 2.0] and np.isnan(out[1, 1])
    with pytest.raises(InputError, match=r"'x' at row 1 \(line 6\) is not a number") as e:
        text.parse_table(["1\t2", "3\tx"], ["a", "b"], first_line=5)
    assert e.value.field == "b"


def test_parse_table_truncated_last_row():
    with pytest.raises(InputError, match=r"row 2 has 2 fields, expected 3 \(file truncated\?\)"):
        text.parse_table(["1,2,3", "4,5,6", "7,8"], ["a", "b", "c"], sep=",")


def test_read_text_lines_refuses_missing_empty_binary(tmp_path):
    with pytest.raises(InputError, match="file not found"):
        text.read_text_lines(tmp_path / "nope.sto")
    (tmp_path / "e.sto").write_text("  \n")
    with pytest.raises(InputError, match="file is empty"):
        text.read_text_lines(tmp_path / "e.sto")
    (tmp_path / "b.sto").write_bytes(b"\xff\xfe\x00\x81garbage")
    with pytest.raises(InputError, match="not a UTF-8 text file"):
        text.read_text_lines(tmp_path / "b.sto")


def test_where_gives_row_and_file_line():
    assert text.where(3, None) == "row 3"
    assert text.where(3, 10) == "row 3 (line 13)"  # data start at line 10: row 0 is line 10


def test_read_text_lines_drops_bom_and_line_ends_refuses_folder(tmp_path):
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbftime,x\r\n0,1\r\n")
    assert text.read_text_lines(tmp_path / "bom.csv") == ["time,x", "0,1"]
    with pytest.raises(InputError, match="not a file"):
        text.read_text_lines(tmp_path)


def test_parse_table_without_rows_is_empty_with_the_right_width():
    assert text.parse_table([], ["a", "b", "c"]).shape == (0, 3)


def test_whole_table_parse_equals_row_by_row():
    """The one-conversion path gives the row-by-row parse's array, and steps aside (None) for
    the tables the row-by-row parse must refuse or fill: an empty cell, a missing or extra
    field, a word."""
    from pipeline.io.text import _parse_whole

    rows = ["0.0\t1,-2.5e-3,nan,4", "0.01\t 5,6,7,8.25E+2"]
    fast = _parse_whole(rows, 5, "\t", ",")
    slow = np.array([[0.0, 1, -2.5e-3, np.nan, 4], [0.01, 5, 6, 7, 825.0]])
    np.testing.assert_array_equal(fast, slow)
    np.testing.assert_array_equal(text.parse_table(rows, list("abcde"), also_sep=","), slow)
    for bad in (["0\t1,2,,4"], ["0\t1,2,3"], ["0\t1,2,3,4,5"], ["0\t1,2,x,4"], ["0\t1,2 3,4"]):
        assert _parse_whole(bad, 5, "\t", ",") is None
