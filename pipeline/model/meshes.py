"""Visuals of the subject-scaled URDF: template STL meshes, scaled per segment (DESIGN.md §3).

The meshes are example-robot-data's ``human_description`` STL files, referenced by
``package://example-robot-data/...`` URIs (:func:`resolve_package_uri` finds the file). Each
segment's mesh scale is the template's times the subject's ratios: lengths along y (thigh, shank)
or x (foot) by the length ratio ``l = L / L_template``; widths by knee / ankle width over assumed
template widths of 0.100 m / 0.070 m (the shank by their mean). These widths are for the viewer
only; no dimension downstream uses them.

The template uses the same STL files with the same positive scales on both legs; they are treated
as right-leg shapes (z lateral; the thigh shaft sits ~1 mm lateral of its proximal cap). The left
leg's visuals are their sagittal mirror images: scale ``(s_x, s_y, -s_z)`` and origin ``M p``
(``M = diag(1, 1, -1)``), so a left vertex is ``M`` times the right one in the (mirrored) segment
frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pipeline.model.geometry import SubjectGeometry, mirror_point
from pipeline.model.resources import example_robot_data_share
from pipeline.model.urdf_xml import Material, Visual

__all__ = ["leg_visuals", "materials", "pelvis_visuals", "resolve_package_uri"]

_MESH_URI = "package://example-robot-data/robots/human_description/meshes/"
_T_KNEE_WIDTH, _T_ANKLE_WIDTH = 0.100, 0.070  # assumed epicondylar / bimalleolar widths at 1.80 m
_COLORS = {
    "middle": (0.0, 0.0, 0.8, 1.0),
    "right": (0.8, 0.0, 0.0, 1.0),
    "left": (0.0, 0.8, 0.0, 1.0),
}


def resolve_package_uri(uri: str) -> Path:
    """File behind ``package://example-robot-data/...`` (ROS_PACKAGE_PATH = the share folder)."""
    prefix = "package://"
    if not uri.startswith(prefix):
        return Path(uri)
    return example_robot_data_share().parent / uri[len(prefix) :]


def _visual(
    name: str,
    mesh: str,
    scale: Sequence[float],
    xyz: Sequence[float],
    mat: str,
    mirror: bool = False,
) -> Visual:
    """Mesh visual; ``mirror``: reflect it through the sagittal plane (``M = diag(1, 1, -1)``).

    A mesh vertex ``v`` lands at ``S v + p``; mirrored, at ``M (S v + p) = (M S) v + M p``: the z
    scale is negated and the origin reflected (the origins carry no rotation).
    """
    scale, xyz = np.asarray(scale, dtype=float), np.asarray(xyz, dtype=float)
    if mirror:
        scale, xyz = scale * [1.0, 1.0, -1.0], mirror_point(xyz)
    origin = np.eye(4)
    origin[:3, 3] = xyz
    return Visual(name, _MESH_URI + mesh, scale, origin, Material(mat))


def pelvis_visuals(height_ratio: float) -> list[Visual]:
    """Pelvis mesh scaled by ``height_ratio = H / 1.80 m`` (material ``body_color``)."""
    s = height_ratio
    return [
        _visual(
            "pelvis",
            "pelvis_mesh.STL",
            (0.006430 * s, 0.005897 * s, 0.005897 * s),
            (0.0, -0.05 * s, 0.0),
            "body_color",
        )
    ]


def leg_visuals(
    g: SubjectGeometry, l_thigh: float, l_shank: float, l_foot: float
) -> dict[str, list[Visual]]:
    """Link name (``<side>_femur``, ``_tibia``, ``_foot``) -> its visuals for leg ``g.side``.

    ``l_*`` are the segment length ratios to the template; the left leg is mirrored.
    """
    side = g.side
    femur, tibia, foot = f"{side}_femur", f"{side}_tibia", f"{side}_foot"
    mat = f"body_color_{side[0].upper()}"
    w_knee, w_ankle = g.knee_width / _T_KNEE_WIDTH, g.ankle_width / _T_ANKLE_WIDTH
    w_shank = 0.5 * (w_knee + w_ankle)
    mirror = side == "left"  # template meshes are right-leg shapes
    return {
        femur: [
            _visual(
                femur,
                "upperleg_mesh.STL",
                (0.0062 * w_knee, 0.0064 * l_thigh, 0.0069 * w_knee),
                (0.0, -0.05 * l_thigh, 0.0),
                mat,
                mirror,
            )
        ],
        tibia: [
            _visual(
                tibia,
                "lowerleg_mesh.STL",
                (0.0063 * w_shank, 0.0066 * l_shank, 0.007 * w_shank),
                (0.0, 0.0, 0.0),
                mat,
                mirror,
            ),
            _visual(
                f"{side}_knee", "knee_mesh.STL", (0.0056 * w_knee,) * 3, (0, 0, 0), mat, mirror
            ),
        ],
        foot: [
            _visual(
                foot,
                "foot_mesh.STL",
                (0.0067 * l_foot, 0.0067 * w_ankle, 0.0067 * w_ankle),
                (0.0, 0.0, 0.0),
                mat,
                mirror,
            )
        ],
    }


def materials() -> list[Material]:
    """``body_color`` (pelvis, blue), ``body_color_R`` (red), ``body_color_L`` (green)."""
    return [
        Material(n, _COLORS[k])
        for n, k in (("body_color", "middle"), ("body_color_R", "right"), ("body_color_L", "left"))
    ]
