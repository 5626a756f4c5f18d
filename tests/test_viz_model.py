"""Tests of pipeline.viz.model: a scaled model's motion written to .rrd and read back."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from _helpers import blueprint_views, read_blueprint

from pipeline.analysis.joint_angles import joint_angles
from pipeline.errors import InputError
from pipeline.model import Skeleton, SubjectGeometry
from pipeline.rotations import matrix_from_quat, rot_z
from pipeline.viz.model import ANGLE_COLORS, SceneOptions, log_motion, segment_meshes
from pipeline.viz.recording import entity_row_counts, read_entities

N = 3000
NAN_ROW = 17  # one configuration with a NaN: not logged
SEGMENTS = ("pelvis", "right_femur", "right_tibia", "right_foot", "left_femur", "left_tibia")
SEGMENTS += ("left_foot",)


def _rows(path: Path, entity: str, static: bool = False) -> dict[str, list]:
    """Rows of one entity (temporal or static chunks), component name -> list of values."""
    from rerun.chunk import RrdReader

    out: dict[str, list] = {}
    for c in RrdReader(path).stream().to_chunks():
        if c.entity_path != entity or c.is_static != static:
            continue
        rb = c.to_record_batch()
        for name in rb.schema.names:
            out.setdefault(name, []).extend(rb.column(name).to_pylist())
    return out


def _first(rows: dict[str, list], component: str) -> np.ndarray:
    """Per row, the first instance of a component: (rows, ...)."""
    return np.array([v[0] for v in rows[component]])


@pytest.fixture(scope="module")
def motion(tmp_path_factory):
    folder = tmp_path_factory.mktemp("viz_model")
    sk = Skeleton.build(SubjectGeometry.default(1.75, "m", "right"), knee="free")
    t = np.arange(N) / 100.0
    Q = np.tile(sk.neutral(), (N, 1))
    for side, lag in (("right", 0.0), ("left", np.pi)):
        Q[:, sk.q_index(f"{side}_hip_Z")] = 0.5 * np.sin(t + lag)
        Q[:, sk.q_index(f"{side}_hip_X")] = 0.1 * np.sin(2 * t)
        Q[:, sk.q_index(f"{side}_knee_Z")] = 0.6 + 0.5 * np.sin(t + lag)
        Q[:, sk.q_index(f"{side}_knee_Y")] = 0.1 * np.cos(t)
        Q[:, sk.q_index(f"{side}_ankle_Z")] = 0.2 * np.sin(3 * t)
    Q[NAN_ROW, 3] = np.nan
    ref = {"right_EFM": np.zeros((N, 3)) + [0.1, -0.4, 0.1]}
    extra = {"residual/right_knee": np.linspace(0.0, 1.0, N)}
    path = folder / "motion.rrd"
    import rerun  # noqa: F401  (import time is not logging time)

    elapsed = []
    for _ in range(2):  # the first call pays rerun's lazy initialisation and loads the STLs
        start = time.perf_counter()
        log_motion(path, t, sk, Q, SceneOptions(reference_landmarks=ref, extra_scalars=extra,
                                                recording_name="synthetic gait"))
        elapsed.append(time.perf_counter() - start)
    print(f"\nlog_motion, {N} frames, two legs: first {elapsed[0]:.3f} s, then {elapsed[1]:.3f} s")
    ok = np.ones(N, dtype=bool)
    ok[NAN_ROW] = False
    return path, sk, t, Q, ok, elapsed[1]


def test_entity_layout_and_rows(motion):
    path, sk, _, _, _, elapsed = motion
    counts = entity_row_counts(path)
    assert set(read_entities(path)) == set(counts)
    for seg in SEGMENTS:
        assert counts[f"/world/model/{seg}"] == N - 1, seg  # the NaN row is skipped
        assert counts[f"/world/model/{seg}/mesh"] == 0  # static
    for name in sk.landmark_frames:
        assert counts[f"/world/landmarks/{name}"] == N - 1, name
    assert len(sk.landmark_frames) == 22 and len(sk.imu_frames) == 7
    for name in sk.imu_frames:
        assert counts[f"/world/imus/{name}"] == N - 1, name
    for side in ("right", "left"):
        assert counts[f"/world/bones/{side}"] == N - 1
        for joint in ("hip", "knee"):
            for angle in ("flexion", "adduction", "rotation"):
                assert counts[f"/plots/{side}_{joint}/{angle}"] == N - 1
    assert counts["/world/reference/right_EFM"] == N
    assert counts["/world/errors/right_EFM"] == N - 1
    assert counts["/plots/residual/right_knee"] == N
    assert counts["/world"] == 0


def test_up_axis_view_coordinates(motion, tmp_path):
    import rerun as rr

    path = motion[0]
    xyz = _rows(path, "/world", static=True)["ViewCoordinates:xyz"][0][0]
    assert xyz == rr.ViewCoordinates.RIGHT_HAND_Y_UP.as_arrow_array().to_pylist()[0]
    sk, t, Q = motion[1], motion[2][:4], motion[3][:4]
    z_up = log_motion(tmp_path / "z.rrd", t, sk, Q, SceneOptions(up_axis="z", meshes=False))
    xyz = _rows(z_up, "/world", static=True)["ViewCoordinates:xyz"][0][0]
    assert xyz == rr.ViewCoordinates.RIGHT_HAND_Z_UP.as_arrow_array().to_pylist()[0]


def test_meshes_have_vertices_in_metres(motion):
    path, sk = motion[0], motion[1]
    for seg in SEGMENTS:
        rows = _rows(path, f"/world/model/{seg}/mesh", static=True)
        v = np.array(rows["Mesh3D:vertex_positions"][0])
        tri = np.array(rows["Mesh3D:triangle_indices"][0])
        normals = np.array(rows["Mesh3D:vertex_normals"][0])
        assert len(v) > 1000 and len(tri) > 2000, seg
        assert tri.min() == 0 and tri.max() == len(v) - 1
        np.testing.assert_allclose(np.linalg.norm(normals, axis=1), 1.0, atol=1e-4)
        assert np.ptp(v, axis=0).max() < 0.6, seg  # metres, not the STL's millimetre-like units
    g = SubjectGeometry.default(1.75, "m", "right")
    femur = np.array(
        _rows(path, "/world/model/right_femur/mesh", True)["Mesh3D:vertex_positions"][0]
    )
    # The thigh mesh spans the thigh along the femoral y axis: from near the HJC (the segment
    # origin) down to near the knee centre.
    assert abs(np.ptp(femur[:, 1]) - g.thigh_length) < 0.1 * g.thigh_length
    assert abs(femur[:, 1].min() - g.kjc_femur[1]) < 0.05
    assert abs(femur[:, 1].max()) < 0.05
    tibia = segment_meshes(sk)["right_tibia"].vertices
    assert abs(tibia[:, 1].min() - g.ajc_tibia[1]) < 0.05  # shank mesh reaches the ankle


def test_transforms_reproduce_forward_kinematics(motion):
    path, sk, t, Q, ok, _ = motion
    rows_t = np.flatnonzero(ok)
    for seg in ("pelvis", "right_tibia", "left_femur", "left_foot"):
        rows = _rows(path, f"/world/model/{seg}")
        xyzw = _first(rows, "Transform3D:quaternion")
        p = _first(rows, "Transform3D:translation")
        assert len(p) == N - 1
        for k in (0, 250, 1234, N - 1):
            i = np.searchsorted(rows_t, k)
            T = sk.forward(Q[k]).frame_pose(seg)
            np.testing.assert_allclose(
                matrix_from_quat(xyzw[i, [3, 0, 1, 2]]), T[:3, :3], atol=1e-5
            )
            np.testing.assert_allclose(p[i], T[:3, 3], atol=1e-6)
    times = [d.total_seconds() for d in _rows(path, "/world/model/pelvis")["time"]]
    np.testing.assert_allclose(times, t[ok], atol=1e-6)


def test_landmarks_bones_imus_and_errors(motion):
    path, sk, _, Q, ok, _ = motion
    rows_t = np.flatnonzero(ok)
    efl = _first(_rows(path, "/world/landmarks/left_EFL"), "Points3D:positions")
    strips = np.array([s[0] for s in _rows(path, "/world/bones/right")["LineStrips3D:strips"]])
    assert strips.shape == (N - 1, 3, 3)
    imu = _first(_rows(path, "/world/imus/right_tibia_imu"), "Transform3D:translation")
    arrows = _rows(path, "/world/errors/right_EFM")
    origin, vector = _first(arrows, "Arrows3D:origins"), _first(arrows, "Arrows3D:vectors")
    efm = _first(_rows(path, "/world/landmarks/right_EFM"), "Points3D:positions")
    for k in (3, 999, N - 2):
        i = np.searchsorted(rows_t, k)
        sk.forward(Q[k])
        np.testing.assert_allclose(efl[i], sk.frame_position("left_EFL"), atol=1e-6)
        hka = [sk.frame_position(f"right_{j}") for j in ("HJC", "KJC", "AJC")]
        np.testing.assert_allclose(strips[i], hka, atol=1e-6)
        np.testing.assert_allclose(imu[i], sk.frame_position("right_tibia_imu"), atol=1e-6)
    np.testing.assert_allclose(origin, np.tile([0.1, -0.4, 0.1], (N - 1, 1)), atol=1e-6)
    np.testing.assert_allclose(origin + vector, efm, atol=1e-6)
    static = _rows(path, "/world/landmarks/left_EFL", static=True)
    assert static["Points3D:labels"] == [["left_EFL"]]


def test_joint_angle_plots_in_degrees(motion):
    path, sk, _, Q, ok, _ = motion
    expected = joint_angles(sk, Q[ok])
    for key in ("right_knee_flexion", "left_hip_adduction", "left_knee_rotation"):
        joint, angle = key.rsplit("_", 1)
        y = _first(_rows(path, f"/plots/{joint}/{angle}"), "Scalars:scalars")
        np.testing.assert_allclose(y, np.degrees(expected[key]), atol=1e-9)
    # Knee flexion q_Z = 0.6 + 0.5 sin(t) (free knee, ISB JCS): the plot peaks near 63 deg.
    knee = _first(_rows(path, "/plots/right_knee/flexion"), "Scalars:scalars")
    assert abs(knee.max() - np.degrees(1.1)) < 0.5
    extra = _first(_rows(path, "/plots/residual/right_knee"), "Scalars:scalars")
    np.testing.assert_allclose(extra, np.linspace(0.0, 1.0, N), atol=1e-12)


def test_segment_meshes_apply_scale_origin_and_mirroring(tmp_path):
    """A hand-checkable URDF: one triangle, visual origin Rz(90 deg) + p, scale (2, 1, -1)."""
    import trimesh

    tri = trimesh.Trimesh(
        vertices=[[0, 0, 0], [1, 0, 0], [0, 1, 0]], faces=[[0, 1, 2]], process=False
    )
    tri.export(tmp_path / "tri.stl")
    urdf = tmp_path / "one.urdf"
    urdf.write_text(
        '<robot name="one"><link name="pelvis"><visual><origin xyz="0.1 0.2 0.3" '
        'rpy="0 0 1.5707963267948966"/><geometry><mesh filename="tri.stl" scale="2 1 -1"/>'
        "</geometry></visual></link></robot>"
    )
    mesh = segment_meshes(Skeleton.from_urdf(urdf))["pelvis"]
    expected = (np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]]) * [2, 1, -1]) @ rot_z(np.pi / 2).T
    np.testing.assert_allclose(mesh.vertices, expected + [0.1, 0.2, 0.3], atol=1e-6)
    # The scale mirrors (det < 0): the winding is reversed, so the normal is Rz(90) M (0,0,1).
    a, b, c = mesh.vertices[mesh.triangles[0]]
    n = np.cross(b - a, c - a)
    np.testing.assert_allclose(n / np.linalg.norm(n), [0, 0, -1], atol=1e-9)
    np.testing.assert_allclose(mesh.normals, np.tile([0, 0, -1.0], (3, 1)), atol=1e-9)


def test_bad_inputs_are_input_errors(motion, tmp_path):
    _, sk, t, Q, _, _ = motion
    with pytest.raises(InputError, match="Q"):
        log_motion(tmp_path / "a.rrd", t[:10], sk, Q[:9])
    assert not (tmp_path / "a.rrd").exists()
    with pytest.raises(InputError, match="landmarks"):
        log_motion(tmp_path / "b.rrd", t[:10], sk, Q[:10], SceneOptions(landmarks=["right_XYZ"]))
    with pytest.raises(InputError, match="up_axis"):
        log_motion(tmp_path / "c.rrd", t[:10], sk, Q[:10],
                   SceneOptions(up_axis="x", meshes=False))
    assert not (tmp_path / "c.rrd").exists()


def test_default_layout_3d_view_and_one_plot_per_joint(motion):
    path, sk, _, Q, ok, _ = motion
    bp = read_blueprint(path)
    views = blueprint_views(bp)
    assert views["3D"][:2] == ("3D", "/world")
    for side in ("right", "left"):
        for joint in ("hip", "knee"):
            assert views[f"{side} {joint} (deg)"][:2] == ("TimeSeries", f"/plots/{side}_{joint}")
    assert views["other"][0] == "TimeSeries"
    other = bp[f"{views['other'][2]}/ViewContents"]["ViewContents:query"]
    assert other == ["/plots/residual/right_knee"]
    # The line grid lies on the ground: the lowest point any foot-mesh vertex reaches.
    grid = bp[f"{views['3D'][2]}/LineGrid3D"]["LineGrid3D:plane"][0]
    lowest = np.inf
    for k in np.flatnonzero(ok)[::97]:
        sk.forward(Q[k])
        for side in ("right", "left"):
            T = sk.frame_pose(f"{side}_foot")
            v = segment_meshes(sk)[f"{side}_foot"].vertices
            lowest = min(lowest, (v @ T[:3, :3].T + T[:3, 3])[:, 1].min())
    np.testing.assert_allclose(grid[:3], [0.0, 1.0, 0.0])
    assert lowest - 0.005 < grid[3] <= lowest + 1e-6  # frames in between may reach lower
    # The camera looks at the legs from the front (+x) right (+z), above, y up.
    eye = bp[f"{views['3D'][2]}/EyeControls3D"]
    target, position = (
        np.array(eye["EyeControls3D:look_target"][0]),
        np.array(eye["EyeControls3D:position"][0]),
    )
    np.testing.assert_allclose(eye["EyeControls3D:eye_up"][0], [0.0, 1.0, 0.0])
    assert grid[3] < target[1] < 0.0
    offset = position - target
    assert offset[0] > 0.0 and offset[2] > 0.0 and offset[1] > 0.0
    assert 1.0 < np.linalg.norm(offset) < 3.0


def test_angle_colours_and_translucent_meshes(motion):
    path = motion[0]
    for joint in ("right_hip", "left_knee"):
        for angle in ("flexion", "adduction", "rotation"):
            rgb = ANGLE_COLORS[angle]
            style = _rows(path, f"/plots/{joint}/{angle}", static=True)
            assert style["SeriesLines:names"] == [[angle]]
            r, g, b = rgb
            assert style["SeriesLines:colors"] == [[(r << 24) | (g << 16) | (b << 8) | 0xFF]]
    albedo = _rows(path, "/world/model/left_tibia/mesh", static=True)["Mesh3D:albedo_factor"]
    assert 0 < (albedo[0][0] & 0xFF) < 255  # landmarks, bones and IMU axes show through


def test_recording_opens_playing_from_the_start_in_a_loop(motion):
    """The time panel of the default blueprint: 'time' timeline, playing, looping over all."""
    from rerun.blueprint.components import LoopMode, PlayState

    panel = read_blueprint(motion[0])["/time_panel"]
    assert panel["TimePanelBlueprint:timeline"] == ["time"]
    assert panel["TimePanelBlueprint:play_state"] == [PlayState.Playing.value]
    assert panel["TimePanelBlueprint:loop_mode"] == [LoopMode.All.value]


def test_a_body_that_walks_through_the_room(motion, tmp_path):
    """With a root path (4 m along x, swaying 0.3 m along z), the recording draws the pelvis's
    path on the floor and each foot's footprints (static), and the camera frames the whole walk
    from across its main direction, raised 30 deg; a body that stays put has neither."""
    from pipeline.viz.scene import ROOM_DISTANCE, ROOM_ELEVATION_DEG

    _, sk, t, Q, _, _ = motion
    n = len(t)
    root = np.zeros((n, 3))
    root[:, 0] = np.clip(t - 2.0, 0.0, 4.0)
    root[:, 2] = 0.15 * np.sin(2 * t)
    prints = np.full((n, 3), np.nan)
    prints[500:1500], prints[1500:] = [1.0, -0.9, 0.1], [2.5, -0.9, 0.1]
    path = log_motion(tmp_path / "walk.rrd", t, sk, Q, SceneOptions(
        root_path=root, landmarks=False, reference_landmarks={"right_footprint": prints}))
    strip = np.array(_rows(path, "/world/walk/path", static=True)["LineStrips3D:strips"][0][0])
    footprints = np.array(_rows(path, "/world/walk/right_footprints", static=True)[
        "Points3D:positions"][0])
    np.testing.assert_allclose(footprints, [[1.0, -0.9, 0.1], [2.5, -0.9, 0.1]])
    assert np.ptp(strip[:, 1]) == 0.0  # on the floor
    assert np.ptp(strip[:, 0]) > 3.9 and np.ptp(strip[:, 2]) > 0.29
    views = blueprint_views(bp := read_blueprint(path))
    eye = bp[f"{views['3D'][2]}/EyeControls3D"]
    target = np.array(eye["EyeControls3D:look_target"][0])
    offset = np.array(eye["EyeControls3D:position"][0]) - target
    assert abs(target[0] - 2.0) < 0.1  # the middle of the path along its main direction (x)
    up = np.degrees(np.arcsin(offset[1] / np.linalg.norm(offset)))
    assert abs(up - ROOM_ELEVATION_DEG) < 0.1 and abs(offset[0]) < 0.05 * np.linalg.norm(offset)
    assert np.linalg.norm(offset) == pytest.approx(ROOM_DISTANCE * 4.0, rel=0.05)
    assert not [e for e in entity_row_counts(motion[0]) if e.startswith("/world/walk")]
