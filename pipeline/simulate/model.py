"""Simulate a trial on a scaled model with Pinocchio: joint trajectories, IMU signals, landmarks.

The motions - exact joint trajectories ``q``, ``v``, ``a`` on a free-flyer root, sums of
sinusoids - are defined in :mod:`pipeline.simulate.motions` (``'gait'``,
``'supine_hip_flexion'``, ``'still_thigh'``, ``'static'``) and, by inverse kinematics on
prescribed feet, in :mod:`pipeline.simulate.walk` (``'walk'``). World frame: z up, gravity
``g = (0, 0, -9.81)``; segment frames ISB (x anterior, y proximal, z right).

Every angle stays inside the model's joint limits (checked). Signals at each sensor, from
``pin.forwardKinematics(model, data, q, v, a)``:

* gyroscope ``gyr = omega``: the angular velocity of the sensor frame in the sensor frame
  (``pin.getFrameVelocity``, LOCAL);
* accelerometer ``acc = R^T (p_ddot - g)`` (specific force, reads ``+9.81`` up at rest), with
  ``R^T p_ddot`` the classical acceleration of the sensor origin in the sensor frame
  (``pin.getFrameClassicalAcceleration``, LOCAL);
* magnetometer ``mag = R^T m`` with the earth's field :data:`MAGNETIC_FIELD` (uT, no
  disturbance).

The *true* sensor is the model's IMU frame (``<segment>_imu``) rotated by a random
sensor-to-segment misalignment and shifted by a random mounting offset: ``R_GS = R_imu M``,
``p_GS = p_imu + d`` (segment frame) - the truth a calibration has to recover. Then white noise,
a constant gyro bias per sensor, optional orientation noise and OMC-like landmark noise are added,
all from ``np.random.SeedSequence(seed)``: one stream for the motion, one for the placements
(so two motions with one seed share the sensor placements), one for the noise.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from pipeline.errors import InputError
from pipeline.io.recording import Recording, SensorSignals
from pipeline.io.sensor_names import MODEL_FRAME_NAMES
from pipeline.model.geometry import SubjectGeometry
from pipeline.model.skeleton import Skeleton
from pipeline.rotations import exp3, normalize, quat_from_matrix
from pipeline.simulate.artefacts import (
    SEGMENT_SCALE,
    Artefacts,
    floor_field,
    soft_tissue_motion,
    with_soft_tissue,
)
from pipeline.simulate.motions import joint_trajectories, motion_name, ramp, standing_start
from pipeline.simulate.walk import WalkPlan, walk_trajectories

__all__ = [
    "GRAVITY",
    "STANDING_LEAN_DEG",
    "MAGNETIC_FIELD",
    "SensorNoise",
    "SimulatedImu",
    "SimulatedTrial",
    "simulate_trial",
]

GRAVITY = np.array([0.0, 0.0, -9.81])
#: How far each leg leans forward, as a whole, in a standing start (deg, drawn uniformly): in
#: quiet standing the shank leans forward over the foot (on the real walk gaittoolbox_s02 the
#: optical joint centres put the tibias at 5.6 and 6.7 deg, the ankles at 6-8 deg of
#: dorsiflexion); the knee straight.
STANDING_LEAN_DEG = (2.0, 6.0)
#: The motions whose rest pose is standing (the others rest lying or seated).
STANDING_MOTIONS = ("gait", "walk", "static")
#: The earth's magnetic field in the simulator's world (x east, y north, z up; uT): 46 uT,
#: inclination 62 deg (central Europe).
MAGNETIC_FIELD = np.array([0.0, 21.6, -40.6])
_SEGMENT_OF_IMU = {"pelvis_imu": "pelvis"}
_JOINT_SEGMENTS = {"hip": ("pelvis", "femur", "HJC"), "knee": ("femur", "tibia", "KJC")}
_JOINT_SEGMENTS["ankle"] = ("tibia", "foot", "AJC")


@dataclass(frozen=True)
class SensorNoise:
    """White noise SDs (``gyro_sd`` rad/s, ``acc_sd`` m/s^2, ``mag_sd`` uT), constant gyro bias SD
    per axis (``gyro_bias_sd`` rad/s), orientation noise (``orientation_sd_deg`` per axis per
    sample) and landmark (marker) noise (``landmark_sd_m``). Defaults: consumer MEMS IMUs at
    100 Hz, an OMC
    system's sub-millimetre noise."""

    gyro_sd: float = 0.01
    acc_sd: float = 0.05
    gyro_bias_sd: float = 0.005
    orientation_sd_deg: float = 0.0
    mag_sd: float = 0.5
    landmark_sd_m: float = 0.0005

    @classmethod
    def none(cls) -> SensorNoise:
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


@dataclass(frozen=True)
class SimulatedImu:
    """One simulated sensor. ``recording``: noisy ``gyr``/``acc`` and the orientation ``quat``
    (sensor -> world, wxyz, + orientation noise). ``rotation`` (N,3,3) / ``position`` (N,3): true
    world pose of the sensor. ``R_segment``/``p_segment``: true sensor placement in its segment
    frame; ``misalignment`` (sensor axes in the model's IMU frame) and ``offset_m`` (segment frame)
    are its deviation from the model's IMU frame ``frame``."""

    frame: str
    segment: str
    recording: Recording
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
    ``walk``: the ``'walk'`` motion's :class:`~pipeline.simulate.walk.WalkPlan`, else None.
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
    walk: WalkPlan | None = None

    @property
    def recording(self) -> Recording:
        """All simulated sensors as one :class:`~pipeline.io.recording.Recording` (what a user's
        readers return: orientations, gyroscope and accelerometer signals)."""
        first = next(iter(self.imus.values())).recording
        sensors = {name: imu.recording.sensor for name, imu in self.imus.items()}
        return Recording(self.time, first.rate_hz, sensors, notes=(f"simulated {self.motion!r}",))

    def raw_recording(self, magnetometers: bool = True) -> Recording:
        """Raw signals only, each sensor named as ``pipeline ik`` reads it (``femur_r_imu``)."""
        keep = ("gyr", "acc", "mag") if magnetometers else ("gyr", "acc")
        rec = self.recording
        sensors = {MODEL_FRAME_NAMES[name]: SensorSignals(**{k: getattr(sig, k) for k in keep})
                   for name, sig in rec.sensors.items()}
        return Recording(self.time, rec.rate_hz, sensors)

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


# ------------------------------------------------------------------------------------- truth


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


def _real_world(skeleton, imus, placements, q, v, a, t, standing_s, R, P, W, AW, A, art, rng):
    """The sensors' poses and signals with soft tissue (:mod:`pipeline.simulate.artefacts`):
    ``(R, P, W, A)`` of the sensors themselves (A: classical acceleration, sensor frame)."""
    model = skeleton.model
    s = ramp(t, standing_s)[:3] if standing_s > 0 else (np.ones_like(t), 0 * t, 0 * t)

    def drive(names):
        cols = []
        for name in names:
            j = model.joints[model.getJointId(name)]
            cols.append((q[:, j.idx_q], v[:, j.idx_v], a[:, j.idx_v]))
        return tuple(np.stack([c[m] for c in cols], axis=1) for m in range(3))

    knee = "knee" if skeleton.knee == "hinge" else "knee_Z"
    R, P, W, A = R.copy(), P.copy(), W.copy(), A.copy()
    for i, imu in enumerate(imus):
        seg = _segment_of(imu)
        part = "pelvis" if seg == "pelvis" else seg.split("_", 1)[1]
        side = seg.split("_", 1)[0]
        names = {"pelvis": [f"{x}_hip_Z" for x in skeleton.legs],
                 "femur": [f"{side}_hip_Z", f"{side}_{knee}"],
                 "tibia": [f"{side}_{knee}", f"{side}_ankle_Z"],
                 "foot": [f"{side}_ankle_Z", f"{side}_ankle_X"]}[part]
        scale = SEGMENT_SCALE[part]
        long_axis = placements[imu][0].T @ np.array([0.0, 1.0, 0.0])  # segment y, sensor frame
        wobble = (np.deg2rad(art.wobble_deg), t, s) if part == "femur" else None
        delta, d = soft_tissue_motion(rng, drive(names), long_axis,
                                      np.deg2rad(art.soft_tissue_deg) * scale,
                                      art.soft_tissue_m * scale, wobble)
        R_i = R[i]
        P[i] = P[i] + np.einsum("nij,nj->ni", R_i, d[0])
        R[i], W[i], A_loc = with_soft_tissue(R_i, W[i], AW[i], A[i], delta, d)
        A[i] = np.einsum("nji,nj->ni", exp3(delta[0]), A_loc)  # into the sensor's own frame
    return R, P, W, A


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
    standing_s: float = 0.0,
    standing_lean_deg: tuple[float, float] = STANDING_LEAN_DEG,
    artefacts: Artefacts | None = None,
) -> SimulatedTrial:
    """Simulate ``motion`` on ``skeleton`` (reloaded with a free-flyer root if needed; None:
    a 1.75 m male :meth:`SubjectGeometry.default` with a hinge knee, built in memory).

    Each IMU frame of the model gets a true sensor misaligned by a random rotation of
    ``misalignment_deg * U(0.5, 1)`` about a random axis and offset by ``offset_m * U(0.5, 1)``
    in a random direction. ``noise`` defaults to :class:`SensorNoise` ``()``. ``standing_s > 0``
    starts the trial with that long still in the neutral standing pose, then a smooth transition
    into the motion (:func:`pipeline.simulate.motions.standing_start`): a calibration pose in the
    same continuous recording, as a lab records it. Standing (:data:`STANDING_MOTIONS`), each
    leg leans forward as a whole
    by ``U(*standing_lean_deg)`` degrees (hip flexion ``-lean``, knee 0, ankle dorsiflexion
    ``+lean``, the foot flat), as people stand (:data:`STANDING_LEAN_DEG`); ``(0, 0)``: upright.
    ``artefacts`` (:class:`~pipeline.simulate.artefacts.Artefacts`): soft tissue, wandering gyro
    bias, accelerometer bias and the floor's magnetic field, as real recordings have them (None:
    an ideal recording). The truth (``rotation``, ``position``) is then the sensor's own pose,
    soft tissue included; ``R_segment``/``p_segment`` its nominal placement.
    """
    motion = motion_name(motion)
    if not (np.isfinite(duration_s) and duration_s > 0 and np.isfinite(rate_hz) and rate_hz > 0):
        raise InputError(f"expected positive duration and rate, got {duration_s}, {rate_hz}")
    n = int(round(duration_s * rate_hz))
    if n < 8:
        raise InputError(f"expected at least 8 samples, got {n}", field="duration_s")
    noise = SensorNoise() if noise is None else noise
    if skeleton is None:
        skeleton = Skeleton.build(SubjectGeometry.default(1.75, "m"), "hinge", root="freeflyer")
    skeleton = skeleton.with_root("freeflyer")
    # streams by index (spawn's children do not depend on how many are spawned): the
    # magnetometer's noise has its own, so that adding it changed no other signal
    r_motion, r_place, r_noise, r_mag, r_posture, r_real = (
        np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(6)
    )
    t = np.arange(n) / rate_hz
    posture: dict[str, float] = {}
    if standing_s > 0 and motion in STANDING_MOTIONS:  # the others start lying or seated
        for side in skeleton.legs:
            lean = np.deg2rad(r_posture.uniform(*standing_lean_deg))
            posture[f"{side}_hip_Z"], posture[f"{side}_ankle_Z"] = -lean, lean
    plan = None
    if motion == "walk":
        q, v, a, plan = walk_trajectories(skeleton, t, standing_s, r_motion, posture)
    elif standing_s > 0:
        q, v, a = standing_start(skeleton, motion, t, standing_s, r_motion, posture)
    else:
        q, v, a = joint_trajectories(skeleton, motion, t, r_motion)
    lo, hi = skeleton.lower_limits[7:], skeleton.upper_limits[7:]
    if np.any(q[:, 7:] < lo - 1e-12) or np.any(q[:, 7:] > hi + 1e-12):
        raise InputError(f"motion {motion!r} leaves the joint limits of the model", field="motion")
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
    AW = np.empty((k_imu, n, 3))
    A = np.empty((k_imu, n, 3))
    L = np.empty((len(lm_ids), n, 3))
    local = pin.ReferenceFrame.LOCAL
    for k in range(n):
        pin.forwardKinematics(model, data, q[k], v[k], a[k])
        for i, (jid, M) in enumerate(sensors):
            oM = data.oMi[jid] * M
            R[i, k], P[i, k] = oM.rotation, oM.translation
            W[i, k] = pin.getFrameVelocity(model, data, jid, M, local).angular
            AW[i, k] = pin.getFrameAcceleration(model, data, jid, M, local).angular
            A[i, k] = pin.getFrameClassicalAcceleration(model, data, jid, M, local).linear
        for i, fid in enumerate(lm_ids):
            L[i, k] = pin.updateFramePlacement(model, data, fid).translation
    if artefacts is not None:
        R, P, W, A = _real_world(skeleton, imus, placements, q, v, a, t, standing_s, R, P, W, AW,
                                 A, artefacts, r_real)
    F = A - np.einsum("knji,j->kni", R, GRAVITY)  # specific force, sensor frame

    out_imus = {}
    for i, imu in enumerate(imus):
        R_gs, p_gs, M, d = placements[imu]
        bias = r_noise.normal(0.0, noise.gyro_bias_sd, 3)
        gyr = W[i] + bias + r_noise.normal(0.0, noise.gyro_sd, (n, 3))
        acc = F[i] + r_noise.normal(0.0, noise.acc_sd, (n, 3))
        field = np.tile(MAGNETIC_FIELD, (n, 1))
        if artefacts is not None:
            walk = r_real.normal(0.0, artefacts.gyro_bias_walk / np.sqrt(rate_hz), (n, 3))
            gyr = gyr + np.cumsum(walk, axis=0)
            acc = acc + r_real.normal(0.0, artefacts.acc_bias_sd, 3)
            field = field + floor_field(P[i], r_real, artefacts.floor_field_ut,
                                        artefacts.floor_decay_m)
        R_meas = R[i]
        if noise.orientation_sd_deg > 0:
            R_meas = R[i] @ exp3(r_noise.normal(0.0, np.deg2rad(noise.orientation_sd_deg), (n, 3)))
        mag = np.einsum("nji,nj->ni", R[i], field) + r_mag.normal(0.0, noise.mag_sd, (n, 3))
        rec = Recording.single(imu, t, gyr=gyr, acc=acc, mag=mag, quat=quat_from_matrix(R_meas),
                               rate_hz=rate_hz)
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
            a_f, a_t = skeleton.knee_axis(side)
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
        walk=plan,
        imus=out_imus,
        knee_axis=knee_axis,
        joint_centres=_joint_truth(skeleton, placements),
        landmarks=landmarks,
        noise=noise,
        skeleton=skeleton,
    )
