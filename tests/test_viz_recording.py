"""Tests of pipeline.viz.recording: write a trial to .rrd, read it back (entities, rows, values),
commands."""

from __future__ import annotations

import importlib.metadata
import time
from pathlib import Path

import numpy as np
import pytest

from pipeline.errors import InputError
from pipeline.rotations import exp3, matrix_from_quat, rot_z
from pipeline.viz.recording import (
    entity_row_counts,
    log_trial,
    read_entities,
)

N = 3000
NAMES = ("EFM", "EFL", "MM", "LM")


def _trial(rng: np.random.Generator):
    t = np.arange(N) / 100.0
    lm = {n: 0.1 * rng.standard_normal((N, 3)) for n in NAMES}
    ref = {n: v + 0.01 for n, v in lm.items()}
    ref["MM"][[5, 6, 7]] = np.nan  # three missing reference samples
    R_tib = exp3(np.column_stack([0.2 * np.sin(t), np.zeros(N), t]))
    poses = {
        "femur": (rot_z(0.5 * np.sin(t)), np.zeros((N, 3))),
        "tibia": (R_tib, 0.45 * rng.standard_normal((N, 3))),
    }
    angles = {"knee_flexion": np.sin(t), "hip_flexion": 0.5 * np.cos(t)}
    return t, lm, ref, poses, angles


def _columns(path: Path, entity: str) -> dict[str, list]:
    """All temporal rows of one entity, component name -> list of values (concatenated chunks)."""
    from rerun.chunk import RrdReader

    out: dict[str, list] = {}
    for c in RrdReader(path).stream().to_chunks():
        if c.entity_path != entity or c.is_static:
            continue
        rb = c.to_record_batch()
        for name in rb.schema.names:
            out.setdefault(name, []).extend(rb.column(name).to_pylist())
    return out


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    rng = np.random.default_rng(0)
    data = _trial(rng)
    path = tmp_path_factory.mktemp("viz") / "trial.rrd"
    import rerun  # noqa: F401  (import time, ~1 s, is not logging time)

    elapsed = []
    for _ in range(2):  # first call pays rerun's lazy initialisation
        start = time.perf_counter()
        log_trial(path, *data[:2], data[2], True, data[3], data[4], recording_name="synthetic")
        elapsed.append(time.perf_counter() - start)
    print(
        f"\nlog_trial, {N} frames (4+4 landmarks, 4 arrows, 2 poses, 2 angles): "
        f"first {elapsed[0]:.3f} s, then {elapsed[1]:.3f} s"
    )
    return path, data, elapsed[1]


def test_entities_and_row_counts(recording):
    path, _, elapsed = recording
    expected = (
        {f"/world/landmarks/{n}" for n in NAMES}
        | {f"/world/reference/{n}" for n in NAMES}
        | {f"/world/errors/{n}" for n in NAMES}
        | {"/world/segments/femur", "/world/segments/tibia"}
        | {"/plots/knee_flexion", "/plots/hip_flexion"}
    )
    assert read_entities(path) == expected | {"/world"}
    counts = entity_row_counts(path)
    for entity in expected:
        missing = 3 if entity in ("/world/reference/MM", "/world/errors/MM") else 0
        assert counts[entity] == N - missing, entity
    assert counts["/world"] == 0  # static view coordinates only


def test_values_round_trip(recording):
    path, (t, lm, ref, poses, angles), _ = recording
    cols = _columns(path, "/world/landmarks/EFL")
    np.testing.assert_allclose(np.array(cols["Points3D:positions"])[:, 0], lm["EFL"], atol=1e-6)
    times = np.array(
        [d.total_seconds() if hasattr(d, "total_seconds") else d for d in cols["time"]]
    )
    np.testing.assert_allclose(times, t, atol=1e-6)

    cols = _columns(path, "/world/errors/MM")
    ok = np.all(np.isfinite(ref["MM"]), axis=1)
    origins = np.array(cols["Arrows3D:origins"])[:, 0]
    vectors = np.array(cols["Arrows3D:vectors"])[:, 0]
    np.testing.assert_allclose(origins, ref["MM"][ok], atol=1e-6)
    np.testing.assert_allclose(origins + vectors, lm["MM"][ok], atol=1e-6)

    cols = _columns(path, "/world/segments/tibia")
    xyzw = np.array(cols["Transform3D:quaternion"])[:, 0]
    R = matrix_from_quat(xyzw[:, [3, 0, 1, 2]])
    np.testing.assert_allclose(R, poses["tibia"][0], atol=1e-5)
    np.testing.assert_allclose(
        np.array(cols["Transform3D:translation"])[:, 0], poses["tibia"][1], atol=1e-6
    )

    cols = _columns(path, "/plots/knee_flexion")
    np.testing.assert_allclose(
        np.array(cols["Scalars:scalars"])[:, 0], np.degrees(angles["knee_flexion"]), atol=1e-9
    )


def test_bad_shapes_are_input_errors(tmp_path):
    t = np.arange(10) / 100.0
    with pytest.raises(InputError, match="EFM"):
        log_trial(tmp_path / "a.rrd", t, {"EFM": np.zeros((9, 3))})
    assert not (tmp_path / "a.rrd").exists()
    with pytest.raises(InputError):
        log_trial(tmp_path / "b.rrd", t, {}, segment_poses={"femur": (np.zeros((10, 3)), 0)})
    with pytest.raises(InputError):
        read_entities(tmp_path / "missing.rrd")


def _human_urdf() -> Path | None:
    try:
        files = importlib.metadata.files("example-robot-data") or []
    except importlib.metadata.PackageNotFoundError:
        return None
    for f in files:
        if str(f).endswith("human_description/robots/human.urdf"):
            return Path(str(f.locate()))
    return None


def test_urdf_is_logged_with_meshes(tmp_path):
    urdf = _human_urdf()
    if urdf is None:
        pytest.skip("example-robot-data is not installed")
    path = tmp_path / "model.rrd"
    t = np.arange(5) / 100.0
    log_trial(path, t, {"EFM": np.zeros((5, 3))}, urdf_path=urdf)
    entities = read_entities(path)
    assert "/world/model_root" in entities
    visuals = [e for e in entities if "/world/model/" in e and "right_upperleg" in e]
    assert visuals, sorted(entities)[:10]
    # package:// meshes resolved: the visual carries an Asset3D blob.
    from rerun.chunk import RrdReader

    names = set()
    root = None
    for c in RrdReader(path).stream().to_chunks():
        rb = c.to_record_batch()
        if c.entity_path == visuals[0]:
            names |= set(rb.schema.names)
        if c.entity_path == "/world/model_root":
            root = rb
    assert "Asset3D:blob" in names
    assert root.column("Transform3D:child_frame").to_pylist() == [["middle_pelvis"]]
    assert root.column("Transform3D:parent_frame").to_pylist() == [["tf#/world"]]
    # Default root pose Rx(+90 deg): the model's y (up) becomes the world's z.
    col_major = np.array(root.column("Transform3D:mat3x3").to_pylist()[0][0]).reshape(3, 3).T
    np.testing.assert_allclose(col_major @ [0, 1.0, 0], [0, 0, 1.0], atol=1e-6)


def test_default_layout_and_hidden_labels(recording):
    """The file's default blueprint: the 3D view of /world beside one plot of /plots; landmark
    labels are stored but hidden (shown on hover)."""
    from rerun.chunk import RrdReader

    path = recording[0]
    reader = RrdReader(path)
    (store,) = reader.blueprints()
    views = {}
    for c in reader.stream(store=store).to_chunks():
        rb = c.to_record_batch()
        if "ViewBlueprint:class_identifier" in rb.schema.names:
            row = {n: rb.column(n).to_pylist()[0][0] for n in rb.schema.names if ":" in n}
            views[row["ViewBlueprint:display_name"]] = (
                row["ViewBlueprint:class_identifier"],
                row["ViewBlueprint:space_origin"],
            )
    assert views == {"3D": ("3D", "/world"), "joint angles (deg)": ("TimeSeries", "/plots")}
    for c in reader.stream().to_chunks():
        if c.entity_path == "/world/landmarks/EFM" and c.is_static:
            rb = c.to_record_batch()
            assert rb.column("Points3D:labels").to_pylist() == [["EFM"]]
            assert rb.column("Points3D:show_labels").to_pylist() == [[False]]
            break
    else:
        raise AssertionError("no static landmark style")


def test_the_program_records_without_importing_pandas(tmp_path):
    """`pipeline demo` as a program: pyarrow is told once that pandas is absent (0.5 s saved)
    and the recording is complete, with no rerun warning."""
    import subprocess
    import sys

    code = ("import sys; sys.argv = ['pipeline', 'demo', '--out', sys.argv[1]]\n"
            "from pipeline.cli import main\nrc = main()\nprint(rc, 'pandas' in sys.modules)")
    res = subprocess.run([sys.executable, "-c", code, str(tmp_path)], capture_output=True,
                         text=True, check=True)
    assert res.stdout.split()[-2:] == ["0", "False"]
    assert "Warning" not in res.stderr
    rrd = next(tmp_path.glob("*.rrd"))
    counts = entity_row_counts(rrd)
    assert any(k.startswith("/plots/") for k in counts) and any("mesh" in k for k in counts)
