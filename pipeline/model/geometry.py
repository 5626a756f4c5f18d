"""Subject geometry: every dimension of the scaled lower-limb model, in metres, in ISB frames.

Segment frames (DESIGN.md §2; Wu et al. 2002):

* femoral frame: origin at the hip joint centre (HJC); y from the knee joint centre
  KJC = (EFM + EFL) / 2 to the HJC; x anterior (normal to the HJC-EFM-EFL plane); z = x × y, to the
  right. The femoral landmarks EFM and EFL are given in it (Wang et al. 2023, eq 14).
* tibial frame: origin at the KJC; y from the ankle joint centre AJC = (MM + LM) / 2 to the KJC;
  z along the knee axis projected ⟂ y; x = y × z. The malleoli MM and LM are given in it.
* pelvis frame: the template's ``middle_pelvis`` (x anterior, y up, z right); the hip centres are
  given in it.

Left leg: its segment frames are **mirrored** so that z still points to the subject's right (x
anterior, y proximal, z right: the same right-handed axes as the right leg). Reflecting a right leg
through the sagittal plane, ``M = diag(1, 1, -1)``, flips the z coordinate of every landmark
(the lateral epicondyle and malleolus move to z < 0, the medial ones to z > 0), and maps a rotation
axis ``a`` (a pseudo-vector) to ``-M a = (-a_x, -a_y, a_z)``, which still points right.
:meth:`SubjectGeometry.mirrored` does exactly that.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace

import numpy as np

from pipeline.errors import InputError
from pipeline.model.conventions import other_side
from pipeline.rotations import angle_between

__all__ = [
    "FOOT_FRACTIONS",
    "FOOT_RATIOS",
    "TEMPLATE_HEIGHT_M",
    "TEMPLATE_HIP_OFFSET",
    "SubjectGeometry",
    "mirror_point",
    "mirror_axis",
]

#: Body height of example-robot-data's ``human.urdf``. Its segment lengths are Dumas et al. (2007)
#: male ratios times 1.80 m (thigh 0.2441 H = 0.439 m, shank 0.2446 H = 0.440 m) and its masses
#: the Dumas male fractions of 75 kg (thigh 0.123 -> 9.22 kg); example-robot-data's own loader
#: documents 1.80 m / 75 kg as the URDF's defaults.
TEMPLATE_HEIGHT_M = 1.80
#: Body mass of the template (kg), see :data:`TEMPLATE_HEIGHT_M`.
TEMPLATE_MASS_KG = 75.0
#: Right hip centre in the template's pelvis frame (human.urdf, joint ``right_hip_Z``).
TEMPLATE_HIP_OFFSET = np.array([0.023, -0.1, 0.082])
#: Foot dimensions / body height: length (heel to toe tip) 0.152, breadth (across the metatarsal
#: heads) 0.055, ankle height (floor to ankle centre) 0.039; Drillis & Contini (1966), as
#: tabulated by Winter, Biomechanics and Motor Control of Human Movement (4th ed. 2009), Fig. 4.1.
FOOT_RATIOS = {"length": 0.152, "breadth": 0.055, "ankle_height": 0.039}
#: Foot landmarks along the foot (fraction of the foot length from the heel): the first and fifth
#: metatarsal heads at 72.5 % and 63.5 % (the ball-girth proportions of shoe-last design, e.g.
#: Luximon (ed.), Handbook of Footwear Design and Manufacture, 2013), the toe tip at 100 %; the
#: ankle centre at 23.6 % (measured on example-robot-data's foot mesh: heel 0.064 m behind the
#: ankle joint of a 0.271 m foot).
FOOT_FRACTIONS = {"MT1": 0.725, "MT5": 0.635, "TOE": 1.0, "ankle": 0.236}
_SIDES = ("right", "left")
_SEXES = ("m", "f", "all")
_FEMUR_KEYS = ("EFM", "EFL")
_TIBIA_KEYS = ("MM", "LM")
#: Largest accepted angle between a knee AoR and the segment's z axis (it must point right).
_MAX_AXIS_TILT = np.deg2rad(60.0)
#: Largest accepted distance of KJC (AJC) from the femoral (tibial) y axis.
_MAX_OFF_AXIS_M = 0.02

_M = np.diag([1.0, 1.0, -1.0])


def mirror_point(p: np.ndarray) -> np.ndarray:
    """Reflection of a point through the sagittal plane: ``M p`` with ``M = diag(1, 1, -1)``."""
    return np.asarray(p, dtype=float) @ _M


def mirror_axis(a: np.ndarray) -> np.ndarray:
    """Reflection of a rotation axis (pseudo-vector): ``-M a``; a rightward axis stays rightward."""
    return -(np.asarray(a, dtype=float) @ _M)


def _vec3(v: object, name: str) -> np.ndarray:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) or not np.all(np.isfinite(a)):
        raise InputError(f"expected 3 finite coordinates in metres, got {v!r}", field=name)
    a = a.copy()
    a.setflags(write=False)
    return a


def _landmarks(d: Mapping[str, object], keys: tuple[str, ...], name: str) -> dict[str, np.ndarray]:
    if not isinstance(d, Mapping) or set(d) != set(keys):
        found = sorted(d) if isinstance(d, Mapping) else type(d).__name__
        raise InputError(f"expected landmarks {list(keys)}, got {found}", field=name)
    return {k: _vec3(d[k], f"{name}.{k}") for k in keys}


@dataclass(frozen=True, eq=False)
class SubjectGeometry:
    """Dimensions of one leg (``side``) plus the pelvis, in metres, in ISB segment frames.

    Attributes:
        sex: ``'m'``, ``'f'`` or ``'all'`` (unknown).
        height_m: body height (m), 1.0-2.5.
        femur_landmarks: ``{'EFM', 'EFL'}`` in the femoral frame (origin HJC).
        tibia_landmarks: ``{'MM', 'LM'}`` in the tibial frame (origin KJC).
        knee_axis_femur, knee_axis_tibia: unit knee AoR in the femoral / tibial frame, pointing
            right (Wang eq 6 and 8). Default ``(0, 0, 1)``.
        side: ``'right'`` or ``'left'``; left-leg frames are mirrored (z to the right), so
            lateral landmarks have z < 0 there.
        right_hip, left_hip: hip centres in the pelvis frame. Default: the template's
            ``(0.023, -0.1, ±0.082)`` m scaled by ``height_m / 1.80``.
        foot_length_m: heel-to-toe foot length, for the foot landmarks (:attr:`foot_landmarks`),
            mesh and IMU. Default: 0.152 H (:data:`FOOT_RATIOS`).
        body_mass_kg: optional; segment masses scale by ``body_mass_kg / 75`` when given, by
            ``(height_m / 1.80) ** 3`` otherwise.
    """

    sex: str
    height_m: float
    femur_landmarks: Mapping[str, np.ndarray]
    tibia_landmarks: Mapping[str, np.ndarray]
    knee_axis_femur: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    knee_axis_tibia: np.ndarray = field(default_factory=lambda: np.array([0.0, 0.0, 1.0]))
    side: str = "right"
    right_hip: np.ndarray | None = None
    left_hip: np.ndarray | None = None
    foot_length_m: float | None = None
    body_mass_kg: float | None = None

    def __post_init__(self) -> None:
        set_ = object.__setattr__
        if self.sex not in _SEXES:
            raise InputError(f"expected sex in {_SEXES}, got {self.sex!r}", field="sex")
        if self.side not in _SIDES:
            raise InputError(f"expected side in {_SIDES}, got {self.side!r}", field="side")
        h = float(self.height_m)
        if not np.isfinite(h) or not 1.0 <= h <= 2.5:
            hint = " (looks like cm or mm: give metres)" if h > 2.5 else ""
            raise InputError(f"expected a body height of 1.0-2.5 m, got {h}{hint}", field="height")
        set_(self, "height_m", h)
        set_(self, "femur_landmarks", _landmarks(self.femur_landmarks, _FEMUR_KEYS, "femur"))
        set_(self, "tibia_landmarks", _landmarks(self.tibia_landmarks, _TIBIA_KEYS, "tibia"))
        s = h / TEMPLATE_HEIGHT_M
        if self.right_hip is None:
            set_(self, "right_hip", _vec3(TEMPLATE_HIP_OFFSET * s, "right_hip"))
        if self.left_hip is None:
            set_(self, "left_hip", _vec3(mirror_point(TEMPLATE_HIP_OFFSET) * s, "left_hip"))
        set_(self, "right_hip", _vec3(self.right_hip, "right_hip"))
        set_(self, "left_hip", _vec3(self.left_hip, "left_hip"))
        if self.foot_length_m is None:
            set_(self, "foot_length_m", FOOT_RATIOS["length"] * h)
        set_(self, "foot_length_m", float(self.foot_length_m))
        if not 0.10 * h <= self.foot_length_m <= 0.20 * h:
            raise InputError(f"expected a foot length of 10-20 % of the height, got "
                             f"{self.foot_length_m:.3f} m for {h:.2f} m",
                             field="foot_length")
        if self.body_mass_kg is not None:
            m = float(self.body_mass_kg)
            if not np.isfinite(m) or not 20.0 <= m <= 250.0:
                raise InputError(f"expected a body mass of 20-250 kg, got {m}", field="mass")
            set_(self, "body_mass_kg", m)
        for name in ("knee_axis_femur", "knee_axis_tibia"):
            a = _vec3(getattr(self, name), name)
            n = np.linalg.norm(a)
            if n < 1e-9:
                raise InputError("expected a non-zero knee axis, got a zero vector", field=name)
            set_(self, name, _vec3(a / n, name))
        self._validate()

    # ---- derived dimensions -------------------------------------------------------------------
    @property
    def kjc_femur(self) -> np.ndarray:
        """Knee joint centre in the femoral frame: (EFM + EFL) / 2 (Wang eq 16)."""
        return 0.5 * (self.femur_landmarks["EFM"] + self.femur_landmarks["EFL"])

    @property
    def ajc_tibia(self) -> np.ndarray:
        """Ankle joint centre in the tibial frame: (MM + LM) / 2."""
        return 0.5 * (self.tibia_landmarks["MM"] + self.tibia_landmarks["LM"])

    @property
    def foot_landmarks(self) -> dict[str, np.ndarray]:
        """``HEE``, ``MT1``, ``MT5``, ``TOE`` in the foot frame (origin AJC; neutral foot, sole on
        the floor ``y = -h``): heel and toe tip on the foot's long axis, the metatarsal heads
        half the breadth medial (MT1) and lateral (MT5) of it (:data:`FOOT_FRACTIONS`,
        :data:`FOOT_RATIOS`; length ``foot_length_m``, breadth and ankle height from the
        height)."""
        L, lat = self.foot_length_m, self.lateral_sign
        b = FOOT_RATIOS["breadth"] * self.height_m
        y = -FOOT_RATIOS["ankle_height"] * self.height_m
        x0 = FOOT_FRACTIONS["ankle"] * L  # the ankle centre's distance from the heel

        def at(fraction: float, z: float) -> np.ndarray:
            return np.array([fraction * L - x0, y, lat * z])

        f = FOOT_FRACTIONS
        return {"HEE": at(0.0, 0.0), "MT1": at(f["MT1"], -0.5 * b), "MT5": at(f["MT5"], 0.5 * b),
                "TOE": at(f["TOE"], 0.0)}

    @property
    def thigh_length(self) -> float:
        """|HJC - KJC| (m)."""
        return float(np.linalg.norm(self.kjc_femur))

    @property
    def shank_length(self) -> float:
        """|KJC - AJC| (m)."""
        return float(np.linalg.norm(self.ajc_tibia))

    @property
    def knee_width(self) -> float:
        """|EFM - EFL| (m), Wang's k."""
        return float(np.linalg.norm(self.femur_landmarks["EFM"] - self.femur_landmarks["EFL"]))

    @property
    def ankle_width(self) -> float:
        """|MM - LM| (m), Wang's a."""
        return float(np.linalg.norm(self.tibia_landmarks["MM"] - self.tibia_landmarks["LM"]))

    @property
    def hip(self) -> np.ndarray:
        """This leg's hip centre in the pelvis frame."""
        return self.right_hip if self.side == "right" else self.left_hip

    @property
    def lateral_sign(self) -> float:
        """+1 for the right leg (lateral = +z), -1 for the mirrored left leg."""
        return 1.0 if self.side == "right" else -1.0

    @property
    def mass_scale(self) -> float:
        """Body mass relative to the template's 75 kg (see ``body_mass_kg``)."""
        if self.body_mass_kg is not None:
            return self.body_mass_kg / TEMPLATE_MASS_KG
        return (self.height_m / TEMPLATE_HEIGHT_M) ** 3

    # ---- mirroring ----------------------------------------------------------------------------
    def mirrored(self) -> SubjectGeometry:
        """The same dimensions for the other leg: landmark z and axis x, y change sign.

        Points map by ``M p`` and rotation axes by ``-M a`` (``M = diag(1, 1, -1)``), so the
        left leg's frames keep z to the subject's right and its knee axis still points right.
        """
        return replace(
            self,
            side=other_side(self.side),
            femur_landmarks={k: mirror_point(v) for k, v in self.femur_landmarks.items()},
            tibia_landmarks={k: mirror_point(v) for k, v in self.tibia_landmarks.items()},
            knee_axis_femur=mirror_axis(self.knee_axis_femur),
            knee_axis_tibia=mirror_axis(self.knee_axis_tibia),
        )

    def for_side(self, side: str) -> SubjectGeometry:
        """This geometry if it describes ``side``, its mirror image otherwise."""
        if side not in _SIDES:
            raise InputError(f"expected side in {_SIDES}, got {side!r}", field="side")
        return self if side == self.side else self.mirrored()

    # ---- validation ---------------------------------------------------------------------------
    def _validate(self) -> None:
        h, lat = self.height_m, self.lateral_sign
        f, t = self.femur_landmarks, self.tibia_landmarks
        for name, length in (("thigh", self.thigh_length), ("shank", self.shank_length)):
            if not 0.17 * h <= length <= 0.32 * h:
                raise InputError(
                    f"expected a {name} length of 17-32 % of the height ({0.17 * h:.3f}-"
                    f"{0.32 * h:.3f} m), got {length:.3f} m (units must be metres)",
                    field=name,
                )
        for name, width, lo, hi in (
            ("knee_width", self.knee_width, 0.04, 0.20),
            ("ankle_width", self.ankle_width, 0.03, 0.15),
        ):
            if not lo <= width <= hi:
                raise InputError(f"expected {name} of {lo}-{hi} m, got {width:.4f} m", field=name)
        for seg, c, name in ((f, self.kjc_femur, "femur"), (t, self.ajc_tibia, "tibia")):
            if c[1] >= 0.0 or any(p[1] >= 0.0 for p in seg.values()):
                raise InputError(f"expected {name} landmarks below the origin (y < 0)", field=name)
            off = float(np.hypot(c[0], c[2]))
            if off > _MAX_OFF_AXIS_M:
                raise InputError(
                    f"expected the midpoint of the {name} landmarks on the segment's -y axis "
                    f"(ISB definition), got {off * 1000:.1f} mm off it",
                    field=name,
                )
        if lat * (f["EFL"][2] - f["EFM"][2]) <= 0 or lat * (t["LM"][2] - t["MM"][2]) <= 0:
            side = "+z" if lat > 0 else "-z"
            raise InputError(
                f"expected lateral landmarks (EFL, LM) on the {side} side of the medial ones "
                f"for the {self.side} leg (left-leg frames are mirrored)",
                field="landmarks",
            )
        for name in ("knee_axis_femur", "knee_axis_tibia"):
            tilt = float(angle_between(getattr(self, name), np.array([0.0, 0.0, 1.0])))
            if tilt > _MAX_AXIS_TILT:
                raise InputError(
                    f"expected a knee axis pointing right (within 60 deg of +z), got "
                    f"{np.rad2deg(tilt):.1f} deg from +z (flip its sign if it points left)",
                    field=name,
                )
        for name in ("right_hip", "left_hip"):
            p = getattr(self, name)
            if np.linalg.norm(p) > 0.25 * h or (p[2] > 0) != (name == "right_hip"):
                raise InputError(
                    f"expected the {name.replace('_', ' ')} centre within 0.25 H of the pelvis "
                    f"origin, on the {name.split('_')[0]} (z {'>' if name[0] == 'r' else '<'} 0)",
                    field=name,
                )
        if not 0.10 * h <= self.foot_length_m <= 0.20 * h:
            raise InputError(
                f"expected a foot length of 10-20 % of the height, got {self.foot_length_m:.3f} m",
                field="foot_length",
            )

    @classmethod
    def default(
        cls, height_m: float = 1.75, sex: str = "m", side: str = "right"
    ) -> SubjectGeometry:
        """A plausible geometry from height alone (thigh 0.24 H, shank 0.245 H, knee 0.10 m).

        For tests and demos only; real subjects use :mod:`pipeline.model.anthropometry` (Wang eq
        14).
        """
        h = float(height_m)
        thigh, shank, k, a = 0.24 * h, 0.245 * h, 0.10 * h / 1.75, 0.07 * h / 1.75
        g = cls(
            sex=sex,
            height_m=h,
            femur_landmarks={"EFM": [0.0, -thigh, -k / 2], "EFL": [0.0, -thigh, k / 2]},
            tibia_landmarks={
                "MM": [0.01, -shank + 0.01, -a / 2],
                "LM": [-0.01, -shank - 0.01, a / 2],
            },
        )
        return g.for_side(side)
