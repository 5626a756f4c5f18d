"""The heading between two sensors across one joint, from the joint's constraint: the building
blocks of :mod:`pipeline.process.heading_alignment`.

A ball joint (hip, ankle) by the specific force at its centre (:func:`ball_heading`, the centre
from Hu 2021's spherical fit, :func:`centre_fit`); the knee by its trusted hinge axes, else by the
better of its centre's force and the segments' flexion axes (:func:`knee_heading`,
:func:`flexion_heading`); each solves eq (1) of :mod:`pipeline.calibration.heading_offset` on
windows of :data:`WINDOW_S`.
"""

from __future__ import annotations

from functools import partial

import numpy as np

from pipeline.calibration.flexion_axis import FlexionAxis, knee_signs, leg_flexion_axes
from pipeline.calibration.heading_offset import (
    MIN_ACCELERATION,
    HeadingDrift,
    heading_between,
    hinge_heading,
)
from pipeline.errors import InputError
from pipeline.io.recording import Recording
from pipeline.io.sensor_names import SEGMENT_SENSOR

__all__ = ["CENTRE_BOUND_M", "CUTOFF_HZ", "MAX_HINGE_RESIDUAL_DEG", "MAX_RESIDUAL_DEG", "UP",
           "WINDOW_S", "ball_heading", "breaks_of", "centre_fit", "flexion_heading",
           "has_signals", "knee_heading", "leg_axes", "own_rows", "signals_of"]

#: The model's world vertical (y up).
UP = np.array([0.0, 1.0, 0.0])
#: Window of eq (1) (s): several whole strides (a stride takes ~1-1.3 s).
WINDOW_S = 4.0
#: Low-pass cut-off (Hz) of the signals the hip's and ankle's centre force is computed from: on
#: the simulator 4 Hz already bent the force's harmonics (the hips' headings 2.1-2.8 deg off,
#: 0.8-1.9 at 6 Hz); on the real walk 6 Hz keeps every hip and ankle window that agrees.
CUTOFF_HZ = 6.0
#: A joint's heading is not used when the constraint's RMS residual after the turn (the angle
#: between the two sensors' views of its axis or centre force, over the windows used) exceeds
#: this (deg). The simulated joints leave 0.1-1 deg; the real walk gaittoolbox_s02 4.6-6.8 deg
#: (knees and ankles) and 3-4 deg (hips); the x-IMU3 recording's knees and ankles 11-15 deg.
MAX_RESIDUAL_DEG = 20.0
#: The trusted hinge axes hold a hinge exactly (0.1-0.4 deg on the simulator's hinge): beyond this
#: the knee is not one (the simulator's free knee with soft tissue: 18.7 deg, and 150 deg off) and
#: the knee centre or the flexion axes take over.
MAX_HINGE_RESIDUAL_DEG = 10.0
#: Bound (m) of a joint centre's components in its sensor's frame in the centre's fit here: past
#: any lower-limb sensor's distance from its joint (S02's knees: 0.34 m along their axis), so that
#: it binds nowhere and the fit ends alike however the sensors sit (0.3 m bound S02's knees).
CENTRE_BOUND_M = 0.5


#: One leg's segments from the pelvis down: a filter started again above a pair moves the
#: heading of every sensor turned into the pelvis's through it.
_CHAIN = ("pelvis", "femur", "tibia", "foot")


def breaks_of(trial: Recording, dist: str) -> np.ndarray | None:
    """The rows across which the heading of segment ``dist`` relative to the one above it may
    jump: the gaps of the sensors from the pelvis down to it whose filter started again after
    them (:attr:`~pipeline.io.gaps.Missing.restarted`); None without any."""
    side, _, kind = dist.partition("_")
    chain = _CHAIN[: _CHAIN.index(kind or side) + 1]
    names = [SEGMENT_SENSOR[seg if seg == "pelvis" else f"{side}_{seg}"] for seg in chain]
    out = trial.missing.breaks(names, trial.n_samples)
    return out if out.any() else None


def own_rows(trial: Recording, *segments: str) -> np.ndarray | slice:
    """The rows the sensors of ``segments`` all have of their own (every row: ``slice(None)``)."""
    own = trial.present(*(SEGMENT_SENSOR[s] for s in segments))
    return slice(None) if own.all() else np.flatnonzero(own)


def has_signals(trial: Recording, segment: str) -> bool:
    s = trial.sensors.get(SEGMENT_SENSOR[segment])
    return s is not None and s.gyr is not None and s.acc is not None


def signals_of(trial: Recording, segment: str):
    if not has_signals(trial, segment):
        raise InputError("raw gyroscope and accelerometer signals of both sensors are needed")
    return trial.sensors[SEGMENT_SENSOR[segment]]


def knee_heading(trial, R_1, R_2, prox, dist, side, knees, axes,
                 method) -> tuple[HeadingDrift, str]:
    """The knee's heading by the trusted hinge axes where they hold, else by whichever of the knee
    centre's force and the segments' flexion axes the data hold better: the smaller residual,
    within :data:`MAX_RESIDUAL_DEG` where either is (module docstring)."""
    c = next((k for k in knees if k.side == side and k.axes_trusted), None)
    if c is not None:  # the fit leaves each axis's sign free: the knee's flexion signs them
        rows = own_rows(trial, prox, dist)
        s_1, s_2 = knee_signs(*(np.einsum("nji,j->ni", R[rows], UP) for R in (R_1, R_2)),
                              c.axis_thigh, c.axis_shank, trial.rate_hz)
        drift = hinge_heading(R_1, R_2, s_1 * c.axis_thigh, s_2 * c.axis_shank, trial.rate_hz,
                              up=UP, window_s=WINDOW_S, breaks=breaks_of(trial, dist))
        if drift.residual_deg <= MAX_HINGE_RESIDUAL_DEG:
            return drift, "the knee's hinge axis"
    solvers = {
        "the knee centre's acceleration": partial(ball_heading, trial, R_1, R_2, prox, dist,
                                                  method),
        "the segments' flexion axes": partial(flexion_heading, trial, R_1, R_2, axes, prox,
                                              dist)}
    found, why = {}, None  # how -> its drift
    for how, solve in solvers.items():
        try:
            found[how] = solve()
        except InputError as e:
            why = e
    if not found:
        raise why
    held = {k: d for k, d in found.items() if d.residual_deg <= MAX_RESIDUAL_DEG} or found
    best = min(held, key=lambda k: held[k].residual_deg)
    return held[best], best + "".join(f", not {k} (its residual {d.residual_deg:.1f} deg)"
                                      for k, d in held.items() if k != best)


def leg_axes(trial: Recording, rotations, side: str) -> dict[str, FlexionAxis] | str:
    """One leg's flexion axes in its sensors' frames, or why there are none."""
    segments, have = {}, []
    for seg in ("femur", "tibia"):
        name = f"{side}_{seg}"
        s = trial.sensors.get(SEGMENT_SENSOR[name])
        if name in rotations and s is not None and s.gyr is not None:
            up = np.einsum("nji,j->ni", rotations[name], UP)  # the vertical in the sensor frame
            segments[seg], have = (s.gyr, up), [*have, name]
    rows = own_rows(trial, *have) if have else slice(None)  # the samples both sensors have
    segments = {seg: (g[rows], u[rows]) for seg, (g, u) in segments.items()}
    try:
        return {f"{side}_{k}": a for k, a in leg_flexion_axes(trial.rate_hz, segments).items()}
    except InputError as e:
        return e.message


def flexion_heading(trial: Recording, R_1, R_2, axes, prox: str, dist: str) -> HeadingDrift:
    """Eq (1) on the two segments' flexion axes (module docstring)."""
    if isinstance(axes, str):
        raise InputError(f"no flexion axes: {axes}")
    if prox not in axes or dist not in axes:
        raise InputError("raw gyroscope signals of both sensors are needed")
    return hinge_heading(R_1, R_2, axes[prox].axis, axes[dist].axis, trial.rate_hz, up=UP,
                         window_s=WINDOW_S, breaks=breaks_of(trial, dist))


def centre_fit(trial: Recording, R_1, R_2, prox: str, dist: str, method: str):
    """Hu's spherical fit of the joint on both signals low-passed at :data:`CUTOFF_HZ`, and those
    signals. IPOPT (the default) starts from the centre's vertical constraint (module docstring);
    ``gn``, ``dwpso``, ``gwo`` from their own random starts in the sensors' frames."""
    from pipeline.calibration.joint_centres import joint_centre
    from pipeline.process.functional import fit_joint

    rate = trial.rate_hz
    s1, s2 = (signals_of(trial, seg) for seg in (prox, dist))
    rows = own_rows(trial, prox, dist)  # not over a sensor's bridged gap
    options = {}
    if method == "ipopt":  # started alike however the sensors sit (the vertical's part of eq 2)
        c = joint_centre(trial.time, s1.gyr, s1.acc, R_1, s2.gyr, s2.acc, R_2, rows=rows,
                         cutoff_hz=CUTOFF_HZ, shared_axis=1)
        options = {"start": (c.o_1, c.o_2), "position_bound": CENTRE_BOUND_M}
    s1, s2 = (s.low_passed(rate, CUTOFF_HZ) for s in (s1, s2))
    return fit_joint(trial.time, s1, s2, rows, method, shared_world=False,
                     joint="spherical", verify_start=False, **options), s1, s2


def ball_heading(trial: Recording, R_1, R_2, prox: str, dist: str, method: str) -> HeadingDrift:
    """Eq (1) on the specific force at the joint's centre (module docstring)."""
    from pipeline.calibration.joint_constraints import joint_data, joint_force

    fit, s1, s2 = centre_fit(trial, R_1, R_2, prox, dist, method)
    # no observability test: a direction the fit leaves free moves the centre without changing
    # its force much; the constraint's residual after the turn is the check (MAX_RESIDUAL_DEG)
    data = joint_data(trial.time, s1.gyr, s1.acc, s2.gyr, s2.acc)
    f1, f2 = joint_force(data, fit.position_1_m, fit.position_2_m)
    u, v = (np.einsum("nij,nj->ni", R, f) for R, f in ((R_1, f1), (R_2, f2)))
    return heading_between(u, v, trial.rate_hz, up=UP, window_s=WINDOW_S,
                           min_weight=MIN_ACCELERATION**2,
                           breaks=breaks_of(trial, dist))
