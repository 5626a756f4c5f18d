"""pipeline.model.osim: the .osim beside the .mot, checked structurally and, where the opensim
package is installed, by OpenSim itself (in a child process) against our landmarks."""

import json
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from lxml import etree

from pipeline.cli import main
from pipeline.io.mot import read_mot

OPENSIM = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "opensim"
WALK = OPENSIM / "xsens_walking_orientations.sto"


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    if not WALK.exists():
        pytest.skip("../shared/data/opensim not present")
    out = tmp_path_factory.mktemp("osim")
    assert main(["ik", "--orientations", str(WALK), "--sex", "m", "--height-m", "1.80",
                 "--sensor-to-model", "-1.5708", "0", "0", "--knee", "hinge", "--osim",
                 "--no-rerun", "--out", str(out)]) == 0
    return out


def _coordinates(path):
    tree = etree.parse(str(path))
    return [c.get("name") for c in tree.iter("Coordinate")], tree


@pytest.mark.dataset
def test_coordinates_are_the_mot_columns_and_markers_the_landmarks(walk):
    names, tree = _coordinates(walk / "xsens_walking_orientations.osim")
    mot = read_mot(walk / "xsens_walking_orientations_ik.mot")
    assert "pelvis_tx" not in mot.columns  # no foot sensors: no path through the room
    moves = ["pelvis_tx", "pelvis_ty", "pelvis_tz"]  # the free pelvis, at its default here
    assert [n for n in names if n not in moves] == list(mot.columns) and moves == names[3:6]
    for joint in tree.iter("CustomJoint"):
        axes = joint.findall("SpatialTransform/TransformAxis")
        assert [a.get("name") for a in axes] == [f"rotation{k}" for k in (1, 2, 3)] + [
            f"translation{k}" for k in (1, 2, 3)]
        moved = [a.findtext("coordinates") for a in axes[3:]]
        free = joint.get("name") == "ground_pelvis"
        assert moved == (["pelvis_tx", "pelvis_ty", "pelvis_tz"] if free else [""] * 3)
    bodies = {b.get("name") for b in tree.iter("Body")}
    assert bodies == {"pelvis", "femur_r", "tibia_r", "calcn_r", "femur_l", "tibia_l", "calcn_l"}
    markers = {m.get("name") for m in tree.iter("Marker")}
    header = (walk / "xsens_walking_orientations_landmarks.csv").read_text().split("\n")[0]
    assert {h[:-2] for h in header.split(",")[1:]} == markers


def test_knee_only_model_has_only_the_knee_coordinates(tmp_path):
    sys.path.insert(0, str(Path(__file__).parent))
    from test_process import _subset, _walk

    from pipeline.io.opensim import write_orientations_sto

    _, _, trial, _ = _walk(tmp_path, n=300)
    sto = tmp_path / "knee.sto"
    write_orientations_sto(sto, _subset(trial, ("femur_r_imu", "tibia_r_imu")))
    assert main(["ik", "--orientations", str(sto), "--sex", "f", "--height-m", "1.6", "--osim",
                 "--no-rerun", "--out", str(tmp_path / "o")]) == 0
    names, tree = _coordinates(tmp_path / "o" / "knee.osim")
    assert names == list(read_mot(tmp_path / "o" / "knee_ik.mot").columns)
    assert names == ["knee_angle_r", "knee_adduction_r", "knee_rotation_r"]
    welds = {j.get("name") for j in tree.iter("WeldJoint")}
    assert welds == {"hip_r", "ankle_r"}  # the femur on the ground at its hip; the ankle neutral


_CHILD = """
import json, sys
import numpy as np
import opensim as osim
from pipeline.io.mot import read_mot
path, mot_path, frames = sys.argv[1], sys.argv[2], json.loads(sys.argv[3])
model = osim.Model(path)
state = model.initSystem()
mot = read_mot(mot_path)
coords = model.getCoordinateSet()
missing = [n for n in mot.columns if not coords.contains(n)]
if missing:
    sys.exit(f"not coordinates of the model: {missing}")
out = {}
for k in frames:
    for name, values in mot.columns.items():
        coords.get(name).setValue(state, float(values[k]), False)
    model.assemble(state)
    model.realizePosition(state)
    ms = model.getMarkerSet()
    out[k] = {ms.get(i).getName(): list(ms.get(i).getLocationInGround(state).to_numpy())
              for i in range(ms.getSize())}
print(json.dumps(out))
"""


@pytest.mark.dataset
def test_opensim_places_the_markers_where_our_landmarks_are(walk):
    """OpenSim's forward kinematics of the .osim with the .mot's angles == our landmarks
    (relative to the right hip centre, in the heading frame of the calibration pose)."""
    import importlib.util

    if importlib.util.find_spec("opensim") is None:  # not imported here: it clashes with CasADi
        pytest.skip("the opensim package is not installed")
    from pipeline.calibration.heading import heading_rotation

    frames = [0, 400, 1234, 2000]
    stem = walk / "xsens_walking_orientations"
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(_CHILD), f"{stem}.osim", f"{stem}_ik.mot",
         json.dumps(frames)], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    osim = json.loads(done.stdout.strip().splitlines()[-1])
    rows = np.loadtxt(walk / "xsens_walking_orientations_landmarks.csv", delimiter=",",
                      skiprows=1)
    header = (walk / "xsens_walking_orientations_landmarks.csv").read_text().split("\n")[0]
    col = {h: i for i, h in enumerate(header.split(","))}
    summary = (walk / "xsens_walking_orientations_summary.md").read_text()
    right = summary.split("(world): (")[1].split(")")[0]
    H = heading_rotation(np.array([float(v) for v in right.split(",")]))
    for k in frames:
        ours = {n: rows[k, [col[f"{n}_{a}"] for a in "xyz"]] for n in osim[str(k)]}
        for name, p in osim[str(k)].items():
            want = H.T @ (ours[name] - ours["right_HJC"])
            got = np.array(p) - np.array(osim[str(k)]["right_HJC"])
            # the .mot holds angles to 1e-6 deg and the CSV positions to 1 um
            assert np.abs(got - want).max() < 2e-4, (k, name, got, want)


@pytest.mark.dataset
def test_opensim_replays_a_walk_through_the_room(tmp_path):
    """S02 (a foot sensor on each foot): every .mot column is a coordinate of the .osim, and
    OpenSim's markers with the .mot's angles and pelvis path are our landmarks in the room
    (``--landmarks world``), in the heading frame of the calibration pose."""
    import importlib.util

    s02 = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "gaittoolbox_s02"
    if importlib.util.find_spec("opensim") is None or not s02.exists():
        pytest.skip("the opensim package or ../shared/data/gaittoolbox_s02 is not present")
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))
    from bench_gait import S02_MAP

    from pipeline.calibration.heading import heading_rotation

    pairs = [f"{k}={v}" for k, v in S02_MAP.items()]
    assert main(["ik", "--orientations", str(s02 / "imu"), "--sensor-map", *pairs, "--sex", "m",
                 "--height-m", "1.72", "--osim", "--no-rerun", "--landmarks", "world", "--out",
                 str(tmp_path)]) == 0
    mot = read_mot(tmp_path / "gaittoolbox_s02_ik.mot")
    assert {"pelvis_tx", "pelvis_ty", "pelvis_tz"} <= set(mot.columns)
    frames = [100, 1300, 1700, 2100]
    done = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(_CHILD), str(tmp_path / "gaittoolbox_s02.osim"),
         str(tmp_path / "gaittoolbox_s02_ik.mot"), json.dumps(frames)], capture_output=True,
        text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    osim = json.loads(done.stdout.strip().splitlines()[-1])
    header = (tmp_path / "gaittoolbox_s02_landmarks.csv").read_text().split("\n")[0].split(",")
    rows = np.loadtxt(tmp_path / "gaittoolbox_s02_landmarks.csv", delimiter=",", skiprows=1)
    summary = (tmp_path / "gaittoolbox_s02_summary.md").read_text()
    right = summary.split("(world): (")[1].split(")")[0]
    H = heading_rotation(np.array([float(v) for v in right.split(",")]))
    walked = 0.0
    for k in frames:
        for name, p in osim[str(k)].items():
            want = H.T @ rows[k, [header.index(f"{name}_{a}") for a in "xyz"]]
            # the heading read from the summary's 3 decimals: 1e-3 rad at up to 4 m
            tol = 2e-4 + 1e-3 * np.linalg.norm(want[[0, 2]])
            assert np.abs(np.array(p) - want).max() < tol, (k, name, p, want)
        walked = max(walked, float(np.linalg.norm(np.array(osim[str(k)]["right_HJC"])[[0, 2]])))
    assert walked > 1.5  # through the room, not in place
