"""The URDF elements the subject model uses, and their XML text (the one URDF writer).

Why not yourdfpy's object model and writer, which this module replaced: importing yourdfpy imports
trimesh and SciPy's spatial package, ~0.8 s, a fifth of a whole ``pipeline ik`` run, for a file
whose elements are a fixed, small set. The text is the same, byte for byte, as yourdfpy's
``URDF.write_xml`` through lxml (ASCII declaration, pretty-printed; elements in yourdfpy's order;
numbers as Python's shortest ``str``; an origin's ``rpy`` as ``trimesh.transformations.
euler_from_matrix`` computes it, static X-Y-Z): ``tests/test_model_urdf_xml.py`` reads every model
variant back with yourdfpy and checks it element by element. yourdfpy remains the way to edit a
model in Python (:func:`pipeline.model.builder.urdf_object`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from lxml import etree

__all__ = [
    "Inertial",
    "Joint",
    "Link",
    "Material",
    "Visual",
    "rpy_from_matrix",
    "urdf_xml",
]

_EPS = float(np.finfo(float).eps) * 4.0
_INERTIA = (("ixx", (0, 0)), ("ixy", (0, 1)), ("ixz", (0, 2)), ("iyy", (1, 1)), ("iyz", (1, 2)),
            ("izz", (2, 2)))


@dataclass(frozen=True)
class Material:
    """A named material, with an RGBA colour where it is defined."""

    name: str
    rgba: tuple[float, ...] | None = None


@dataclass(frozen=True)
class Visual:
    """A mesh visual: ``filename`` (URI), ``scale`` (3,), ``origin`` 4x4 in the link frame."""

    name: str
    filename: str
    scale: np.ndarray
    origin: np.ndarray
    material: Material


@dataclass(frozen=True)
class Inertial:
    origin: np.ndarray  # 4x4, the centre of mass frame in the link frame
    mass: float
    inertia: np.ndarray  # 3x3, about the centre of mass


@dataclass(frozen=True)
class Link:
    name: str
    inertial: Inertial | None = None
    visuals: list[Visual] = field(default_factory=list)


@dataclass(frozen=True)
class Joint:
    """``type`` 'revolute' (``axis`` (3,) and ``limit`` (effort, velocity, lower, upper)) or
    'fixed'; ``origin`` 4x4, the child frame in the parent's."""

    name: str
    type: str
    parent: str
    child: str
    origin: np.ndarray
    axis: np.ndarray | None = None
    limit: tuple[float, float, float, float] | None = None


def rpy_from_matrix(T: np.ndarray) -> tuple[float, float, float]:
    """URDF ``rpy`` (static X-Y-Z: ``R = Rz(y) Ry(p) Rx(r)``) of a rotation or 4x4 transform,
    with trimesh's branch for ``cos(pitch) ~ 0`` and its signs (the identity gives
    ``(0.0, -0.0, 0.0)``)."""
    M = np.asarray(T, dtype=float)[:3, :3]
    # NumPy's arctan2 and sqrt, as trimesh calls them: they may round differently from libm's
    # (NumPy 2.4 does in the last digit), and the text is to be the same byte for byte
    atan2 = np.arctan2
    cy = np.sqrt(M[0, 0] * M[0, 0] + M[1, 0] * M[1, 0])
    if cy > _EPS:
        return (float(atan2(M[2, 1], M[2, 2])), float(atan2(-M[2, 0], cy)),
                float(atan2(M[1, 0], M[0, 0])))
    return float(atan2(-M[1, 2], M[1, 1])), float(atan2(-M[2, 0], cy)), 0.0


def _num(values) -> str:
    return " ".join(str(float(v)) for v in values)


def _origin(parent, T: np.ndarray) -> None:
    etree.SubElement(parent, "origin", attrib={"xyz": _num(np.asarray(T)[:3, 3]),
                                                "rpy": _num(rpy_from_matrix(T))})


def _material(parent, m: Material) -> None:
    el = etree.SubElement(parent, "material", attrib={"name": m.name})
    if m.rgba is not None:
        etree.SubElement(el, "color", attrib={"rgba": _num(m.rgba)})


def _link(robot, link: Link) -> None:
    el = etree.SubElement(robot, "link", attrib={"name": link.name})
    if link.inertial is not None:
        i = etree.SubElement(el, "inertial")
        _origin(i, link.inertial.origin)
        etree.SubElement(i, "mass", attrib={"value": str(float(link.inertial.mass))})
        J = link.inertial.inertia
        etree.SubElement(i, "inertia", attrib={k: str(float(J[a, b])) for k, (a, b) in _INERTIA})
    for v in link.visuals:
        ve = etree.SubElement(el, "visual", attrib={"name": v.name})
        g = etree.SubElement(ve, "geometry")
        etree.SubElement(g, "mesh", attrib={"filename": v.filename, "scale": _num(v.scale)})
        _origin(ve, v.origin)
        _material(ve, v.material)


def _joint(robot, joint: Joint) -> None:
    el = etree.SubElement(robot, "joint", attrib={"name": joint.name, "type": joint.type})
    etree.SubElement(el, "parent", attrib={"link": joint.parent})
    etree.SubElement(el, "child", attrib={"link": joint.child})
    _origin(el, joint.origin)
    if joint.axis is not None:
        etree.SubElement(el, "axis", attrib={"xyz": _num(joint.axis)})
    if joint.limit is not None:
        keys = ("effort", "velocity", "lower", "upper")
        etree.SubElement(el, "limit", attrib={k: str(float(v)) for k, v in zip(keys, joint.limit,
                                                                              strict=True)})


def urdf_xml(name: str, links: list[Link], joints: list[Joint], materials: list[Material]) -> str:
    """The URDF text of a robot: links, then joints, then materials (yourdfpy's order)."""
    robot = etree.Element("robot", attrib={"name": name})
    for link in links:
        _link(robot, link)
    for joint in joints:
        _joint(robot, joint)
    for m in materials:
        _material(robot, m)
    tree = etree.ElementTree(robot)
    return etree.tostring(tree, xml_declaration=True, pretty_print=True).decode("ascii")
