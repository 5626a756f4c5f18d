"""Subject-scaled lower-limb URDF, derived from example-robot-data's ``human.urdf`` (DESIGN.md §3).

Kept from the template: pelvis + thigh/shank/foot per leg, its naming style (``<side>_hip_Z``,
``<side>_hip_X``, ``<side>_hip_Y``, ``<side>_knee_Z``, ``<side>_ankle_Z``, ``<side>_ankle_X``,
``*_virtual`` intermediate links), its STL meshes (scaled, :mod:`pipeline.model.meshes`) and its
Dumas et al. (2007) inertias (scaled). The upper body is dropped. Links are renamed to the
segment names used downstream: ``pelvis``, ``<side>_femur``, ``<side>_tibia``, ``<side>_foot``.
The knee is ``<side>_knee`` (hinge, 1 DoF) or ``<side>_knee_Z``, ``_X``, ``_Y`` (free). Fixed
frames are massless links ``<side>_{HJC,KJC,AJC,EFM,EFL,MM,LM,HEE,MT1,MT5,TOE}``, ``pelvis_imu`` and
``<side>_{femur,tibia,foot}_imu``, each attached by a fixed joint named ``<frame>_joint``. The
left leg's mesh visuals are the sagittal mirror images of the right leg's (see
:mod:`pipeline.model.meshes`).

Every link frame IS the ISB segment frame at ``q = 0`` (femur: origin HJC; tibia: origin KJC;
foot: origin AJC; axes x anterior, y proximal, z right, left leg mirrored), so the landmark frames
are fixed frames at the :class:`SubjectGeometry` positions and Wang eq 15-17 are the forward
kinematics of those frames.

Joints and signs (``L = +1`` right leg, ``-1`` left leg; the left leg's URDF axes are mirrored so
that every angle has the same anatomical meaning on both sides):

=================  =====================  ====================================  =================
joint              axis (parent frame)    positive q                            limits (rad)
=================  =====================  ====================================  =================
``hip_Z``          ``(0, 0, 1)``          hip flexion                           [-1.047, 3.142]
``hip_X``          ``(L, 0, 0)``          hip adduction                         [-1.571, 1.047]
``hip_Y``          ``(0, L, 0)``          hip internal rotation                 [-1.571, 1.047]
``knee`` (hinge)   ``-a_T`` (tibia)       knee flexion about the AoR            [0, 3.142]
``knee_Z`` (free)  ``(0, 0, -1)``         knee flexion                          [0, 3.142]
``knee_X`` (free)  ``(L, 0, 0)``          knee adduction (varus)                [-0.524, 0.524]
``knee_Y`` (free)  ``(0, L, 0)``          tibial internal rotation              [-0.785, 0.785]
``ankle_Z``        ``(0, 0, 1)``          dorsiflexion                          [-1.571, 0.785]
``ankle_X``        ``(L, 0, 0)``          inversion                             [-0.524, 0.785]
``ankle_Y`` (free) ``(0, L, 0)``          the foot's internal rotation          [-0.524, 0.524]
=================  =====================  ====================================  =================

Hip/ankle limits are the template's (its hip_X counted abduction positive; ISB adduction is used
here, so the interval is negated); knee_X/knee_Y limits are ours (the template has a 1-DoF knee).
The ankle is ``ankle_Z``, ``ankle_X`` (``universal``, the model's) or with ``ankle_Y`` after them
(``free``: the simulator's, so that a tibia can turn on its planted foot; Z-X-Y as the JCS).

Hinge knee: the joint frame sits at the KJC with rotation ``R0 = rotation_aligning(a_T, a_F)``
relative to the femur, and turns about ``-a_T`` in the tibial frame, so ``R_F a_F = R_T a_T`` for
every ``q`` (the AoR is fixed in both segments; Wang eq 6-8). Free knee: Z-X-Y chain at the KJC,
so ``e_T = e_F Rz(-q_Z) Rx(L q_X) Ry(L q_Y)`` takes any value and the malleoli follow Wang eq 17.

Masses: template mass times ``geometry.mass_scale`` (``body_mass / 75 kg``, or ``(H / 1.80)^3``);
centres of mass scale with the segment length ratio ``l = L / L_template``; inertia tensors by
``mass_ratio * l^2`` (fixed radii of gyration relative to length, as in Dumas 2007).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from pipeline.errors import InputError
from pipeline.model.conventions import ANKLE_MODES, DEFAULT_KNEE, KNEE_MODES, LANDMARKS, SEGMENTS
from pipeline.model.geometry import TEMPLATE_HEIGHT_M, SubjectGeometry, mirror_point
from pipeline.model.meshes import leg_visuals, materials, pelvis_visuals
from pipeline.model.urdf_xml import Inertial, Joint, Link, urdf_xml
from pipeline.rotations import rotation_aligning

__all__ = [
    "build_urdf",
    "urdf_text",
    "default_imu_placements",
    "imu_frame_names",
    "joint_names",
    "landmark_frame_names",
    "segment_frame_names",
    "urdf_object",
]


# Template (human.urdf, right leg, H = 1.80 m) lengths used as scaling references (m).
_T_THIGH, _T_SHANK = 0.439, 0.44
_T_FOOT = 0.271  # heel to toe of the template's foot mesh (0.1506 H at 1.80 m)

# Template inertials (right side): mass, com, (ixx, ixy, ixz, iyy, iyz, izz).
_INERTIA = {
    "pelvis": (
        10.65,
        (0.03, -0.025, -0.001),
        (0.08977, -0.0055, -0.00127, 0.09888, -0.00056, 0.07942),
    ),
    "femur": (
        9.22,
        (-0.018, -0.188, 0.014),
        (0.1497, 0.00872, -0.00071, 0.04005, -0.00872, 0.1602),
    ),
    "tibia": (3.6, (-0.021, -0.181, 0.003), (0.05471, 0.00112, 0.00028, 0.00698, 0.00174, 0.05471)),
    "foot": (0.9, (0.068, -0.027, 0.005), (0.00081, 0.00048, -0.00018, 0.00385, 0.0, 0.00364)),
}
# (effort, velocity, lower, upper), sign-adapted as in the module docstring.
_LIMITS = {
    "hip_Z": (185.0, 12.0, -1.047196667, 3.14159),
    "hip_X": (120.0, 12.0, -1.570795, 1.047196667),
    "hip_Y": (60.0, 12.0, -1.570795, 1.047196667),
    "knee": (130.0, 18.6, 0.0, 3.14159),
    "knee_Z": (130.0, 18.6, 0.0, 3.14159),
    "knee_X": (60.0, 6.0, -0.523598333, 0.523598333),
    "knee_Y": (60.0, 6.0, -0.785398, 0.785398),
    "ankle_Z": (126.0, 12.7, -1.570795, 0.7853975),
    "ankle_X": (20.0, 6.0, -0.523598333, 0.785398),
    "ankle_Y": (20.0, 6.0, -0.523598333, 0.523598333),
}


def segment_frame_names(legs: Sequence[str] = ("right", "left")) -> dict[str, str]:
    """Segment key -> link/frame name: ``{'pelvis': 'pelvis', 'right_femur': 'right_femur'}``."""
    names = {"pelvis": "pelvis"}
    names.update({f"{s}_{seg}": f"{s}_{seg}" for s in legs for seg in SEGMENTS})
    return names


def landmark_frame_names(legs: Sequence[str] = ("right", "left")) -> list[str]:
    """``right_HJC, right_KJC, right_AJC, right_EFM, right_EFL, right_MM, right_LM`` (+ left)."""
    return [f"{s}_{lm}" for s in legs for lm in LANDMARKS]


def imu_frame_names(legs: Sequence[str] = ("right", "left")) -> list[str]:
    """``pelvis_imu`` and ``<side>_femur_imu``, ``<side>_tibia_imu``, ``<side>_foot_imu``."""
    return ["pelvis_imu"] + [f"{s}_{seg}_imu" for s in legs for seg in SEGMENTS]


def joint_names(knee: str = "hinge", legs: Sequence[str] = ("right", "left"),
                ankle: str = "universal") -> list[str]:
    """Actuated joints in URDF order (hip Z-X-Y, knee, ankle Z-X(-Y) per leg).

    Pinocchio orders the legs alphabetically (left first); use ``Skeleton`` for q indices.
    """
    k = ["knee"] if knee == "hinge" else ["knee_Z", "knee_X", "knee_Y"]
    a = ["ankle_Z", "ankle_X"] + (["ankle_Y"] if ankle == "free" else [])
    per_leg = ["hip_Z", "hip_X", "hip_Y", *k, *a]
    return [f"{s}_{j}" for s in legs for j in per_leg]


def _tf(
    R: np.ndarray | None = None, p: Sequence[float] | np.ndarray = (0.0, 0.0, 0.0)
) -> np.ndarray:
    T = np.eye(4)
    if R is not None:
        T[:3, :3] = R
    T[:3, 3] = p
    return T


def _inertial(segment: str, mass_scale: float, length_ratio: float, side: str) -> Inertial:
    m0, com, (ixx, ixy, ixz, iyy, iyz, izz) = _INERTIA[segment]
    inertia = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    com = np.asarray(com) * length_ratio
    if side == "left":  # mirror the right-side template: M I M, M c
        M = np.diag([1.0, 1.0, -1.0])
        inertia, com = M @ inertia @ M, mirror_point(com)
    inertia = inertia * mass_scale * length_ratio**2
    return Inertial(origin=_tf(p=com), mass=float(m0 * mass_scale), inertia=inertia)


def _revolute(
    name: str, parent: str, child: str, origin: np.ndarray, axis, limit_key: str
) -> Joint:
    return Joint(name, "revolute", parent, child, origin, axis=np.asarray(axis, dtype=float),
                 limit=tuple(_LIMITS[limit_key]))


def _fixed_frame(name: str, parent: str, T: np.ndarray) -> tuple[Link, Joint]:
    return Link(name), Joint(f"{name}_joint", "fixed", parent, name, T)


def default_imu_placements(g: SubjectGeometry) -> dict[str, np.ndarray]:
    """Plausible IMU sites (4x4, identity rotation) in the segment frames of ``g.side``.

    pelvis: sacrum; femur: lateral mid-thigh; tibia: antero-medial shank (flat tibial surface);
    foot: dorsum of the mid-foot. Offsets scale with height / 1.80 m and segment lengths.
    """
    s, lat, side = g.height_m / TEMPLATE_HEIGHT_M, g.lateral_sign, g.side
    return {
        "pelvis_imu": _tf(p=(-0.11 * s, -0.05 * s, 0.0)),
        f"{side}_femur_imu": _tf(p=(0.0, -0.5 * g.thigh_length, 0.08 * s * lat)),
        f"{side}_tibia_imu": _tf(p=(0.03 * s, -0.35 * g.shank_length, -0.03 * s * lat)),
        f"{side}_foot_imu": _tf(p=(0.25 * g.foot_length_m, -0.02 * s, 0.0)),
    }


def _placement(name: str, value: object) -> np.ndarray:
    if isinstance(value, tuple) and len(value) == 2:
        R, p = (np.asarray(v, dtype=float) for v in value)
        T = _tf(R, p) if R.shape == (3, 3) and p.shape == (3,) else np.full((4, 4), np.nan)
    else:
        T = np.asarray(value, dtype=float)
    ok = T.shape == (4, 4) and np.all(np.isfinite(T))
    if ok:
        R = T[:3, :3]
        ok = np.allclose(R.T @ R, np.eye(3), atol=1e-6) and np.linalg.det(R) > 0
        ok = ok and np.allclose(T[3], [0, 0, 0, 1])
    if not ok:
        raise InputError("expected a 4x4 rigid transform or (R 3x3 rotation, p 3)", field=name)
    return T


def _leg(g: SubjectGeometry, knee: str, imus: Mapping[str, np.ndarray],
         ankle: str = "universal") -> tuple[list, list]:
    side, lat = g.side, g.lateral_sign
    femur, tibia, foot = f"{side}_femur", f"{side}_tibia", f"{side}_foot"
    l_thigh, l_shank = g.thigh_length / _T_THIGH, g.shank_length / _T_SHANK
    l_foot = g.foot_length_m / _T_FOOT
    ms = g.mass_scale
    visuals = leg_visuals(g, l_thigh, l_shank, l_foot)
    links = [
        Link(name=f"{femur}_virtual"),
        Link(name=f"{femur}_virtual_2"),
        Link(name=femur, inertial=_inertial("femur", ms, l_thigh, side), visuals=visuals[femur]),
        Link(name=tibia, inertial=_inertial("tibia", ms, l_shank, side), visuals=visuals[tibia]),
        Link(name=f"{foot}_virtual"),
        Link(name=foot, inertial=_inertial("foot", ms, l_foot, side), visuals=visuals[foot]),
    ]
    jn = f"{side}_"
    joints = [
        _revolute(jn + "hip_Z", "pelvis", f"{femur}_virtual", _tf(p=g.hip), (0, 0, 1), "hip_Z"),
        _revolute(
            jn + "hip_X", f"{femur}_virtual", f"{femur}_virtual_2", _tf(), (lat, 0, 0), "hip_X"
        ),
        _revolute(jn + "hip_Y", f"{femur}_virtual_2", femur, _tf(), (0, lat, 0), "hip_Y"),
    ]
    kjc = g.kjc_femur
    if knee == "hinge":
        R0 = rotation_aligning(g.knee_axis_tibia, g.knee_axis_femur)
        joints.append(
            _revolute(jn + "knee", femur, tibia, _tf(R0, kjc), -g.knee_axis_tibia, "knee")
        )
    else:
        v1, v2 = f"{tibia}_virtual", f"{tibia}_virtual_2"
        links += [Link(name=v1), Link(name=v2)]
        joints += [
            _revolute(jn + "knee_Z", femur, v1, _tf(p=kjc), (0, 0, -1), "knee_Z"),
            _revolute(jn + "knee_X", v1, v2, _tf(), (lat, 0, 0), "knee_X"),
            _revolute(jn + "knee_Y", v2, tibia, _tf(), (0, lat, 0), "knee_Y"),
        ]
    last = f"{foot}_virtual_2" if ankle == "free" else foot  # ankle_X's child
    joints += [
        _revolute(
            jn + "ankle_Z", tibia, f"{foot}_virtual", _tf(p=g.ajc_tibia), (0, 0, 1), "ankle_Z"
        ),
        _revolute(jn + "ankle_X", f"{foot}_virtual", last, _tf(), (lat, 0, 0), "ankle_X"),
    ]
    if ankle == "free":
        links.append(Link(name=last))
        joints.append(_revolute(jn + "ankle_Y", last, foot, _tf(), (0, lat, 0), "ankle_Y"))
    fixed = {
        "HJC": (femur, np.zeros(3)),
        "KJC": (femur, kjc),
        "AJC": (tibia, g.ajc_tibia),
        **{k: (femur, v) for k, v in g.femur_landmarks.items()},
        **{k: (tibia, v) for k, v in g.tibia_landmarks.items()},
        **{k: (foot, v) for k, v in g.foot_landmarks.items()},
    }
    for lm in LANDMARKS:
        parent, p = fixed[lm]
        link, joint = _fixed_frame(f"{side}_{lm}", parent, _tf(p=p))
        links.append(link)
        joints.append(joint)
    for seg in SEGMENTS:
        name = f"{side}_{seg}_imu"
        link, joint = _fixed_frame(name, f"{side}_{seg}", imus[name])
        links.append(link)
        joints.append(joint)
    return links, joints


def urdf_text(
    geometry: SubjectGeometry,
    knee: str = DEFAULT_KNEE,
    legs: Sequence[str] = ("right", "left"),
    imu_placements: Mapping[str, object] | None = None,
    other_leg: SubjectGeometry | None = None,
    check: bool = True,
    ankle: str = "universal",
) -> str:
    """The subject's lower-limb URDF as XML text (the model is built in memory from it).

    Args:
        geometry: dimensions of one leg and the pelvis; the other leg is its mirror image
            (:meth:`SubjectGeometry.mirrored`) unless ``other_leg`` is given.
        knee: ``'free'`` (Z-X-Y, Wang eq 15-17; the default, as ``pipeline scale``/``ik``) or
            ``'hinge'`` (1 DoF about the knee AoR).
        legs: which legs to include, a subset of ``('right', 'left')``.
        imu_placements: IMU frame name (e.g. ``'right_tibia_imu'``) -> 4x4 transform or
            ``(R, p)`` in its segment frame; others get :func:`default_imu_placements`.
        other_leg: geometry of the opposite leg, for asymmetric subjects.
        check: load the result with ``pinocchio.buildModelFromXML`` and verify its joints.
        ankle: ``'universal'`` (flexion, inversion: the model's) or ``'free'`` (and the foot's
            rotation about its vertical axis: the simulator's).
    """
    if knee not in KNEE_MODES:
        raise InputError(f"expected knee in {KNEE_MODES}, got {knee!r}", field="knee")
    if ankle not in ANKLE_MODES:
        raise InputError(f"expected ankle in {ANKLE_MODES}, got {ankle!r}", field="ankle")
    legs = tuple(legs)
    if not legs or len(set(legs)) != len(legs) or not set(legs) <= {"right", "left"}:
        raise InputError(f"expected legs from ('right', 'left'), got {legs}", field="legs")
    geoms = {}
    for side in legs:
        if other_leg is not None and other_leg.side == side:
            geoms[side] = other_leg
        else:
            geoms[side] = geometry.for_side(side)
    imus: dict[str, np.ndarray] = {}
    for g in geoms.values():
        imus.update(default_imu_placements(g))
    for name, value in (imu_placements or {}).items():
        if name not in imus:
            raise InputError(
                f"expected an IMU frame among {sorted(imus)}, got {name!r}", field=name
            )
        imus[name] = _placement(name, value)

    s = geometry.height_m / TEMPLATE_HEIGHT_M
    pelvis = Link(
        name="pelvis",
        inertial=_inertial("pelvis", geometry.mass_scale, s, "right"),
        visuals=pelvis_visuals(s),
    )
    links, joints = [pelvis], []
    link, joint = _fixed_frame("pelvis_imu", "pelvis", imus["pelvis_imu"])
    links.append(link)
    joints.append(joint)
    for g in geoms.values():
        leg_links, leg_joints = _leg(g, knee, imus, ankle)
        links += leg_links
        joints += leg_joints
    name = f"lower_limb_{knee}_knee{'_free_ankle' if ankle == 'free' else ''}_ISB_model"
    text = urdf_xml(name, links, joints, materials())
    if check:
        _check_with_pinocchio(text, joint_names(knee, legs, ankle))
    return text


def urdf_object(text: str, **kwargs: object):
    """The model as a ``yourdfpy.URDF``, to inspect or edit it in Python (``kwargs`` go to
    ``yourdfpy.URDF.load``; meshes are not loaded unless asked). yourdfpy is imported here only:
    it imports trimesh, ~0.8 s, which no command needs."""
    import io

    import yourdfpy

    kwargs = {"build_scene_graph": False, "load_meshes": False, **kwargs}
    return yourdfpy.URDF.load(io.BytesIO(text.encode("ascii")), **kwargs)


def build_urdf(
    geometry: SubjectGeometry,
    out_path: str | Path,
    knee: str = DEFAULT_KNEE,
    legs: Sequence[str] = ("right", "left"),
    imu_placements: Mapping[str, object] | None = None,
    other_leg: SubjectGeometry | None = None,
    check: bool = True,
) -> Path:
    """Write :func:`urdf_text` to ``out_path`` (parent folders are created); return the path.

    Only for outputs: code that needs the model builds it in memory
    (:meth:`pipeline.model.skeleton.Skeleton.build`).
    """
    text = urdf_text(geometry, knee, legs, imu_placements, other_leg, check)
    out = Path(out_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(text, encoding="utf-8")
    return out


def _check_with_pinocchio(text: str, expected_joints: list[str]) -> None:
    import pinocchio as pin

    model = pin.buildModelFromXML(text)
    names = list(model.names)[1:]
    if sorted(names) != sorted(expected_joints):
        raise InputError(
            f"the generated URDF loads in Pinocchio with joints {names}, expected "
            f"{expected_joints}",
            field="urdf",
        )
