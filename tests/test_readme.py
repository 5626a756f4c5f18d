"""The README's Python examples run as written from the repository root."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.S)


@pytest.mark.dataset
@pytest.mark.skipif(not (ROOT.parent / "shared" / "data" / "opensim").is_dir(),
                    reason="needs ../shared/data/opensim")  # fmt: skip
@pytest.mark.parametrize("code", BLOCKS)
def test_python_example_runs(code):
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True,
                          timeout=300)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "right knee flexion" in done.stdout


def test_readme_has_a_python_example():
    assert BLOCKS
