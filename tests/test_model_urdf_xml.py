"""Tests of pipeline.model.urdf_xml: the URDF writer against yourdfpy's writer (byte for byte) and
reader (element by element), and the rpy convention by hand."""

from __future__ import annotations

import numpy as np
import pytest
import yourdfpy as ud
from lxml import etree

import pipeline.model.builder as builder
from pipeline.model.builder import urdf_object, urdf_text
from pipeline.model.geometry import SubjectGeometry
from pipeline.model.urdf_xml import rpy_from_matrix
from pipeline.rotations import exp3, matrix_from_euler_xyz_fixed


def test_rpy_by_hand_and_round_trip():
    assert rpy_from_matrix(np.eye(4)) == (0.0, -0.0, 0.0)  # trimesh's signs: "0.0 -0.0 0.0"
    r = np.array([0.3, -1.1, 2.0])
    np.testing.assert_allclose(rpy_from_matrix(matrix_from_euler_xyz_fixed(r)), r, atol=1e-14)
    # pitch at +-pi/2: roll and yaw are not separable; the rotation is still rebuilt
    R = matrix_from_euler_xyz_fixed(np.array([0.4, np.pi / 2, -0.2]))
    np.testing.assert_allclose(matrix_from_euler_xyz_fixed(np.array(rpy_from_matrix(R))), R,
                               atol=1e-12)


def _yourdfpy_text(name, links, joints, materials) -> str:
    """The same robot through yourdfpy's object model and writer."""

    def inertial(i):
        return None if i is None else ud.Inertial(origin=i.origin, mass=i.mass, inertia=i.inertia)

    def visual(v):
        mesh = ud.Geometry(mesh=ud.Mesh(filename=v.filename, scale=v.scale))
        return ud.Visual(name=v.name, origin=v.origin, geometry=mesh,
                         material=ud.Material(name=v.material.name))

    def joint(j):
        lim = None if j.limit is None else ud.Limit(*j.limit)
        return ud.Joint(name=j.name, type=j.type, parent=j.parent, child=j.child,
                        origin=j.origin, axis=j.axis, limit=lim)

    robot = ud.Robot(
        name=name,
        links=[ud.Link(name=k.name, inertial=inertial(k.inertial),
                       visuals=[visual(v) for v in k.visuals]) for k in links],
        joints=[joint(j) for j in joints],
    )
    robot.materials = [ud.Material(name=m.name, color=ud.Color(rgba=np.array(m.rgba)))
                       for m in materials]
    urdf = ud.URDF(robot=robot, build_scene_graph=False, load_meshes=False, filename_handler=str)
    return etree.tostring(urdf.write_xml(), xml_declaration=True, pretty_print=True).decode("ascii")


@pytest.mark.parametrize(("knee", "legs"), [("free", ("right", "left")), ("hinge", ("left",))])
def test_text_is_yourdfpys_byte_for_byte(monkeypatch, knee, legs):
    seen = {}
    original = builder.urdf_xml

    def spy(*args):
        seen["args"] = args
        return original(*args)

    monkeypatch.setattr(builder, "urdf_xml", spy)
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = exp3(np.array([0.3, -1.2, 0.5])), [0.01, -0.2, 0.05]
    text = urdf_text(SubjectGeometry.default(), knee=knee, legs=legs,
                     imu_placements={f"{legs[0]}_tibia_imu": T})
    assert text == _yourdfpy_text(*seen["args"])


def test_yourdfpy_reads_back_every_element():
    g = SubjectGeometry.default()
    text = urdf_text(g, knee="hinge")
    u = urdf_object(text)
    assert u.robot.name == "lower_limb_hinge_knee_ISB_model"
    joints = {j.name: j for j in u.robot.joints}
    knee = joints["right_knee"]
    assert (knee.type, knee.parent, knee.child) == ("revolute", "right_femur", "right_tibia")
    np.testing.assert_allclose(knee.origin[:3, 3], g.for_side("right").kjc_femur, atol=1e-15)
    np.testing.assert_allclose(knee.axis, -g.for_side("right").knee_axis_tibia, atol=1e-15)
    assert knee.limit.lower == 0.0
    links = {k.name: k for k in u.robot.links}
    assert links["right_tibia"].inertial.mass > 0
    assert [v.geometry.mesh.filename.rsplit("/", 1)[1] for v in links["right_tibia"].visuals] == [
        "lowerleg_mesh.STL", "knee_mesh.STL"]
    assert {m.name for m in u.robot.materials} == {"body_color", "body_color_R", "body_color_L"}
