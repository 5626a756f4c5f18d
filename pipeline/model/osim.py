"""The subject's model as an OpenSim model (``.osim``, OpenSim 4 XML) whose coordinates are exactly
the columns of the ``.mot`` that ``pipeline ik`` writes, so model and motion open together in
OpenSim's GUI.

Bodies ``pelvis``, ``femur_r``, ``tibia_r``, ``calcn_r`` (and ``_l``) carry the mass properties of
the Pinocchio model (Dumas 2007, scaled) and its meshes; their frames are our ISB segment frames
(x anterior, y proximal, z right on both legs, as in OpenSim's gait models). The landmarks are
markers (``right_EFM``, ...). An observed joint is a ``CustomJoint`` whose body-fixed rotations
reproduce our joint coordinate system (:mod:`pipeline.analysis.landmarks`), with ``L = +1`` right
and ``-1`` left:

=================  ===================================================================
joint              rotation1, rotation2, rotation3 (coordinate: axis in the parent frame)
=================  ===================================================================
``ground_pelvis``  pelvis_tilt (0 0 1), pelvis_list (1 0 0), pelvis_rotation (0 1 0);
                   translations pelvis_tx, pelvis_ty, pelvis_tz (m, along the ground's x, y, z)
``hip_r``          hip_flexion (0 0 1), hip_adduction (L 0 0), hip_rotation (0 L 0)
``knee_r``         knee_angle (0 0 -1), knee_adduction (L 0 0), knee_rotation (0 L 0)
``ankle_r``        ankle_angle (0 0 1), subtalar_angle (L 0 0), (none) (0 1 0)
=================  ===================================================================

so that ``R_parent^T R_child = Rz(a) Rx(b) Ry(c)`` with the ``.mot``'s angles, whatever the knee
model of the run (a hinge knee's motion is exactly its JCS angles). Joints the sensors do not
observe are ``WeldJoint``s in the neutral pose, and without a pelvis sensor each femur is welded
to the ground at its hip centre (the ``.mot`` then has no hip or pelvis angle). The ground is the
heading frame of the calibration pose (``pelvis_*`` angles and ``pelvis_t*`` are in it), y up.
``ground_pelvis`` is free, as in OpenSim's gait models: the ``.mot``'s pelvis path (a walk with
a foot sensor on each foot) moves the body through the room; without one the pelvis stays at its
default, the height that puts the standing feet on the floor (``y = 0``). The knee has its three
rotations (flexion, ab/adduction, rotation), as the ``.mot`` does: a model replaying our ``.mot``
needs no coordinate the ``.osim`` lacks.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import NamedTuple

import numpy as np
from lxml import etree

from pipeline.model.conventions import LANDMARK_SEGMENT
from pipeline.model.meshes import resolve_package_uri
from pipeline.model.skeleton import Skeleton

__all__ = ["OSIM_BODIES", "PELVIS_TRANSLATIONS", "osim_text"]

#: Our segment -> OpenSim body name (``calcn``: the foot, as OpenSense's ``calcn_r_imu``).
OSIM_BODIES = {"femur": "femur", "tibia": "tibia", "foot": "calcn"}
_JOINTS = {  # joint -> (proximal, distal, [(coordinate, axis with L for the side), ...])
    "hip": ("pelvis", "femur", [("hip_flexion", (0, 0, 1)), ("hip_adduction", ("L", 0, 0)),
                                ("hip_rotation", (0, "L", 0))]),
    "knee": ("femur", "tibia", [("knee_angle", (0, 0, -1)), ("knee_adduction", ("L", 0, 0)),
                                ("knee_rotation", (0, "L", 0))]),
    "ankle": ("tibia", "foot", [("ankle_angle", (0, 0, 1)), ("subtalar_angle", ("L", 0, 0)),
                                (None, (0, 1, 0))]),
}
_PELVIS = [("pelvis_tilt", (0, 0, 1)), ("pelvis_list", (1, 0, 0)), ("pelvis_rotation", (0, 1, 0))]


def _body(segment: str) -> str:
    if segment == "pelvis":
        return "pelvis"
    side, seg = segment.split("_", 1)
    return f"{OSIM_BODIES[seg]}_{side[0]}"


def _vec(v) -> str:
    return " ".join(repr(float(x)) for x in v)


def _sub(parent, tag: str, text: object | None = None, **attrib: str):
    e = etree.SubElement(parent, tag, **attrib)
    if text is not None:
        e.text = text if isinstance(text, str) else _vec(text)
    return e


def osim_text(
    skeleton: Skeleton, joints: Sequence[str], *, pelvis: bool, name: str = "subject"
) -> str:
    """The OpenSim model (XML text) of ``skeleton`` with the observed ``joints``
    (``'right_knee'``, ...; the ``.mot``'s coordinates) and, if ``pelvis``, the pelvis' three."""
    q0 = skeleton.neutral()
    skeleton.forward(q0)
    legs = skeleton.legs
    segments = (["pelvis"] if pelvis else []) + [f"{s}_{g}" for s in legs for g in OSIM_BODIES]
    pose = {seg: skeleton.frame_pose(seg) for seg in ["pelvis", *segments[pelvis:]]}
    root = etree.Element("OpenSimDocument", Version="40000")
    model = _sub(root, "Model", name=name)
    _sub(model, "credits", "written by pipeline (IMU-to-skeleton on Pinocchio)")
    _sub(model, "length_units", "meters")
    _sub(model, "force_units", "N")
    _sub(model, "gravity", "0 -9.80665 0")
    _sub(model, "Ground", name="ground")
    visuals = _visuals(skeleton)
    bodies = _sub(_sub(model, "BodySet", name="bodyset"), "objects")
    for seg in segments:
        _add_body(bodies, skeleton, seg, visuals.get(seg, []))
    objects = _sub(_sub(model, "JointSet", name="jointset"), "objects")
    lowest = min(skeleton.frame_position(f)[1] for f in skeleton.landmark_frames)
    if pelvis:
        joint = _custom_joint(objects, skeleton, _Link("ground_pelvis", "/ground", "pelvis",
                                                       np.eye(4)), _PELVIS, 1.0)
        _free(joint, np.array([0.0, -lowest, 0.0]))
    for side in legs:
        lat = 1.0 if side == "right" else -1.0
        for joint, (prox, dist, coords) in _JOINTS.items():
            child = f"{side}_{dist}"
            parent = "pelvis" if prox == "pelvis" else f"{side}_{prox}"
            rel = np.linalg.inv(pose[parent]) @ pose[child]
            jname = f"{joint}_{side[0]}"
            if parent == "pelvis" and not pelvis:  # the femur welded at its hip centre
                T = pose["pelvis"] @ rel
                T[1, 3] -= lowest
                _weld(objects, jname, "/ground", _body(child), T)
            elif f"{side}_{joint}" in joints:
                T = np.eye(4)
                T[:3, 3] = rel[:3, 3]
                link = _Link(jname, f"/bodyset/{_body(parent)}", _body(child), T)
                _custom_joint(objects, skeleton, link, coords, lat)
            else:
                _weld(objects, jname, f"/bodyset/{_body(parent)}", _body(child), rel)
    markers = _sub(_sub(model, "MarkerSet", name="markerset"), "objects")
    for frame in skeleton.landmark_frames:
        side, lm = frame.split("_", 1)
        seg = f"{side}_{LANDMARK_SEGMENT[lm]}"
        marker = _sub(markers, "Marker", name=frame)
        _sub(marker, "socket_parent_frame", f"/bodyset/{_body(seg)}")
        _sub(marker, "location", (np.linalg.inv(pose[seg]) @ skeleton.frame_pose(frame))[:3, 3])
        _sub(marker, "fixed", "true")
    return etree.tostring(root, xml_declaration=True, pretty_print=True,
                          encoding="UTF-8").decode("utf-8")


def _add_body(bodies, skeleton: Skeleton, segment: str, visuals: list) -> None:
    joint = skeleton.model.frames[skeleton.frame_id(segment)].parentJoint
    inertia = skeleton.model.inertias[joint]
    # the joint frame is the segment frame at q = 0 (module docstring of pipeline.model.builder)
    body = _sub(bodies, "Body", name=_body(segment))
    _sub(body, "mass", repr(float(inertia.mass)))
    _sub(body, "mass_center", inertia.lever)
    I = inertia.inertia  # noqa: E741 (about the centre of mass)
    _sub(body, "inertia", [I[0, 0], I[1, 1], I[2, 2], I[0, 1], I[0, 2], I[1, 2]])
    geometry = _sub(body, "attached_geometry")
    for k, (mesh, scale, T) in enumerate(visuals):
        frame = f"{_body(segment)}_geom_{k}"
        comp = body.find("components")
        if comp is None:
            comp = _sub(body, "components")
        off = _sub(comp, "PhysicalOffsetFrame", name=frame)
        _sub(off, "socket_parent", "..")
        _sub(off, "translation", T[:3, 3])
        _sub(off, "orientation", "0 0 0")
        m = _sub(geometry, "Mesh", name=f"{frame}_mesh")
        _sub(m, "socket_frame", frame)
        _sub(m, "scale_factors", scale)
        _sub(m, "mesh_file", str(mesh))


def _frames(joint, parent_path: str, child: str, T: np.ndarray) -> None:
    _sub(joint, "socket_parent_frame", f"{joint.get('name')}_parent")
    _sub(joint, "socket_child_frame", f"{joint.get('name')}_child")
    frames = _sub(joint, "frames")
    p = _sub(frames, "PhysicalOffsetFrame", name=f"{joint.get('name')}_parent")
    _sub(p, "socket_parent", parent_path)
    _sub(p, "translation", T[:3, 3])
    _sub(p, "orientation", _xyz_body_fixed(T[:3, :3]))
    c = _sub(frames, "PhysicalOffsetFrame", name=f"{joint.get('name')}_child")
    _sub(c, "socket_parent", f"/bodyset/{child}")
    _sub(c, "translation", "0 0 0")
    _sub(c, "orientation", "0 0 0")


def _xyz_body_fixed(R: np.ndarray) -> np.ndarray:
    """OpenSim's frame orientation: body-fixed X-Y-Z angles, ``R = Rx(a) Ry(b) Rz(c)``."""
    b = np.arcsin(np.clip(R[0, 2], -1.0, 1.0))
    a = np.arctan2(-R[1, 2], R[2, 2])
    c = np.arctan2(-R[0, 1], R[0, 0])
    return np.array([a, b, c]) + 0.0


def _weld(objects, name: str, parent_path: str, child: str, T: np.ndarray) -> None:
    _frames(_sub(objects, "WeldJoint", name=name), parent_path, child, T)


class _Link(NamedTuple):
    """A joint's name, its parent frame's path, its child body and the joint frame in the
    parent (4x4)."""

    name: str
    parent_path: str
    child: str
    T: np.ndarray


#: ``ground_pelvis``'s translations, along the ground's x, y, z.
PELVIS_TRANSLATIONS = ("pelvis_tx", "pelvis_ty", "pelvis_tz")


def _free(joint, default: np.ndarray) -> None:
    """Make the custom ``joint``'s translations :data:`PELVIS_TRANSLATIONS` (their defaults
    ``default``, m)."""
    cs = joint.find("coordinates")
    for cname, value in zip(PELVIS_TRANSLATIONS, default, strict=True):
        c = _sub(cs, "Coordinate", name=cname)
        _sub(c, "default_value", repr(float(value)))
        _sub(c, "range", [-100.0, 100.0])
        _sub(c, "clamped", "false")
        _sub(c, "locked", "false")
    for ta in joint.findall("SpatialTransform/TransformAxis"):
        if not ta.get("name").startswith("translation"):
            continue
        k = int(ta.get("name")[-1]) - 1
        ta.find("coordinates").text = PELVIS_TRANSLATIONS[k]
        ta.remove(ta.find("Constant"))
        _sub(_sub(ta, "LinearFunction", name="function"), "coefficients", "1 0")


def _custom_joint(objects, skeleton, link: _Link, coords, lat):
    name, parent_path, child, T = link
    joint = _sub(objects, "CustomJoint", name=name)
    suffix = "" if name == "ground_pelvis" else f"_{name[-1]}"
    cs = _sub(joint, "coordinates")
    for cname, _ in coords:
        if cname is None:
            continue
        c = _sub(cs, "Coordinate", name=cname + suffix)
        _sub(c, "default_value", "0")
        _sub(c, "range", _range(skeleton, name, cname))
        _sub(c, "clamped", "false")
        _sub(c, "locked", "false")
    _frames(joint, parent_path, child, T)
    st = _sub(joint, "SpatialTransform")
    for k, (cname, axis) in enumerate(coords, start=1):
        ax = [lat if a == "L" else a for a in axis]
        ta = _sub(st, "TransformAxis", name=f"rotation{k}")
        _sub(ta, "coordinates", "" if cname is None else cname + suffix)
        _sub(ta, "axis", ax)
        if cname is None:
            _sub(_sub(ta, "Constant", name="function"), "value", "0")
        else:
            _sub(_sub(ta, "LinearFunction", name="function"), "coefficients", "1 0")
    for k, axis in enumerate(np.eye(3), start=1):
        ta = _sub(st, "TransformAxis", name=f"translation{k}")
        _sub(ta, "coordinates", "")
        _sub(ta, "axis", axis)
        _sub(_sub(ta, "Constant", name="function"), "value", "0")
    return joint


def _range(skeleton: Skeleton, joint: str, coordinate: str) -> list[float]:
    """The model's limits of the joint behind a coordinate (wide where it has none)."""
    side = {"r": "right", "l": "left"}.get(joint[-1], "")
    ours = {"hip_flexion": "hip_Z", "hip_adduction": "hip_X", "hip_rotation": "hip_Y",
            "knee_angle": "knee_Z", "knee_adduction": "knee_X", "knee_rotation": "knee_Y",
            "ankle_angle": "ankle_Z", "subtalar_angle": "ankle_X"}.get(coordinate)
    name = f"{side}_{ours}"
    if ours is None or name not in skeleton.joint_names:
        return [-np.pi, np.pi]
    i = skeleton.q_index(name)
    return [float(skeleton.lower_limits[i]), float(skeleton.upper_limits[i])]


def _visuals(skeleton: Skeleton) -> dict[str, list[tuple[Path, np.ndarray, np.ndarray]]]:
    """Segment -> [(mesh file, scale, 4x4 origin in the segment frame)] from the URDF."""
    tree = etree.fromstring(skeleton.urdf.encode())
    out: dict[str, list] = {}
    for link in tree.iter("link"):
        for visual in link.iter("visual"):
            mesh = visual.find("geometry/mesh")
            if mesh is None:
                continue
            T = np.eye(4)
            origin = visual.find("origin")
            if origin is not None and origin.get("xyz"):
                T[:3, 3] = [float(v) for v in origin.get("xyz").split()]
            scale = np.array([float(v) for v in (mesh.get("scale") or "1 1 1").split()])
            path = resolve_package_uri(mesh.get("filename"))
            out.setdefault(link.get("name"), []).append((path, scale, T))
    return out
