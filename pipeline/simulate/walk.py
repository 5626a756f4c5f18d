"""A skeleton that walks through the room: feet that stand on the floor, the pelvis carried by
the legs (the ``'walk'`` motion of :func:`pipeline.simulate.model.simulate_trial`).

The other motions turn the joints by sinusoids, so their feet slide and never rest; a walk's
truth for the pelvis's path and for zero-velocity updates needs feet that stay put while in
contact. Here the feet's poses are prescribed and the legs follow by inverse kinematics:

* **Path.** The pelvis moves along a path of arc length ``s_p(tau) = v (tau - c) + v c
  exp(-tau / c)`` (at rest at ``tau = 0``, then at the walking speed ``v = L / T``; ``c = 0.35 T``
  lets the first step be half a stride), heading ``psi(s)`` turning by ``turn_deg`` on a quintic
  smoothstep over :data:`TURN_LENGTH_M`, on the motion clock ``tau`` of
  :func:`pipeline.simulate.motions.ramp` (standing still first). It sways about that path
  (:data:`PELVIS_SWAY_M`: toward the stance foot, and behind and ahead of its mean walk, slowest
  at each mid-stance) and comes down from its standing height by a smooth upper envelope of what
  the feet ask (:data:`REACH`: no ankle farther from its hip than 99.5 % of the leg, the knee
  then flexed ~9 deg; a moving maximum over +-:data:`SMOOTHING_S` then a Gaussian), so that it is
  lowest in double support and the stance knee nearly straight at mid-stance, as in gait
  (measured once by hand, 1st-99th percentiles over two seeds' walks: knees 12-54 deg, hips
  -14-35 deg, the pelvis 3-4 cm up and down; the real walk S02's Vicon knees -6-63 deg, hips
  -17-34 deg; a constant drop, before, kept the knees above 26 deg). Tried, not kept: 99.9 %
  and a 10 cm swing lift give knees 5-65, hips -17-42 and ankles -13-29 deg (seeds 0-2), like
  S02's, but the faster swing raises the joint-centre fits' residuals (ankles 0.6-1.6 m/s^2
  against 0.5-1.0 here; the real S02's 0.3, the x-IMU3 walk's 1.0: the simulated soft tissue,
  linear in the joint angles, accelerates with them) and a 6-D hip's heading alignment then
  fails on one mounting (``scripts/bench_sensor_sets.py``: 12.9 deg); first the simulated soft
  tissue must lag and damp as real tissue does.
  The pelvis turns with the stride as a walking pelvis does (:data:`PELVIS_TURN_DEG`): about the
  vertical and forward axes once per stride, about the lateral axis twice.
* **Feet** (per stride ``T`` from an initial contact IC, as
  :mod:`pipeline.simulate.foot_walk`): the foot turns about its lateral axis in raised-cosine
  lobes (loading ``+20 deg`` -> flat in ``[0, 0.1 T]``, push-off ``-40 deg`` in
  ``[0.45 T, 0.75 T]``, swing ``+60 deg`` in ``[0.75 T, T]``); it pivots about its heel during
  loading, rests flat on its footprint in ``[0.1 T, 0.45 T]``, pivots about its toe during
  push-off until the final contact FC ``= 0.6 T``, and swings to the next footprint on a
  minimum-jerk blend of the two pivots (Flash & Hogan 1985) lifted by ``64 u^3 (1 - u)^3``
  :data:`CLEARANCE_M`. The foot is not a sagittal hinge either: it lands inverted by a few
  degrees, everts to flat in the same lobe as it pitches, inverts in push-off and swings back
  (:data:`FOOT_INVERSION_DEG`). Measured once by hand (seed 0, 4 Hz low-pass, straight
  walking): about the foot's long axis its sensor turns at 0.5-0.6 rad/s RMS (0.5 without the
  inversion; the real S02 feet 0.5-0.7), its angular acceleration there 5-7 rad/s^2 (S02 9-10),
  and one foot sensor's motion determines a point on it with conditioning 0.16-0.20 (0.14
  without; S02 0.41-0.46): the real foot's rotations off the sagittal plane are quicker, not
  larger, and the simulator does not have them yet. A skeleton built with ``ankle='free'``
  turns the tibia on its planted foot as the foot inverts (:mod:`pipeline.simulate.subtalar`);
  the model's two-axis ankle keeps it from turning. A toe-out of the swinging foot, tried (5-20
  deg), turned the femur about its long axis more than S02's; not kept.
  Footprints lie a hip's half-width either side of the path, where the pelvis passes at
  mid-stance, turned to the path's heading. The right foot pushes off first; the left stays flat
  on its standing footprint until half a stride later.
* **Legs.** Each sample, the hip (3 DoF), knee flexion and ankle (2 DoF; a free ankle's third
  angle set first, as the knee's coupled ones) solve the foot's pose exactly (Newton on
  ``log6``, Pinocchio's frame Jacobian); a free knee is not a hinge: its
  adduction and rotation follow its flexion and the stride (:mod:`pipeline.simulate.knee`), a
  hinge knee stays a hinge. ``v`` and ``a`` are five-point central differences on a grid four
  times finer than the trial's (errors ``O(dt^4)``), the root's as
  :func:`pipeline.simulate.motions.joint_trajectories` defines them.

:func:`walk_plan` gives the truth the gait analysis must recover (events, footprints).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.ndimage import maximum_filter1d

from pipeline.errors import InputError
from pipeline.model.skeleton import Skeleton
from pipeline.progress import step
from pipeline.rotations import quat_xyzw_from_matrix, rot_x, rot_y, rot_z
from pipeline.simulate.chain import UPRIGHT
from pipeline.simulate.knee import Knee, draw_knee, flexion_reaching
from pipeline.simulate.motions import ramp, standing_height
from pipeline.simulate.subtalar import ankle_turns
from pipeline.simulate.walk_feet import (
    CLEARANCE_M,
    MID_STANCE,
    TURN_LENGTH_M,
    WalkPlan,
    arc_length,
    foot_poses,
    leg_length,
    walk_plan,
)

__all__ = ["CLEARANCE_M", "FOOT_INVERSION_DEG", "PELVIS_SWAY_M", "PELVIS_TURN_DEG", "REACH",
           "SMOOTHING_S", "TURN_LENGTH_M", "WalkPlan", "walk_plan", "walk_trajectories"]

#: The hip-to-ankle distance at most, a share of the leg's length (the knee flexed ~9 deg), and
#: the half-width (s) of the pelvis height's envelope (module docstring).
REACH, SMOOTHING_S = 0.995, 0.1
#: The pelvis's sway about its path (m): toward the stance foot (once per stride) and behind and
#: ahead of its mean walk (twice per stride, its speed +-8 %), as in gait (Perry & Burnfield,
#: Gait Analysis, 2010, ch. 10: about 4 cm from side to side).
PELVIS_SWAY_M = (0.02, 0.01)
#: Amplitudes (deg) of the walking pelvis's rotation (about the vertical), obliquity (about the
#: forward axis) and anterior tilt (about the lateral axis, twice per stride): Perry & Burnfield
#: (Gait Analysis, 2010, ch. 10) give +-4, +-4, +-2 for an average walker, the rotation growing
#: with speed (Bruijn et al. 2008, Gait Posture 27:455). Sized by both real walks' pelvis sensors
#: (``scripts/bench_sim_realism.py``): a swing of 12.6 deg a stride and 0.65 rad/s (S02 13.1 and
#: 0.73, the x-IMU3 walk 14.4 and 0.68), where +-4, +-4, +-2 gave 8.6 and 0.50. The simulated
#: walk's figures other modules give as measured once by hand were taken with those, but for the
#: ones the limits of :mod:`pipeline.process.sides`, :mod:`~pipeline.process.swap` and
#: :mod:`~pipeline.process.slip` rest on (measured again); the benchmarks are regenerated.
PELVIS_TURN_DEG = (6.0, 5.0, 2.5)
#: The foot's inversion (deg, the sole turned medially) at initial contact and at the end of
#: push-off, drawn per leg: it lands a little inverted and everts to flat in the loading
#: response, then inverts as the heel rises about the oblique metatarsophalangeal line and the
#: subtalar joint supinates (Bojsen-Moller 1979, Acta Orthop Scand 50:471; Leardini et al. 2007,
#: Gait Posture 25:453-462: the rearfoot's frontal range in walking ~10 deg), and swings back.
FOOT_INVERSION_DEG = ((2.0, 5.0), (5.0, 10.0))
ANKLE_HEIGHT_M = 0.08  # the model's ankle centre above the floor (motions.standing_height)
_FINE = 4  # the kinematics' grid, times finer than the trial's


def _five_point(x: np.ndarray, h: float) -> np.ndarray:
    """First derivative along axis 0 by five-point central differences (one-sided at the ends
    are not needed: the caller trims two samples each side)."""
    d = np.zeros_like(x)
    d[2:-2] = (x[:-4] - 8 * x[1:-3] + 8 * x[3:-1] - x[4:]) / (12 * h)
    return d


def _solve_leg(
    skeleton: Skeleton, q: np.ndarray, side: str, target: pin.SE3, free: list[int], knee: Knee,
    extra: np.ndarray,
) -> np.ndarray:
    """The leg's joints that put its foot frame at ``target``: the knee (flexion and the angles
    coupled to it, ``extra`` the stride's terms; :func:`pipeline.simulate.knee.flexion_reaching`)
    from the hip centre's distance to the ankle's, then the hip's three and the ankle's two
    angles (v indices ``free``) by Newton steps on the pose's ``log6`` error (six equations, five
    unknowns, consistent once the knee is set)."""
    model, data = skeleton.model, skeleton.data
    fid, hip = skeleton.frame_id(f"{side}_foot"), skeleton.frame_id(f"{side}_HJC")
    pin.framesForwardKinematics(model, data, q)
    d2 = float(np.sum((target.translation - data.oMf[hip].translation) ** 2))
    q = q.copy()
    flexion_reaching(skeleton, knee, q, d2, extra, side)
    for _ in range(12):
        pin.framesForwardKinematics(model, data, q)
        err = pin.log6(data.oMf[fid].actInv(target)).vector
        if np.linalg.norm(err) < 1e-10:
            return q
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)[:, free]
        dv = np.zeros(model.nv)
        dv[free] = np.linalg.lstsq(J, err, rcond=None)[0]
        q = pin.integrate(model, q, dv)
    if np.linalg.norm(err) < 1e-7:  # the straight knee's rounding
        return q
    raise InputError(f"the {side} leg did not converge to its foot's pose in the simulated walk",
                     field="motion")


def walk_trajectories(
    skeleton: Skeleton, time: np.ndarray, standing_s: float, rng: np.random.Generator,
    posture: dict[str, float] | None = None,
):
    """``q, v, a`` (as :func:`pipeline.simulate.motions.joint_trajectories`) and the
    :class:`WalkPlan` of a walk after ``standing_s`` s standing in ``posture`` (module
    docstring)."""
    if skeleton.root != "freeflyer":
        raise InputError("expected a skeleton with root='freeflyer'", field="root")
    t = np.asarray(time, dtype=float)
    dt = (t[1] - t[0]) / _FINE if t.size > 1 else 0.01
    tf = t[0] + dt * np.arange(-4, _FINE * (t.size - 1) + 5)
    s, _, _, tau = ramp(tf, float(standing_s))
    model = skeleton.model
    q0 = skeleton.neutral()
    z0 = standing_height(skeleton)
    q0[:3], q0[3:7] = [0.0, 0.0, z0], quat_xyzw_from_matrix(UPRIGHT)
    for name, angle in (posture or {}).items():
        q0[skeleton.q_index(name)] = angle
    skeleton.forward(q0)
    feet = {x: skeleton.data.oMf[skeleton.frame_id(f"{x}_foot")].translation.copy()
            for x in skeleton.legs}
    plan = walk_plan(skeleton, float(tf[-1] - standing_s), rng, feet)
    foot_len = 0.31 * leg_length(skeleton)  # foot 0.152, leg 0.485 of the height
    heel = np.array([-0.25 * foot_len, -ANKLE_HEIGHT_M, 0.0])
    toe = np.array([0.55 * foot_len, -ANKLE_HEIGHT_M, 0.0])
    sp = arc_length(plan.T, plan.speed, tau)
    R = rot_z(plan.heading(sp)) @ UPRIGHT @ _pelvis_turns(tau / plan.T, s, rng)
    knee = {x: draw_knee(skeleton, x, rng) for x in skeleton.legs}
    inversion = {x: np.deg2rad([rng.uniform(*r) for r in FOOT_INVERSION_DEG])
                 for x in skeleton.legs}
    poses = {x: foot_poses(plan, x, tau, heel, toe, inversion[x]) for x in skeleton.legs}
    p = np.concatenate([plan.path(sp) + s[:, None] ** 2 * _sway(plan, tau, sp),
                        np.full((tf.size, 1), z0)], axis=1)
    p[:, 2] -= _pelvis_drop(skeleton, p, R, poses, s, dt)
    extra = {x: knee[x].stride_angles(2 * np.pi * tau / plan.T, s) for x in skeleton.legs}
    # solved: the hip's three and the ankle's flexion and inversion (chain order Z, X); a free
    # ankle's third angle is set, as the knee's coupled ones
    free = {x: [model.joints[model.getJointId(n)].idx_v for n in (
        *skeleton.leg_joints(x, "hip"), *skeleton.leg_joints(x, "ankle")[:2])]
        for x in skeleton.legs}
    subtalar = ankle_turns(skeleton, {x: poses[x][2] for x in skeleton.legs}, rng)
    Q = np.empty((tf.size, model.nq))
    qk = q0.copy()
    pelvis_q = quat_xyzw_from_matrix(R)
    for k in range(tf.size):
        if k % 500 == 0:
            step(f"the legs' joints: {k / tf.size:.0%} of the walk")
        qk[:3], qk[3:7] = p[k], pelvis_q[k]
        for index, angle in subtalar:
            qk[index] = angle[k]
        for x in skeleton.legs:
            qk = _solve_leg(skeleton, qk, x, pin.SE3(poses[x][0][k], poses[x][1][k]), free[x],
                            knee[x], extra[x][k])
        Q[k] = qk
    return (*_derivatives(Q, p, R, dt), plan)


def _pelvis_turns(phase: np.ndarray, s: np.ndarray, rng) -> np.ndarray:
    """(N, 3, 3) the pelvis's turns in its own frame at stride ``phase`` (strides since the
    walk's start), ramped in by ``s**2`` (module docstring, :data:`PELVIS_TURN_DEG`)."""
    rotation, obliquity, tilt = np.deg2rad(PELVIS_TURN_DEG)
    theta = 2 * np.pi * phase + rng.uniform(0, 2 * np.pi)
    ramp = s**2
    return (rot_y(rotation * ramp * np.sin(theta)) @ rot_x(obliquity * ramp * np.cos(theta))
            @ rot_z(tilt * ramp * np.sin(2 * theta)))


def _sway(plan: WalkPlan, tau: np.ndarray, sp: np.ndarray) -> np.ndarray:
    """(N, 2) the pelvis's horizontal sway about its path (module docstring,
    :data:`PELVIS_SWAY_M`): toward each foot at its mid-stance, behind and ahead twice per
    stride (slowest at each mid-stance)."""
    side_m, forward_m = PELVIS_SWAY_M
    psi = plan.heading(sp)
    phase = 2 * np.pi * (tau / plan.T - MID_STANCE)  # the right foot's mid-stance at 0
    right = np.stack([np.sin(psi), -np.cos(psi)], axis=1)
    ahead = np.stack([np.cos(psi), np.sin(psi)], axis=1)
    return (side_m * np.cos(phase)[:, None] * right
            - forward_m * np.sin(2 * phase)[:, None] * ahead)


def _pelvis_drop(skeleton, p, R, poses, s, dt) -> np.ndarray:
    """How far the pelvis comes down from standing (m, per sample): ``s`` times a smooth upper
    envelope of what each sample needs divided by ``s`` (a moving maximum over
    +-:data:`SMOOTHING_S`, then a Gaussian of that support, which cannot fall below it), where
    a sample needs the least drop that keeps every ankle within ``(1 - (1 - REACH) s)`` of the
    leg's length from its hip (module docstring). Zero standing (``s = 0``)."""
    q = skeleton.neutral()
    leg = leg_length(skeleton)
    need = np.zeros(s.size)
    for x in skeleton.legs:
        hjc = skeleton.relative_pose(f"{x}_HJC", "pelvis", q)[:3, 3]
        d = poses[x][1] - (p + R @ hjc)
        room = ((1 - (1 - REACH) * s) * leg) ** 2 - d[:, 0] ** 2 - d[:, 1] ** 2
        if np.any(room <= 0):
            raise InputError("the simulated walk's steps are longer than the legs", field="motion")
        need = np.maximum(need, -d[:, 2] - np.sqrt(room))  # <= 0: none
    moving = s > 1e-6
    per_s = np.where(moving, need / np.where(moving, s, 1.0), 0.0).clip(min=0.0)
    h = max(int(round(SMOOTHING_S / dt)), 1)
    kernel = np.exp(-0.5 * (np.arange(-h, h + 1) / (0.5 * h)) ** 2)
    padded = np.pad(maximum_filter1d(per_s, 2 * h + 1, mode="nearest"), h, mode="edge")
    return s * np.convolve(padded, kernel / kernel.sum(), mode="valid")


def _derivatives(Q: np.ndarray, p: np.ndarray, R: np.ndarray, dt: float):
    """``q, v, a`` on the trial's samples from the fine grid (module docstring)."""
    v = np.empty((Q.shape[0], Q.shape[1] - 1))
    a = np.empty_like(v)
    dp = _five_point(p, dt)
    ddp = _five_point(dp, dt)
    dR = _five_point(R, dt)
    W = np.einsum("nji,njk->nik", R, dR)
    w = 0.5 * np.stack([W[:, 2, 1] - W[:, 1, 2], W[:, 0, 2] - W[:, 2, 0],
                        W[:, 1, 0] - W[:, 0, 1]], axis=1)
    dw = _five_point(w, dt)
    vl = np.einsum("nji,nj->ni", R, dp)
    v[:, :3], v[:, 3:6] = vl, w
    a[:, :3], a[:, 3:6] = np.einsum("nji,nj->ni", R, ddp) - np.cross(w, vl), dw
    dq = _five_point(Q[:, 7:], dt)
    v[:, 6:], a[:, 6:] = dq, _five_point(dq, dt)
    keep = slice(4, Q.shape[0] - 4 + 1, _FINE)
    return Q[keep], v[keep], a[keep]
