"""The one entry to joint-constraint calibration (Hu et al. 2021): :func:`calibrate`.

``method``:

* ``'ipopt'`` (default): one IPOPT problem over both constraints with optional robust losses and
  axis priors (:func:`pipeline.calibration.ipopt.calibrate_ipopt`); the most accurate and the
  fastest on the simulated trials (``scripts/bench_calibration.py``).
* ``'gn'``: Gauss-Newton on each constraint with random restarts (Hu eq 7-15).
* ``'dwpso'`` / ``'gwo'``: the paper's swarm optimisers (eq 17-24 / 25-29), seeded.

**Verification.** A result is called determined only when the observability test finds every
direction determined *and* an independent start (``seed + 1``) reaches the same solution: axes
within :data:`AGREEMENT_DEG`, joint positions within :data:`AGREEMENT_M` (both after the eq-16
projection). A swarm that stopped before converging, or a cost with several minima, is then
reported as undetermined with the disagreement, never returned as a trustworthy result.

CasADi is imported only when ``'ipopt'`` runs; the names of the methods live in
:mod:`pipeline.calibration.conventions`.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from pipeline.calibration.conventions import DEFAULT_METHOD, JOINTS, METHODS
from pipeline.calibration.joint_constraints import JointData
from pipeline.calibration.solvers import CalibrationResult, calibrate_classic
from pipeline.errors import InputError
from pipeline.rotations import angle_between

__all__ = ["AGREEMENT_DEG", "AGREEMENT_M", "ITERATION_OPTION", "POPULATION_OPTION", "SOLVERS",
           "calibrate", "verify"]

AGREEMENT_DEG = 1.0  # axes of two independent starts must agree within this (deg)
AGREEMENT_M = 0.005  # and joint positions within this (m)


def calibrate(
    data: JointData,
    joint: str = "hinge",
    method: str = DEFAULT_METHOD,
    *,
    seed: int = 0,
    quat_1: np.ndarray | None = None,
    quat_2: np.ndarray | None = None,
    verify_start: bool = True,
    **options: object,
) -> CalibrationResult:
    """Calibrate a ``'hinge'`` (axes, eq 4-6, and positions, eq 1-3 and 16) or ``'spherical'``
    (positions) joint from two sensors' signals by ``method`` (module docstring).

    ``quat_1``/``quat_2``: the sensors' orientations, when known, make the two axis signs
    consistent. ``verify_start``: solve again from an independent start (:func:`verify`).
    ``options`` go to the method (e.g. ``loss``, ``prior_axis_1`` for IPOPT; ``restarts``,
    ``particles``, ``wolves``, ``iterations`` for the others).
    """
    if joint not in JOINTS:
        raise InputError(f"expected joint in {JOINTS}, got {joint!r}", field="joint")
    if method not in METHODS:
        raise InputError(f"expected method in {METHODS}, got {method!r}", field="method")
    result = _solve(data, joint, method, seed, quat_1, quat_2, options)
    if not verify_start:
        return result
    second = _solve(data, joint, method, seed + 1, quat_1, quat_2, options)
    return verify(result, second)


def _ipopt(data, joint, method, seed, quat_1, quat_2, options) -> CalibrationResult:
    from pipeline.calibration.ipopt import calibrate_ipopt  # CasADi only when needed

    return calibrate_ipopt(data, joint, seed=seed, quat_1=quat_1, quat_2=quat_2, **options)


def _classic(data, joint, method, seed, quat_1, quat_2, options) -> CalibrationResult:
    return calibrate_classic(data, joint, method, seed=seed, quat_1=quat_1, quat_2=quat_2,
                             **options)


#: Method name -> how it calibrates (adding a method: one function and one entry here, its name
#: in :data:`~pipeline.calibration.conventions.METHODS`), the name of its iteration-limit option
#: and of its population option (swarms).
SOLVERS = {"ipopt": _ipopt, "gn": _classic, "dwpso": _classic, "gwo": _classic}
ITERATION_OPTION = {"ipopt": "max_iter", "gn": "max_iter", "dwpso": "iterations",
                    "gwo": "iterations"}
POPULATION_OPTION = {"dwpso": "particles", "gwo": "wolves"}


def _solve(data, joint, method, seed, quat_1, quat_2, options) -> CalibrationResult:
    return SOLVERS[method](data, joint, method, seed, quat_1, quat_2, options)


def verify(result: CalibrationResult, second: CalibrationResult) -> CalibrationResult:
    """``result`` with the agreement of an independent start recorded in its observability: when
    the axes differ by more than :data:`AGREEMENT_DEG` or the positions by more than
    :data:`AGREEMENT_M`, the disagreement is added to the undetermined directions."""
    problems = []
    axis_deg = 0.0
    if result.axis_1 is not None and second.axis_1 is not None:
        s = 1.0 if float(np.dot(result.axis_1, second.axis_1)) >= 0 else -1.0  # joint sign
        e1 = angle_between(result.axis_1, s * second.axis_1)
        e2 = angle_between(result.axis_2, s * second.axis_2)
        axis_deg = float(np.degrees(max(e1, e2)))
        if axis_deg > AGREEMENT_DEG:
            problems.append(f"axes of two independent starts {axis_deg:.2f} deg apart")
    pos_m = float(max(np.linalg.norm(result.position_1_m - second.position_1_m),
                      np.linalg.norm(result.position_2_m - second.position_2_m)))
    if pos_m > AGREEMENT_M:
        problems.append(f"positions of two independent starts {1e3 * pos_m:.1f} mm apart")
    obs = result.observability
    note = f"independent start: axes {axis_deg:.3f} deg, positions {1e3 * pos_m:.2f} mm apart"
    obs = dataclasses.replace(obs, undetermined=obs.undetermined + tuple(problems),
                              message=f"{obs.message} | {note}")
    return dataclasses.replace(result, observability=obs, seconds=result.seconds + second.seconds)
