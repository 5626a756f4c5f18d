"""pipeline.analysis.quality: the quality gate, by hand and on the real walking trial with its
quaternions in the wrong order."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pipeline.analysis.quality import AT_LIMIT_SHARE, RESIDUAL_BOUND_DEG, quality_flags
from pipeline.cli import main
from pipeline.model import Skeleton, SubjectGeometry

WALK = Path(__file__).resolve().parents[2] / "shared/data/opensim/xsens_walking_orientations.sto"


@pytest.fixture(scope="module")
def leg():
    return Skeleton.build(SubjectGeometry.default(1.75, "m", "right"), knee="free", legs=("right",))


def test_flags_by_hand(leg):
    n = 100
    mid = 0.5 * (leg.lower_limits + leg.upper_limits)
    q = np.tile(mid, (n, 1))
    small = np.full(n, np.radians(1.0))
    assert quality_flags(leg, q, small) == []
    big = np.full(n, np.radians(RESIDUAL_BOUND_DEG + 1.0))
    (flag,) = quality_flags(leg, q, big)
    assert "quaternion order" in flag and f"{RESIDUAL_BOUND_DEG + 1:.1f} deg" in flag
    i = leg.q_index("right_knee_Z")
    q[: int(n * (AT_LIMIT_SHARE + 0.1)), i] = leg.upper_limits[i]
    (flag,) = quality_flags(leg, q, small)
    assert "right_knee_Z (60% of frames)" in flag
    notes = ["the hip and knee flexion axes disagree by up to 80 deg: ..."]
    assert quality_flags(leg, mid[None], small[:1], notes) == notes  # disagreeing heading cues



def test_a_leg_swinging_between_its_limits_and_a_straight_knee_standing_still(leg):
    """Knee ab/adduction at a limit 20 % of the frames, the ankle at one in another 20 %: each
    joint below AT_LIMIT_SHARE, the leg at its limits 40 % of the time (AT_LIMIT_LEG_SHARE). A
    knee straight at its extension limit while the subject stands still is the pose, not a
    fault; the same knee held there while the sensors move is flagged."""
    n = 100
    q = np.tile(0.5 * (leg.lower_limits + leg.upper_limits), (n, 1))
    knee, ankle = leg.q_index("right_knee_X"), leg.q_index("right_ankle_Z")
    q[:20, knee] = leg.upper_limits[knee]
    q[50:70, ankle] = leg.lower_limits[ankle]
    small = np.full(n, np.radians(1.0))
    (flag,) = quality_flags(leg, q, small)
    assert flag.startswith("the right leg has a joint at its limit in 40% of the frames")
    assert "right_knee_X" in flag and "right_ankle_Z" in flag
    q[:, :] = 0.5 * (leg.lower_limits + leg.upper_limits)
    flexion = leg.q_index("right_knee_Z")
    q[:, flexion] = leg.lower_limits[flexion]  # straight throughout
    still = np.ones(n, dtype=bool)
    assert quality_flags(leg, q, small, still=still) == []
    (flag,) = quality_flags(leg, q, small, still=~still)
    assert "right_knee_Z (100% of frames)" in flag


def _reordered(tmp_path: Path) -> Path:
    """The walking file with every quaternion written x, y, z, w (a common export mistake)."""
    lines = WALK.read_text().split("\n")
    start = lines.index("endheader") + 2
    out = lines[:start]
    for line in lines[start:]:
        if not line.strip():
            out.append(line)
            continue
        cells = line.split("\t")
        quats = [",".join(np.roll(c.split(","), -1)) for c in cells[1:]]
        out.append("\t".join([cells[0], *quats]))
    path = tmp_path / "xyzw.sto"
    path.write_text("\n".join(out))
    return path


@pytest.mark.dataset
@pytest.mark.skipif(not WALK.is_file(), reason="needs ../shared/data/opensim")
def test_wrong_quaternion_order_is_flagged_first_and_strict_refuses(tmp_path, capsys):
    sto = _reordered(tmp_path)
    base = ["ik", "--orientations", str(sto), "--sex", "m", "--height-m", "1.8",
            "--sensor-to-model", "-1.5708", "0", "0"]
    assert main([*base, "--out", str(tmp_path / "flagged")]) == 0
    captured = capsys.readouterr()
    assert "warning: median orientation residual" in captured.err
    summary = (tmp_path / "flagged" / "xyzw_summary.md").read_text().splitlines()
    assert summary[2].startswith("**WARNING: median orientation residual")  # first thing
    assert main([*base, "--strict", "--out", str(tmp_path / "strict")]) == 3
    assert "quaternion order" in capsys.readouterr().err
    assert not (tmp_path / "strict").exists()  # a refused run leaves no folder
    # the file as written passes without a flag
    assert main(["ik", "--orientations", str(WALK), "--sex", "m", "--height-m", "1.8",
                 "--sensor-to-model", "-1.5708", "0", "0", "--strict",
                 "--out", str(tmp_path / "ok")]) == 0
    assert "warning" not in capsys.readouterr().err
