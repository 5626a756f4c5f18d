"""pipeline.viz.arrow: a recording command's blueprint without pandas' import, in a new process
(pandas is installed here: mat-io needs it)."""

from __future__ import annotations

import subprocess
import sys

CODE = """
import sys
import numpy as np
{setup}
from pipeline.viz.layout import default_blueprint
default_blueprint([("knee", "/plots/right_knee")], "y", (np.ones(3), np.zeros(3)), 0.0)
print("pandas" in sys.modules)
"""


def _pandas_imported(setup: str) -> bool:
    out = subprocess.run([sys.executable, "-c", CODE.format(setup=setup)], check=True,
                         capture_output=True, text=True).stdout
    return out.strip() == "True"


def test_the_programs_blueprint_does_not_import_pandas():
    assert _pandas_imported("")  # what pyarrow does by itself
    shortcut = "from pipeline.viz.arrow import avoid_pandas_when_recording\n"
    assert not _pandas_imported(shortcut + "avoid_pandas_when_recording()")
