"""URDF mesh visuals (pipeline.model.meshes): template STL references, scaling, left-leg mirror."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import yourdfpy
from _helpers import MIRROR, asymmetric_subject

from pipeline.model import Skeleton, build_urdf
from pipeline.model.meshes import resolve_package_uri


def test_resolve_package_uri_maps_to_the_share_folder():
    from pipeline.model.resources import example_robot_data_share

    uri = "package://example-robot-data/robots/human_description/meshes/foot_mesh.STL"
    expected = example_robot_data_share().parent / uri[len("package://") :]
    assert resolve_package_uri(uri) == expected
    assert str(resolve_package_uri("/abs/file.stl")) == "/abs/file.stl"


def test_mesh_references_resolve_and_follow_template_style(tmp_path):
    path = build_urdf(asymmetric_subject(), tmp_path / "m.urdf", knee="hinge")
    urdf = yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)
    meshes = [v.geometry.mesh for link in urdf.robot.links for v in link.visuals]
    assert len(meshes) == 1 + 2 * 4  # pelvis + (thigh, shank, knee, foot) per leg
    for mesh in meshes:
        assert mesh.filename.startswith(
            "package://example-robot-data/robots/human_description/meshes/"
        )
        assert resolve_package_uri(mesh.filename).is_file(), mesh.filename
    for link in urdf.robot.links:  # right leg and pelvis as the template; left leg z-mirrored
        for v in link.visuals:
            sign = [1.0, 1.0, -1.0] if link.name.startswith("left") else [1.0, 1.0, 1.0]
            assert np.all(np.asarray(v.geometry.mesh.scale) * sign > 0), link.name


# ---- mesh handedness ----------------------------------------------------------------------------
def _visual_vertices(urdf: yourdfpy.URDF, link: str) -> np.ndarray:
    """A link's visual mesh vertices in the link (segment) frame: ``R_o (s * v) + p_o``."""
    import trimesh

    out = []
    for visual in urdf.link_map[link].visuals:
        mesh = visual.geometry.mesh
        v = trimesh.load(resolve_package_uri(mesh.filename), force="mesh").vertices
        T = visual.origin
        out.append((v * np.asarray(mesh.scale)) @ T[:3, :3].T + T[:3, 3])
    return np.concatenate(out)


@pytest.fixture(scope="module")
def mesh_urdf(tmp_path_factory):
    path = build_urdf(
        asymmetric_subject(), tmp_path_factory.mktemp("meshes") / "m.urdf", knee="free"
    )
    return path, yourdfpy.URDF.load(str(path), build_scene_graph=False, load_meshes=False)


def test_left_leg_meshes_are_mirror_images_of_right_ones(mesh_urdf):
    """Symmetric subject: every left-leg mesh vertex is M = diag(1, 1, -1) times the right one."""
    _, urdf = mesh_urdf
    for seg in ("femur", "tibia", "foot"):
        right = _visual_vertices(urdf, f"right_{seg}")
        left = _visual_vertices(urdf, f"left_{seg}")
        assert np.ptp(right[:, 2]) > 0.05  # a real mesh, several cm wide
        np.testing.assert_allclose(left, right @ MIRROR, rtol=0, atol=1e-9, err_msg=seg)


def test_femur_mesh_shaft_lies_lateral_of_its_proximal_cap_on_both_legs(mesh_urdf):
    """The template thigh mesh is a stylised, nearly z-symmetric shape; its one handed feature
    (found by inspecting upperleg_mesh.STL slice by slice) is that the whole shaft is shifted by
    ~1.1 mm x (knee-width scale) to +z, lateral for a right leg, relative to its rounded proximal
    cap (centred on z = 0), as a femoral shaft lies lateral of the head. That direction must be
    lateral on both legs, i.e. along EFL - EFM taken from the landmark frames (before the mirror
    fix the left shaft was shifted medially)."""
    path, urdf = mesh_urdf
    sk = Skeleton.from_urdf(path)
    q = sk.neutral()

    def z_mid(v):
        return 0.5 * (v[:, 2].min() + v[:, 2].max())

    for side in ("right", "left"):
        v = _visual_vertices(urdf, f"{side}_femur")
        y, h = v[:, 1], np.ptp(v[:, 1])
        cap = v[y > y.max() - 0.05 * h]
        shaft = v[(y > y.min() + 0.2 * h) & (y < y.min() + 0.8 * h)]
        efm = sk.relative_pose(f"{side}_EFM", f"{side}_femur", q)[:3, 3]
        efl = sk.relative_pose(f"{side}_EFL", f"{side}_femur", q)[:3, 3]
        lateral = np.sign(efl[2] - efm[2])
        assert lateral == (1.0 if side == "right" else -1.0)
        offset = z_mid(shaft) - z_mid(cap)
        assert 0.0005 < lateral * offset < 0.002, (side, offset)
        assert lateral * v[:, 2].mean() > 0  # the bulk of the thigh mesh is lateral too


def test_mirrored_meshes_load_in_pinocchio_and_render_outward(mesh_urdf):
    """pin.buildGeomFromUrdf accepts the negative z scale (vertices mirrored), and the viewer's
    merged meshes keep outward normals (positive signed volume, normals mirrored) on the left."""
    import trimesh

    from pipeline.model.resources import example_robot_data_share
    from pipeline.viz.model import segment_meshes

    path, _ = mesh_urdf
    model = pin.buildModelFromUrdf(str(path))
    share = str(example_robot_data_share().parent)
    geom = pin.buildGeomFromUrdf(model, str(path), pin.GeometryType.VISUAL, package_dirs=[share])
    assert geom.ngeoms == 1 + 2 * 4

    def placed(name):
        obj = geom.geometryObjects[geom.getGeometryId(name)]
        v = np.asarray(obj.geometry.vertices())
        return v @ obj.placement.rotation.T + obj.placement.translation, np.asarray(obj.meshScale)

    for seg in ("femur", "tibia", "foot"):
        (right, s_r), (left, s_l) = placed(f"right_{seg}_0"), placed(f"left_{seg}_0")
        np.testing.assert_allclose(s_l, s_r * [1.0, 1.0, -1.0])
        np.testing.assert_allclose(left, right @ MIRROR, rtol=0, atol=1e-9)

    meshes = segment_meshes(Skeleton.from_urdf(path))
    for seg in ("femur", "tibia", "foot"):
        right, left = meshes[f"right_{seg}"], meshes[f"left_{seg}"]
        np.testing.assert_allclose(left.vertices, right.vertices @ MIRROR, atol=1e-9)
        np.testing.assert_allclose(left.normals, right.normals @ MIRROR, atol=1e-9)
        vol = [
            trimesh.Trimesh(m.vertices, m.triangles, process=False).volume for m in (right, left)
        ]
        assert vol[0] > 1e-4 and vol[1] == pytest.approx(vol[0], rel=1e-9), seg


def test_scaled_normals_by_the_inverse_transpose():
    """A mesh scaled unevenly keeps normals perpendicular to its faces: the template's vertex
    normals carried by the inverse transpose stay close to the scaled mesh's own."""
    from pipeline.io.stl import vertex_normals
    from pipeline.model.geometry import SubjectGeometry
    from pipeline.model.skeleton import Skeleton
    from pipeline.viz.model import segment_meshes

    sk = Skeleton.build(SubjectGeometry.default(1.95, "m"), "hinge")
    for seg, mesh in segment_meshes(sk).items():
        own = vertex_normals(mesh.vertices, mesh.triangles)
        cos = np.einsum("ij,ij->i", mesh.normals, own)
        assert np.median(cos) > 0.999 and np.percentile(cos, 5) > 0.97, seg
