"""``Skeleton``: the one thin wrapper around a ``pin.Model`` + ``pin.Data`` of a generated URDF.

Names (see :mod:`pipeline.model.builder`): segment frames ``pelvis``, ``<side>_femur``,
``<side>_tibia``, ``<side>_foot``; landmark frames ``<side>_{HJC,KJC,AJC,EFM,EFL,MM,LM}``; IMU
frames ``pelvis_imu``, ``<side>_{femur,tibia,foot}_imu``; joints ``<side>_hip_{Z,X,Y}``,
``<side>_knee`` (hinge) or ``<side>_knee_{Z,X,Y}`` (free), ``<side>_ankle_{Z,X}``.

Root: ``'fixed'`` (pelvis = world), ``'freeflyer'`` (q[:7] = position, quaternion **x, y, z, w**
in Pinocchio's order) or ``'spherical'`` (q[:4] = quaternion x, y, z, w; pelvis origin fixed).
Pinocchio orders the legs alphabetically (left before right): always index q through
:meth:`Skeleton.q_index` / :meth:`Skeleton.q_slice`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.model.builder import urdf_text
from pipeline.model.conventions import DEFAULT_KNEE, LANDMARKS, SEGMENTS
from pipeline.model.geometry import SubjectGeometry

__all__ = ["ROOTS", "Skeleton", "frame_ids", "knee_axis"]

ROOTS = ("fixed", "freeflyer", "spherical")


def frame_ids(model: pin.Model) -> dict[str, int]:
    """Frame name -> Pinocchio frame index, a link's BODY frame preferred over the joint or fixed
    frame of the same name (the one lookup of frames by name)."""
    ids: dict[str, int] = {}
    for i, f in enumerate(model.frames):
        ids.setdefault(f.name, i)  # first frame of a name
    for i, f in enumerate(model.frames):
        if f.type == pin.FrameType.BODY:
            ids[f.name] = i
    return ids


def knee_axis(model: pin.Model, side: str = "right") -> tuple[np.ndarray, np.ndarray]:
    """Knee axis ``(a_F, a_T)`` of a hinge-knee model in its femoral and tibial frames.

    Read from the ``pin.Model`` (the URDF is the source of truth): world axis of joint
    ``<side>_knee`` at the neutral configuration, expressed in the frames ``<side>_femur`` and
    ``<side>_tibia``, signed to point right (z > 0).
    """
    name = f"{side}_knee"
    if not model.existJointName(name):
        raise InputError(f"expected a hinge-knee model with joint {name!r}", field="model")
    jm = model.joints[model.getJointId(name)]
    if jm.nv != 1:
        raise InputError(f"expected a 1-DoF joint {name!r}, found {jm.shortname()}")
    data = model.createData()
    q = pin.neutral(model)
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    axis_w = pin.getJointJacobian(model, data, model.getJointId(name), pin.LOCAL_WORLD_ALIGNED)[
        3:, jm.idx_v
    ]
    out = []
    for seg in ("femur", "tibia"):
        R = data.oMf[model.getFrameId(f"{side}_{seg}", pin.FrameType.BODY)].rotation
        a = R.T @ axis_w
        a = a / np.linalg.norm(a)
        out.append(a if a[2] >= 0 else -a)
    return out[0], out[1]


def _root_joint(root: str):
    if root not in ROOTS:
        raise InputError(f"expected root in {ROOTS}, got {root!r}", field="root")
    return {"fixed": None, "freeflyer": pin.JointModelFreeFlyer,
            "spherical": pin.JointModelSpherical}[root]


@dataclass
class Skeleton:
    """A loaded model: ``model``, ``data``, and name lookups.

    ``urdf`` is the URDF text the model was built from (the single source of every dimension);
    ``source`` the file it was read from, if any (relative mesh paths resolve against it).
    Built in memory by :meth:`build` or :meth:`from_urdf_text`; :meth:`from_urdf` reads a file.
    """

    model: pin.Model
    data: pin.Data
    urdf: str
    root: str = "fixed"
    source: Path | None = None
    _frame_ids: dict[str, int] = field(default_factory=dict, repr=False)

    # ---- construction -------------------------------------------------------------------------
    @classmethod
    def from_urdf_text(
        cls, text: str, root: str = "fixed", source: str | Path | None = None
    ) -> Skeleton:
        """Build the model from URDF text written by :func:`urdf_text` with the given root."""
        joint = _root_joint(root)
        try:
            model = pin.buildModelFromXML(text) if joint is None else pin.buildModelFromXML(
                text, joint()
            )
        except (RuntimeError, ValueError) as exc:
            raise InputError(f"cannot build a model from the URDF: {exc}", file=source) from exc
        src = None if source is None else Path(source)
        return cls(model, model.createData(), text, root, src, frame_ids(model))

    @classmethod
    def from_urdf(cls, path: str | Path, root: str = "fixed") -> Skeleton:
        """Read a URDF file written by :func:`pipeline.model.builder.build_urdf` and build it."""
        path = Path(path)
        _root_joint(root)
        if not path.is_file():
            raise InputError("expected an existing URDF file", file=path)
        return cls.from_urdf_text(path.read_text(encoding="utf-8"), root, source=path)

    @classmethod
    def build(
        cls,
        geometry: SubjectGeometry,
        knee: str = DEFAULT_KNEE,
        root: str = "fixed",
        **kwargs: object,
    ) -> Skeleton:
        """:func:`urdf_text` of ``geometry`` built in memory (nothing is written)."""
        return cls.from_urdf_text(urdf_text(geometry, knee=knee, **kwargs), root=root)

    def with_root(self, root: str) -> Skeleton:
        """The same URDF with another root joint (``self`` when it already has it)."""
        if root == self.root:
            return self
        return Skeleton.from_urdf_text(self.urdf, root, self.source)

    def write_urdf(self, path: str | Path) -> Path:
        """Write the URDF text (an output; the model itself never needs the file)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(self.urdf, encoding="utf-8")
        return path

    def knee_axis(self, side: str = "right") -> tuple[np.ndarray, np.ndarray]:
        """Hinge-knee axis in the femoral and tibial frames (:func:`knee_axis`)."""
        return knee_axis(self.model, side)

    # ---- names --------------------------------------------------------------------------------
    @property
    def nq(self) -> int:
        return self.model.nq

    @property
    def legs(self) -> tuple[str, ...]:
        """Legs present, in ``('right', 'left')`` order."""
        return tuple(s for s in ("right", "left") if f"{s}_femur" in self._frame_ids)

    @property
    def knee(self) -> str:
        """``'hinge'`` or ``'free'``."""
        return "free" if any(n.endswith("_knee_Z") for n in self.model.names) else "hinge"

    @property
    def ankle(self) -> str:
        """``'universal'`` or ``'free'`` (:data:`~pipeline.model.conventions.ANKLE_MODES`)."""
        return "free" if any(n.endswith("_ankle_Y") for n in self.model.names) else "universal"

    @property
    def joint_names(self) -> list[str]:
        """Actuated joints in Pinocchio order (root joint included if any)."""
        return list(self.model.names)[1:]

    @property
    def segment_frames(self) -> dict[str, str]:
        """``{'pelvis': 'pelvis', 'right_femur': 'right_femur', ...}`` for the legs present."""
        out = {"pelvis": "pelvis"}
        out.update({f"{s}_{seg}": f"{s}_{seg}" for s in self.legs for seg in SEGMENTS})
        return out

    @property
    def landmark_frames(self) -> list[str]:
        names = [f"{s}_{lm}" for s in self.legs for lm in LANDMARKS]
        return [n for n in names if self.has_frame(n)]  # a URDF from before the foot landmarks

    @property
    def imu_frames(self) -> list[str]:
        return ["pelvis_imu"] + [f"{s}_{seg}_imu" for s in self.legs for seg in SEGMENTS]

    def has_frame(self, name: str) -> bool:
        return name in self._frame_ids

    def frame_id(self, name: str) -> int:
        """Pinocchio frame index of ``name`` (link/BODY frame preferred)."""
        try:
            return self._frame_ids[name]
        except KeyError:
            raise InputError(
                f"expected a frame of the model, got {name!r}", field="frame"
            ) from None

    def q_index(self, joint: str) -> int:
        """Index in q of a 1-DoF joint (e.g. ``'right_hip_X'``)."""
        if not self.model.existJointName(joint):
            raise InputError(f"expected a joint among {self.joint_names}, got {joint!r}")
        return self.model.joints[self.model.getJointId(joint)].idx_q

    def q_slice(self, joint: str) -> slice:
        """Slice of q for any joint (root joints included)."""
        if not self.model.existJointName(joint):
            raise InputError(f"expected a joint among {self.joint_names}, got {joint!r}")
        j = self.model.joints[self.model.getJointId(joint)]
        return slice(j.idx_q, j.idx_q + j.nq)

    def leg_joints(self, side: str, group: str) -> list[str]:
        """Joint names of ``group`` in ``('hip', 'knee', 'ankle')`` for ``side``, chain order."""
        prefix = f"{side}_{group}"
        return [n for n in self.joint_names if n == prefix or n.startswith(prefix + "_")]

    @property
    def lower_limits(self) -> np.ndarray:
        return np.array(self.model.lowerPositionLimit)

    @property
    def upper_limits(self) -> np.ndarray:
        return np.array(self.model.upperPositionLimit)

    # ---- kinematics ---------------------------------------------------------------------------
    def neutral(self) -> np.ndarray:
        """Neutral configuration: all joint angles 0 (segments in their ISB reference pose)."""
        return pin.neutral(self.model)

    def forward(self, q: np.ndarray) -> Skeleton:
        """Forward kinematics of every joint and frame (``pin.framesForwardKinematics``)."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.model.nq,):
            raise InputError(f"expected q of shape ({self.model.nq},), got {q.shape}", field="q")
        pin.framesForwardKinematics(self.model, self.data, q)
        return self

    def frame_pose(self, name: str) -> np.ndarray:
        """4x4 world pose of a frame after :meth:`forward`."""
        return self.data.oMf[self.frame_id(name)].homogeneous.copy()

    def frame_rotation(self, name: str) -> np.ndarray:
        """3x3 rotation (frame axes as columns in world) after :meth:`forward`."""
        return self.data.oMf[self.frame_id(name)].rotation.copy()

    def frame_position(self, name: str) -> np.ndarray:
        """World position of a frame's origin after :meth:`forward`."""
        return self.data.oMf[self.frame_id(name)].translation.copy()

    def local_placement(self, name: str) -> np.ndarray:
        """4x4 placement of a frame in its parent joint's frame (read from the URDF)."""
        return self.model.frames[self.frame_id(name)].placement.homogeneous.copy()

    def relative_pose(
        self, name: str, reference: str, q: Sequence[float] | None = None
    ) -> np.ndarray:
        """4x4 pose of frame ``name`` in frame ``reference`` (at ``q`` if given)."""
        if q is not None:
            self.forward(np.asarray(q, dtype=float))
        a, b = self.data.oMf[self.frame_id(reference)], self.data.oMf[self.frame_id(name)]
        return (a.actInv(b)).homogeneous.copy()
