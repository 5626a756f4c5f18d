"""Tests of pipeline.viz.rrd: the recording written by rerun's native writer without the rerun
package holds what rerun's own Python API writes for the same calls (chunks, descriptors, Arrow
data, the blueprint up to its random ids); version check; colours."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from _helpers import read_blueprint

import pipeline.viz.recording as recording
from pipeline.viz.layout import sdk_blueprint
from pipeline.viz.rrd import RrdWriter, check_version, pack_colors


class SdkWriter:
    """The same interface as RrdWriter through rerun's Python API (the reference)."""

    def __init__(self, path, app_id, recording_name=None, layout=None):
        import rerun as rr

        self.rr = rr
        self.rec = rr.RecordingStream(app_id)
        self.rec.save(path, default_blueprint=None if layout is None else sdk_blueprint(layout))
        if recording_name:
            self.rec.send_recording_name(recording_name)

    def log(self, entity, archetype, **fields):
        self.rec.log(entity, getattr(self.rr, archetype).from_fields(**fields), static=True)

    def send_columns(self, entity, t, archetype, **fields):
        cols = getattr(self.rr, archetype).columns(**fields)
        self.rec.send_columns(entity, indexes=[self.rr.TimeColumn("time", duration=t)],
                              columns=cols)

    def log_file_from_path(self, path, entity_path_prefix):
        self.rec.log_file_from_path(path, entity_path_prefix=entity_path_prefix, static=True)
        self.rec.flush()

    def close(self):
        self.rec.flush()
        self.rec.disconnect()

    def abort(self):
        self.rec.disconnect()


def _content(path: Path) -> list:
    """Every data chunk of the recording as comparable rows: (entity, static, component columns
    with their descriptors and values, time values)."""
    from rerun.chunk import RrdReader

    reader = RrdReader(path)
    (store,) = reader.recordings()
    rows = []
    for c in reader.stream(store=store).to_chunks():
        if c.entity_path.startswith("/__"):
            continue
        rb = c.to_record_batch()
        cols = {}
        for i, name in enumerate(rb.schema.names):
            if name.startswith("log_") or name.startswith("rerun."):
                continue  # the writer's log time, row ids
            meta = {k.decode(): v.decode() for k, v in (rb.schema.field(i).metadata or {}).items()
                    if b"component" in k or b"archetype" in k}
            cols[name] = (str(rb.schema.field(i).type), sorted(meta.items()),
                          rb.column(i).to_pylist())
        rows.append((c.entity_path, c.is_static, sorted(cols.items(), key=lambda kv: kv[0])))
    return sorted(rows, key=repr)


def _normalised(bp: dict) -> list:
    """The blueprint with its random view and container ids named by their place in the layout
    tree (root container first, contents in order), sorted."""
    import uuid

    root = bp["/viewport"].pop("ViewportBlueprint:root_container")[0]
    names: dict[str, str] = {}

    def walk(path: str) -> None:
        names[path.split("/")[1]] = f"node{len(names)}"
        for sub in bp["/" + path].get("ContainerBlueprint:contents", []):
            walk(sub)

    walk(f"container/{uuid.UUID(bytes=bytes(root))}")
    text = repr(sorted(bp.items()))
    for old, new in names.items():
        text = text.replace(old, new)
    return sorted(re.findall(r"\('/[^']*', \{.*?\}\)", text))


def _scene(walk: bool = False):
    """A simulated gait on a scaled model: meshes, poses, landmarks with references and error
    arrows, IMU axes, bones, angles with truth, an extra scalar (one NaN); ``walk``: carried 2 m
    further through the room, with footprints."""
    from pipeline.simulate.model import simulate_trial
    from pipeline.viz.model import SceneOptions, motion_scene

    sim = simulate_trial(seed=0, duration_s=2.0)
    t = sim.time
    ref = {k: v + 0.01 for k, v in list(sim.landmarks.items())[:3]}
    extra = np.sin(t)
    extra[5] = np.nan
    truth = {"right_knee_flexion": 0.1 * np.sin(t)}
    root = None
    if walk:
        root = np.zeros((len(t), 3))
        root[:, 0] = t
        ref["left_footprint"] = np.where(t[:, None] < 1.0, [0.2, -0.9, -0.1], [1.3, -0.9, -0.1])
    return motion_scene(t, sim.skeleton, sim.q, SceneOptions(
        reference_landmarks=ref, reference_angles=truth, extra_scalars={"residual": extra},
        recording_name="sim", root_path=root))


@pytest.mark.parametrize("walk", [False, True])
def test_recording_equals_rerun_sdk(tmp_path, monkeypatch, walk):
    from pipeline.viz.scene import log_scene

    scene = _scene(walk)
    ours = log_scene(tmp_path / "ours.rrd", scene)
    monkeypatch.setattr(recording, "RrdWriter", SdkWriter)
    sdk = log_scene(tmp_path / "sdk.rrd", scene)
    a, b = _content(ours), _content(sdk)
    assert len(a) == len(b) > 40
    walked = {row[0] for row in a if row[0].startswith("/world/walk")}  # the sim walks 2.3 m
    assert walked == {"/world/walk/path"} | ({"/world/walk/left_footprints"} if walk else set())
    for x, y in zip(a, b, strict=True):
        assert x == y
    assert _normalised(read_blueprint(ours)) == _normalised(read_blueprint(sdk))


def test_blueprint_comparison_is_not_vacuous(tmp_path):
    from pipeline.viz.scene import log_scene

    bp = _normalised(read_blueprint(log_scene(tmp_path / "ours.rrd", _scene())))
    assert len(bp) > 15 and any("EyeControls3D" in row for row in bp)


def test_pack_colors_by_hand():
    # 0xRRGGBBAA: (227, 218, 201, 150) -> 0xE3DAC996; alpha 255 when not given
    assert pack_colors([(227, 218, 201, 150)]).tolist() == [0xE3DAC996]
    assert pack_colors([(1, 2, 3)]).tolist() == [0x010203FF]


def test_other_rerun_version_refused(monkeypatch):
    import rerun_bindings

    monkeypatch.setattr(rerun_bindings, "version", lambda: "rerun_py 0.99.1 (x)")
    with pytest.raises(RuntimeError, match=r"rerun-sdk 0\.41\.x, found 0\.99\.1"):
        check_version()
    with pytest.raises(RuntimeError, match="0.99.1"):
        RrdWriter("unused.rrd", "app")


def test_recording_written_without_importing_rerun(tmp_path):
    """The point of the module: a recording costs no import of the rerun package."""
    code = (
        "import sys, numpy as np\n"
        "from pipeline.viz.recording import log_trial\n"
        "t = np.arange(50) / 100.0\n"
        f"log_trial({str(tmp_path / 'a.rrd')!r}, t, {{'EFM': np.zeros((50, 3))}},\n"
        "          joint_angles={'knee_flexion': np.sin(t)})\n"
        "print(sorted(m for m in sys.modules if m == 'rerun' or m.startswith('rerun.')))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True, cwd=Path(__file__).resolve().parents[1])
    assert out.stdout.strip() == "[]"
    from pipeline.viz.recording import entity_row_counts

    assert entity_row_counts(tmp_path / "a.rrd")["/plots/knee_flexion"] == 50


def test_trial_with_gaps_and_urdf_equals_rerun_sdk(tmp_path, monkeypatch):
    """log_trial: missing samples (NaN rows left out), reference landmarks and error arrows,
    segment poses, angles and a URDF placed by a named-frame transform: the same chunks."""
    from pipeline.model.resources import human_urdf

    rng = np.random.default_rng(1)
    n = 120
    t = np.arange(n) / 100.0
    lm = {"EFM": rng.standard_normal((n, 3)), "MM": rng.standard_normal((n, 3))}
    lm["MM"][[3, 4, 50]] = np.nan
    ref = {k: v + 0.01 for k, v in lm.items()}
    ref["EFM"][7] = np.nan
    from pipeline.rotations import exp3

    R = exp3(0.3 * rng.standard_normal((n, 3)))
    R[10] = np.nan
    poses = {"femur": (R, rng.standard_normal((n, 3)))}
    angles = {"knee_flexion": np.sin(t)}
    kwargs = dict(reference_landmarks=ref, segment_poses=poses, joint_angles=angles,
                  urdf_path=human_urdf(), recording_name="gaps")
    ours = recording.log_trial(tmp_path / "ours.rrd", t, lm, **kwargs)
    monkeypatch.setattr(recording, "RrdWriter", SdkWriter)
    sdk = recording.log_trial(tmp_path / "sdk.rrd", t, lm, **kwargs)
    a, b = _content(ours), _content(sdk)
    assert len(a) == len(b) > 10
    for x, y in zip(a, b, strict=True):
        assert x == y


def test_rerun_verifies_the_file(tmp_path):
    """rerun's own checker (``rerun rrd verify``: every chunk decoded against its component
    types) accepts what the native writer wrote through us."""
    import shutil

    from pipeline.viz.scene import log_scene

    exe = shutil.which("rerun") or str(Path(sys.executable).with_name("rerun"))
    if not Path(exe).exists():
        pytest.skip("the rerun command-line program is not installed")
    path = log_scene(tmp_path / "ours.rrd", _scene())
    out = subprocess.run([exe, "rrd", "verify", str(path)], capture_output=True, text=True,
                         timeout=120)
    assert out.returncode == 0 and "verified without error" in out.stdout + out.stderr, out


def test_rrd_problem_tells_a_whole_recording_from_others(tmp_path):
    """A recording the writer finished, the same cut short, empty, and another file."""
    from pipeline.viz.rrd import rrd_problem
    from pipeline.viz.scene import log_scene

    path = log_scene(tmp_path / "whole.rrd", _scene())
    assert rrd_problem(path) is None
    data = path.read_bytes()
    (tmp_path / "cut.rrd").write_bytes(data[: len(data) // 2])
    assert rrd_problem(tmp_path / "cut.rrd").startswith("cut short")
    (tmp_path / "empty.rrd").write_bytes(b"")
    assert rrd_problem(tmp_path / "empty.rrd") == "empty"
    (tmp_path / "notes.rrd").write_text("hello")
    assert rrd_problem(tmp_path / "notes.rrd").startswith("not a rerun recording")
    assert rrd_problem(tmp_path) == "not a file"
