"""Simulate a trial on a scaled model with Pinocchio: joint trajectories, IMU signals, landmarks.

Joint trajectories are sums of sinusoids (:class:`pipeline.simulate.Sinusoids`), so ``q``, ``v``
and ``a`` are exact. The model is loaded with a free-flyer root (``q[:7]`` = pelvis position and
quaternion ``x, y, z, w``; ``v[:6]`` = pelvis velocity in the pelvis frame, linear then angular;
``a[:6]`` its time derivative). World frame: z up, gravity ``g = (0, 0, -9.81)``; segment frames
ISB (x anterior, y proximal, z right). Motions:

* ``'gait'`` (alias ``'rich'``): walking at ~1.2 m/s along a weaving path (heading +-15-22 deg
  at 0.08 Hz), stride ~0.9 Hz, pelvis yaw/obliquity/tilt and bounce, both legs half a stride apart
  (hip Z-X-Y, knee 4-72 deg, ankle Z-X);
* ``'supine_hip_flexion'``: lying on a table (pelvis fixed), right hip and knee flexing together
  at ~0.25 Hz (hip 1-69 deg, knee 3-93 deg), small hip ab/adduction and rotation (as in the Wang
  2023 recordings); left leg still;
* ``'still_thigh'``: seated (pelvis fixed), thigh horizontal with tremor < 0.5 deg, right knee
  swinging 7-103 deg (poor excitation: the thigh axis is nearly unobservable);
* ``'static'``: standing still in the neutral pose (a gravity reference).

Every angle stays inside the model's joint limits (checked). Signals at each sensor, from
``pin.forwardKinematics(model, data, q, v, a)``:

* gyroscope ``gyr = omega``: the angular velocity of the sensor frame in the sensor frame
  (``pin.getFrameVelocity``, LOCAL);
* accelerometer ``acc = R^T (p_ddot - g)`` (specific force, reads ``+9.81`` up at rest), with
  ``R^T p_ddot`` the classical acceleration of the sensor origin in the sensor frame
  (``pin.getFrameClassicalAcceleration``, LOCAL).

The *true* sensor is the model's IMU frame (``<segment>_imu``) rotated by a random
sensor-to-segment misalignment and shifted by a random mounting offset: ``R_GS = R_imu M``,
``p_GS = p_imu + d`` (segment frame) - the truth a calibration has to recover. Then white noise,
a constant gyro bias per sensor, optional orientation noise and OMC-like landmark noise are added,
all from ``np.random.SeedSequence(seed)``: one stream for the motion, one for the placements
(so two motions with one seed share the sensor placements), one for the noise.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.io.imu_csv import ImuRecording
from pipeline.model.geometry import SubjectGeometry
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import exp3, normalize, quat_from_matrix, rot_x
from pipeline.simulate import Sinusoids, chain_kinematics

__all__ = [
    "GRAVITY",
    "MOTIONS",
    "SensorNoise",
    "SimulatedImu",
    "SimulatedTrial",
    "joint_trajectories",
    "knee_axis_in_segments",
    "simulate_trial",
]

GRAVITY = np.array([0.0, 0.0, -9.81])
MOTIONS = ("gait", "supine_hip_flexion", "still_thigh", "static")
_ALIASES = {"rich": "gait"}
_X, _Y, _Z = np.eye(3)
_STANDING = rot_x(np.pi / 2)  # pelvis (y up, z right) -> world (z up, subject faces +x)
_SUPINE = np.array([[0.0, 1, 0], [0, 0, 1], [1, 0, 0]])  # pelvis x -> up, y -> +x (head)
_SEGMENT_OF_IMU = {"pelvis_imu": "pelvis"}
_JOINT_SEGMENTS = {"hip": ("pelvis", "femur", "HJC"), "knee": ("femur", "tibia", "KJC")}
_JOINT_SEGMENTS["ankle"] = ("tibia", "foot", "AJC")


@dataclass(frozen=True)
class SensorNoise:
    """White noise SDs (``gyro_sd`` rad/s, ``acc_sd`` m/s^2), constant gyro bias SD per axis
    (``gyro_bias_sd`` rad/s), orientation noise (``orientation_sd_deg`` per axis per sample) and
    landmark (marker) noise (``landmark_sd_m``). Defaults: consumer MEMS IMUs at 100 Hz, an OMC
    system's sub-millimetre noise."""

    gyro_sd: float = 0.01
    acc_sd: float = 0.05
    gyro_bias_sd: float = 0.005
    orientation_sd_deg: float = 0.0
    landmark_sd_m: float = 0.0005

    @classmethod
    def none(cls) -> SensorNoise:
        return cls(0.0, 0.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class SimulatedImu:
    """One simulated sensor. ``recording``: noisy ``gyr``/``acc`` and the orientation ``quat``
    (sensor -> world, wxyz, + orientation noise). ``rotation`` (N,3,3) / ``position`` (N,3): true
    world pose of the sensor. ``R_segment``/``p_segment``: true sensor placement in its segment
    frame; ``misalignment`` (sensor axes in the model's IMU frame) and ``offset_m`` (segment frame)
    are its deviation from the model's IMU frame ``frame``."""

    frame: str
    segment: str
    recording: ImuRecording
    rotation: np.ndarray
    position: np.ndarray
    R_segment: np.ndarray
    p_segment: np.ndarray
    misalignment: np.ndarray
    offset_m: np.ndarray
    gyro_bias: np.ndarray


@dataclass(frozen=True)
class SimulatedTrial:
    """A simulated trial and its truth.

    ``q``/``v``/``a``: model configuration, velocity, acceleration (N, nq/nv). ``imus``: IMU frame
    name -> :class:`SimulatedImu`. ``knee_axis``: IMU frame -> unit knee axis (pointing right) in
    that sensor's frame, for the thigh and shank sensors of each leg (hinge knee only).
    ``joint_centres``: ``'<side>_{hip,knee,ankle}'`` -> {IMU frame -> centre in that sensor's
    frame (sensor -> joint, m)}. ``landmarks``: landmark frame -> (N,3) world positions + noise.
    """

    time: np.ndarray
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    motion: str
    seed: int
    imus: dict[str, SimulatedImu]
    knee_axis: dict[str, np.ndarray]
    joint_centres: dict[str, dict[str, np.ndarray]]
    landmarks: dict[str, np.ndarray]
    noise: SensorNoise
    skeleton: Skeleton = field(repr=False)
    gravity: np.ndarray = field(default_factory=lambda: GRAVITY.copy())

    @property
    def urdf_path(self) -> Path:
        return self.skeleton.urdf_path

    def hinge_truth(self, side: str = "right") -> dict[str, np.ndarray]:
        """Knee truth for a thigh (1) / shank (2) sensor pair, in the calibration's terms:
        ``axis_1``, ``axis_2`` (same physical direction) and ``position_1_m``, ``position_2_m``."""
        s1, s2 = f"{side}_femur_imu", f"{side}_tibia_imu"
        if s1 not in self.knee_axis:
            raise InputError(f"no hinge knee truth for side {side!r}", field="side")
        c = self.joint_centres[f"{side}_knee"]
        return {
            "axis_1": self.knee_axis[s1],
            "axis_2": self.knee_axis[s2],
            "position_1_m": c[s1],
            "position_2_m": c[s2],
        }


# ------------------------------------------------------------------------------------ motions

# joint suffix -> (offset deg, ((amplitude deg, frequency x base, phase rad), ...))
_Spec = dict[str, tuple[float, tuple[tuple[float, float, float], ...]]]
_GAIT: _Spec = {
    "hip_Z": (12.0, ((22.0, 1.0, 0.0), (3.0, 2.0, 0.5))),
    "hip_X": (1.0, ((5.0, 1.0, 1.0), (2.0, 2.0, 0.3))),
    "hip_Y": (0.0, ((5.0, 1.0, 2.0), (2.0, 2.0, 1.0))),
    "knee": (38.0, ((26.0, 1.0, -1.2), (8.0, 2.0, 0.4))),
    "knee_X": (0.0, ((2.0, 1.0, 0.3),)),
    "knee_Y": (0.0, ((5.0, 1.0, -1.0),)),
    "ankle_Z": (2.0, ((10.0, 1.0, -0.6), (5.0, 2.0, 0.2))),
    "ankle_X": (1.0, ((5.0, 1.0, 0.8),)),
}
_SUPINE_RIGHT: _Spec = {
    "hip_Z": (35.0, ((30.0, 1.0, 0.0), (4.0, 2.4, 0.7))),
    "hip_X": (0.0, ((1.5, 1.5, 0.2), (0.7, 4.4, 1.0))),
    "hip_Y": (0.0, ((2.0, 1.2, 0.5), (0.8, 3.6, 0.1))),
    "knee": (48.0, ((40.0, 1.0, -0.3), (5.0, 2.4, 0.9))),
    "knee_X": (0.0, ((1.0, 1.0, 0.0),)),
    "knee_Y": (0.0, ((3.0, 1.0, 0.4),)),
    "ankle_Z": (0.0, ((5.0, 1.0, 1.0),)),
    "ankle_X": (0.0, ((2.0, 1.3, 0.0),)),
}
_STILL_RIGHT: _Spec = {
    "hip_Z": (90.0, ((0.3, 1.0, 0.0), (0.1, 6.2, 1.0))),
    "hip_X": (0.0, ((0.2, 1.4, 0.3), (0.1, 5.4, 0.0))),
    "hip_Y": (0.0, ((0.2, 1.2, 0.8),)),
    "knee": (55.0, ((40.0, 1.0, 0.0), (8.0, 2.2, 0.5))),
    "knee_X": (0.0, ((0.5, 1.0, 0.0),)),
    "knee_Y": (0.0, ((2.0, 1.0, 0.3),)),
    "ankle_Z": (0.0, ((5.0, 1.0, 0.5),)),
    "ankle_X": (0.0, ((2.0, 1.0, 0.0),)),
}
_STATIC = {"knee": 0.0}
_STILL_LEFT = {"hip_Z": 90.0, "knee": 90.0}
_SUPINE_LEFT = {"knee": 5.0}
_BASE_HZ = {"gait": (0.85, 1.0), "supine_hip_flexion": (0.22, 0.28), "still_thigh": (0.45, 0.55)}


def _motion_name(motion: str) -> str:
    m = _ALIASES.get(motion, motion)
    if m not in MOTIONS:
        raise InputError(f"expected a motion in {MOTIONS}, got {motion!r}", field="motion")
    return m


def _angle_fns(motion: str, side: str, rng: np.random.Generator) -> dict[str, Sinusoids]:
    """Per joint suffix (``hip_Z``, ``knee``, ``knee_Z``, ...) a seeded :class:`Sinusoids`."""
    if motion == "static":
        const = _STATIC
    elif motion == "still_thigh" and side == "left":
        const = _STILL_LEFT
    elif motion == "supine_hip_flexion" and side == "left":
        const = _SUPINE_LEFT
    else:
        const = None
    if const is not None:
        out = {k: Sinusoids(np.deg2rad(v)) for k, v in const.items()}
        out["knee_Z"] = out["knee"]
        return out
    spec = {"gait": _GAIT, "supine_hip_flexion": _SUPINE_RIGHT, "still_thigh": _STILL_RIGHT}
    base = rng.uniform(*_BASE_HZ[motion])
    shift = rng.uniform(0, 2 * np.pi) + (np.pi if side == "left" else 0.0)
    out = {}
    for name, (off, terms) in spec[motion].items():
        scale = rng.uniform(0.9, 1.0, len(terms))  # never beyond the designed (limit-safe) range
        out[name] = Sinusoids(
            np.deg2rad(off),
            [np.deg2rad(a) * s for (a, _, _), s in zip(terms, scale, strict=True)],
            [base * f for _, f, _ in terms],
            [shift * f + p for _, f, p in terms],
        )
    out["knee_Z"] = out["knee"]
    return out


def _heading(amp_m: float, freq: float, phase: float, speed: float) -> Callable:
    """Heading ``psi = atan(y'/x')`` of the path ``(speed t, amp sin(2 pi f t + phase))``."""
    path = Sinusoids(0.0, [amp_m], [freq], [phase])

    def fn(t: np.ndarray):
        _, dy, ddy = path(t)
        w = 2 * np.pi * freq
        dddy = -(w**2) * dy
        u, du, ddu = dy / speed, ddy / speed, dddy / speed
        s = 1.0 + u * u
        return np.arctan(u), du / s, (ddu * s - 2 * u * du * du) / (s * s)

    return fn


def _pelvis(motion: str, t: np.ndarray, rng: np.random.Generator, height: float):
    """Pelvis ``R (N,3,3)``, body ``w``, ``dw``, world ``p``, ``dp``, ``ddp`` (N,3)."""
    n = t.size
    if motion != "gait":
        R0 = {"supine_hip_flexion": _SUPINE, "still_thigh": _STANDING}.get(motion, _STANDING)
        z = {"supine_hip_flexion": 0.15, "still_thigh": 0.55}.get(motion, height)
        p = np.tile([0.0, 0.0, z], (n, 1))
        zero = np.zeros((n, 3))
        return np.broadcast_to(R0, (n, 3, 3)).copy(), zero, zero, p, zero, zero
    f = rng.uniform(*_BASE_HZ["gait"])
    ph = rng.uniform(0, 2 * np.pi, 6)
    speed, weave, fw = rng.uniform(1.1, 1.3), rng.uniform(0.7, 0.9), 0.08
    R, w, dw = chain_kinematics(
        t,
        [
            (_Z, _heading(weave, fw, ph[0], speed)),
            _STANDING,
            (_Y, Sinusoids(0.0, [np.deg2rad(5.0)], [f], ph[1:2])),  # pelvis rotation (yaw)
            (_X, Sinusoids(0.0, [np.deg2rad(4.0)], [f], ph[2:3])),  # obliquity
            (_Z, Sinusoids(np.deg2rad(3.0), [np.deg2rad(2.0)], [2 * f], ph[3:4])),  # tilt
        ],
    )
    xyz = [
        Sinusoids(0.0, [0.01], [2 * f], ph[4:5], rate=speed),
        Sinusoids(0.0, [weave, 0.02], [fw, f], [ph[0], ph[5]]),
        Sinusoids(height, [0.02], [2 * f], ph[3:4]),
    ]
    p, dp, ddp = (np.stack([c(t)[k] for c in xyz], axis=1) for k in range(3))
    return R, w, dw, p, dp, ddp


def _freeflyer(skeleton: Skeleton) -> Skeleton:
    if skeleton.root == "freeflyer":
        return skeleton
    return Skeleton.from_urdf(skeleton.urdf_path, root="freeflyer")


def _standing_height(skeleton: Skeleton) -> float:
    """Pelvis origin height with the ankle centres 8 cm above the floor, neutral pose."""
    q = skeleton.neutral()
    side = skeleton.legs[0]
    return 0.08 - float(skeleton.relative_pose(f"{side}_AJC", "pelvis", q)[1, 3])


def joint_trajectories(
    skeleton: Skeleton, motion: str, time: np.ndarray, seed: int | np.random.Generator = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Exact ``q (N,nq)``, ``v (N,nv)``, ``a (N,nv)`` of ``motion`` on a free-flyer ``skeleton``.

    Free-flyer: ``q[:3] = p``, ``q[3:7]`` = quaternion (x, y, z, w) of ``R``; ``v[:3] = R^T p'``,
    ``v[3:6] = w`` (body); ``a[:3] = R^T p'' - w x v[:3]``, ``a[3:6] = w'``.
    """
    if skeleton.root != "freeflyer":
        raise InputError("expected a skeleton with root='freeflyer'", field="root")
    motion = _motion_name(motion)
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    t = np.asarray(time, dtype=float)
    model = skeleton.model
    q = np.zeros((t.size, model.nq))
    v = np.zeros((t.size, model.nv))
    a = np.zeros((t.size, model.nv))
    R, w, dw, p, dp, ddp = _pelvis(motion, t, rng, _standing_height(skeleton))
    vl = np.einsum("nji,nj->ni", R, dp)
    q[:, :3], q[:, 3:7] = p, quat_from_matrix(R)[:, [1, 2, 3, 0]]
    v[:, :3], v[:, 3:6] = vl, w
    a[:, :3], a[:, 3:6] = np.einsum("nji,nj->ni", R, ddp) - np.cross(w, vl), dw
    for side in skeleton.legs:
        fns = _angle_fns(motion, side, rng)
        for name in skeleton.joint_names:
            if not name.startswith(side + "_"):
                continue
            j = model.joints[model.getJointId(name)]
            fn = fns.get(name[len(side) + 1 :], Sinusoids(0.0))
            q[:, j.idx_q], v[:, j.idx_v], a[:, j.idx_v] = fn(t)
    return q, v, a


# ------------------------------------------------------------------------------------- truth


def knee_axis_in_segments(skeleton: Skeleton, side: str = "right") -> tuple[np.ndarray, np.ndarray]:
    """Unit hinge-knee axis (pointing right) in the femoral and tibial frames, read from the
    model: the LOCAL angular Jacobian column of the knee joint at the tibia frame."""
    name = f"{side}_knee"
    model = skeleton.model
    if not model.existJointName(name):
        raise InputError(f"expected a hinge knee joint {name!r} in the model", field="knee")
    data = model.createData()
    q = pin.neutral(model)
    fid = skeleton.frame_id(f"{side}_tibia")
    J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
    a_t = normalize(J[3:, model.joints[model.getJointId(name)].idx_v])
    a_t = a_t if a_t[2] >= 0 else -a_t  # z points to the subject's right on both legs
    pin.framesForwardKinematics(model, data, q)
    R_f = data.oMf[skeleton.frame_id(f"{side}_femur")].rotation
    R_t = data.oMf[fid].rotation
    return R_f.T @ R_t @ a_t, a_t


def _segment_of(imu: str) -> str:
    return _SEGMENT_OF_IMU.get(imu, imu.removesuffix("_imu"))


def _placements(skeleton: Skeleton, rng: np.random.Generator, mis_deg: float, off_m: float):
    q0 = skeleton.neutral()
    out = {}
    for imu in skeleton.imu_frames:
        T = skeleton.relative_pose(imu, _segment_of(imu), q0)
        axis = normalize(rng.normal(size=3))
        M = exp3(axis * np.deg2rad(mis_deg) * rng.uniform(0.5, 1.0))
        d = normalize(rng.normal(size=3)) * off_m * rng.uniform(0.5, 1.0)
        out[imu] = (T[:3, :3] @ M, T[:3, 3] + d, M, d)
    return out


def _joint_truth(skeleton: Skeleton, placements: dict) -> dict[str, dict[str, np.ndarray]]:
    q0 = skeleton.neutral()
    out: dict[str, dict[str, np.ndarray]] = {}
    for side in skeleton.legs:
        for joint, (seg1, seg2, centre) in _JOINT_SEGMENTS.items():
            entry = {}
            for seg in (seg1, seg2):
                seg_name = seg if seg == "pelvis" else f"{side}_{seg}"
                imu = f"{seg_name}_imu"
                c = skeleton.relative_pose(f"{side}_{centre}", seg_name, q0)[:3, 3]
                R, p = placements[imu][:2]
                entry[imu] = R.T @ (c - p)
            out[f"{side}_{joint}"] = entry
    return out


# ---------------------------------------------------------------------------------- simulation


def simulate_trial(
    skeleton: Skeleton | None = None,
    motion: str = "gait",
    *,
    duration_s: float = 15.0,
    rate_hz: float = 100.0,
    seed: int = 0,
    noise: SensorNoise | None = None,
    misalignment_deg: float = 15.0,
    offset_m: float = 0.02,
) -> SimulatedTrial:
    """Simulate ``motion`` on ``skeleton`` (reloaded with a free-flyer root if needed; None:
    a 1.75 m male :meth:`SubjectGeometry.default` with a hinge knee, in a temporary folder).

    Each IMU frame of the model gets a true sensor misaligned by a random rotation of
    ``misalignment_deg * U(0.5, 1)`` about a random axis and offset by ``offset_m * U(0.5, 1)``
    in a random direction. ``noise`` defaults to :class:`SensorNoise` ``()``.
    """
    motion = _motion_name(motion)
    if not (np.isfinite(duration_s) and duration_s > 0 and np.isfinite(rate_hz) and rate_hz > 0):
        raise InputError(f"expected positive duration and rate, got {duration_s}, {rate_hz}")
    n = int(round(duration_s * rate_hz))
    if n < 8:
        raise InputError(f"expected at least 8 samples, got {n}", field="duration_s")
    noise = SensorNoise() if noise is None else noise
    if skeleton is None:
        skeleton = Skeleton.build(SubjectGeometry.default(1.75, "m"), "hinge", root="freeflyer")
    skeleton = _freeflyer(skeleton)
    r_motion, r_place, r_noise = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(3)
    )
    t = np.arange(n) / rate_hz
    q, v, a = joint_trajectories(skeleton, motion, t, r_motion)
    lo, hi = skeleton.lower_limits[7:], skeleton.upper_limits[7:]
    if np.any(q[:, 7:] < lo - 1e-12) or np.any(q[:, 7:] > hi + 1e-12):
        raise RuntimeError(f"motion {motion!r} leaves the joint limits of {skeleton.urdf_path}")
    placements = _placements(skeleton, r_place, misalignment_deg, offset_m)

    model, data = skeleton.model, skeleton.data
    imus = list(placements)
    sensors = []  # (parent joint, placement in the joint frame)
    for imu in imus:
        seg = model.frames[skeleton.frame_id(_segment_of(imu))]
        sensors.append((seg.parentJoint, seg.placement * pin.SE3(*placements[imu][:2])))
    lm_names = skeleton.landmark_frames
    lm_ids = [skeleton.frame_id(x) for x in lm_names]
    k_imu = len(imus)
    R = np.empty((k_imu, n, 3, 3))
    P = np.empty((k_imu, n, 3))
    W = np.empty((k_imu, n, 3))
    A = np.empty((k_imu, n, 3))
    L = np.empty((len(lm_ids), n, 3))
    local = pin.ReferenceFrame.LOCAL
    for k in range(n):
        pin.forwardKinematics(model, data, q[k], v[k], a[k])
        for i, (jid, M) in enumerate(sensors):
            oM = data.oMi[jid] * M
            R[i, k], P[i, k] = oM.rotation, oM.translation
            W[i, k] = pin.getFrameVelocity(model, data, jid, M, local).angular
            A[i, k] = pin.getFrameClassicalAcceleration(model, data, jid, M, local).linear
        for i, fid in enumerate(lm_ids):
            L[i, k] = pin.updateFramePlacement(model, data, fid).translation
    F = A - np.einsum("knji,j->kni", R, GRAVITY)  # specific force, sensor frame

    out_imus = {}
    for i, imu in enumerate(imus):
        R_gs, p_gs, M, d = placements[imu]
        bias = r_noise.normal(0.0, noise.gyro_bias_sd, 3)
        gyr = W[i] + bias + r_noise.normal(0.0, noise.gyro_sd, (n, 3))
        acc = F[i] + r_noise.normal(0.0, noise.acc_sd, (n, 3))
        R_meas = R[i]
        if noise.orientation_sd_deg > 0:
            R_meas = R[i] @ exp3(r_noise.normal(0.0, np.deg2rad(noise.orientation_sd_deg), (n, 3)))
        rec = ImuRecording(time=t, gyr=gyr, acc=acc, quat=quat_from_matrix(R_meas))
        out_imus[imu] = SimulatedImu(
            frame=imu,
            segment=_segment_of(imu),
            recording=rec,
            rotation=R[i],
            position=P[i],
            R_segment=R_gs,
            p_segment=p_gs,
            misalignment=M,
            offset_m=d,
            gyro_bias=bias,
        )
    landmarks = {
        name: L[i] + r_noise.normal(0.0, noise.landmark_sd_m, (n, 3))
        for i, name in enumerate(lm_names)
    }
    knee_axis = {}
    if skeleton.knee == "hinge":
        for side in skeleton.legs:
            a_f, a_t = knee_axis_in_segments(skeleton, side)
            for seg, ax in (("femur", a_f), ("tibia", a_t)):
                imu = f"{side}_{seg}_imu"
                knee_axis[imu] = placements[imu][0].T @ ax
    return SimulatedTrial(
        time=t,
        q=q,
        v=v,
        a=a,
        motion=motion,
        seed=int(seed),
        imus=out_imus,
        knee_axis=knee_axis,
        joint_centres=_joint_truth(skeleton, placements),
        landmarks=landmarks,
        noise=noise,
        skeleton=skeleton,
    )
