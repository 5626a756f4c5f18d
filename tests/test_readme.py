"""The README's Python examples run as written from the repository root, on the shipped
examples only (a fresh clone has no ../shared)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)


@pytest.mark.parametrize("code", BLOCKS)
def test_python_example_runs(code):
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)
    assert done.returncode == 0, done.stderr
    assert "right knee flexion" in done.stdout


def test_readme_has_a_python_example():
    assert BLOCKS


def test_no_example_reads_data_a_user_does_not_have():
    assert "shared/data" not in "".join(BLOCKS)
    for line in (ROOT / "README.md").read_text().splitlines():
        if line.startswith("pipeline "):
            assert "shared/data" not in line, line


def test_the_lab_outlet_example_is_python_that_streams():
    """The README's LSL outlet (a ``py`` block: it needs the lab's sensor) is Python that reads
    the sensor and pushes its samples (the outlets' path itself: test_live_sources)."""
    (code,) = re.findall(r"```py\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)
    compile(code, "README.md", "exec")
    assert "read_my_sensor" in code and "push_sample" in code
