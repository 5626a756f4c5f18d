"""pipeline.io.mot: OpenSim numeric tables written and read back in SI units."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.io import mot

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opensim"
NAMES = ["pelvis_imu", "femur_r_imu", "tibia_r_imu"]



def test_mot_truncated_and_bad_column_length(tmp_path):
    t = np.arange(20) / 100.0
    p = mot.write_mot(tmp_path / "a.mot", t, {"knee": t})
    text = p.read_text().splitlines()
    (tmp_path / "cut.mot").write_text("\n".join(text[:-5]) + "\n")
    with pytest.raises(InputError, match=r"nRows=20 but the table has 15 \(file truncated\?\)"):
        mot.read_mot(tmp_path / "cut.mot")
    with pytest.raises(ValueError, match="has 3 values, time has 20"):
        mot.write_mot(tmp_path / "b.mot", t, {"knee": [1, 2, 3]})


def test_numbers_are_written_as_python_prints_them(tmp_path):
    """0.03 s, not 0.029999999999999999 (issue 25), and still read back exactly."""
    import numpy as np

    from pipeline.io.mot import read_mot, write_mot

    t = np.arange(5) * 0.01
    y = np.array([0.1, 0.2, 0.3, 1 / 3, 2.0])
    write_mot(tmp_path / "a.mot", t, {"knee_angle_r": y}, in_degrees=False)
    lines = (tmp_path / "a.mot").read_text().splitlines()
    assert lines[-2].split("\t") == ["0.03", "0.3333333333333333"]
    back = read_mot(tmp_path / "a.mot")
    assert np.array_equal(back.time, t) and np.array_equal(back.columns["knee_angle_r"], y)
