"""The one entry to joint-constraint calibration (Hu et al. 2021): :func:`calibrate`.

``method``:

* ``'ipopt'`` (default): one IPOPT problem over both constraints with optional robust losses and
  axis priors (:func:`pipeline.calibration.ipopt.calibrate_ipopt`); the most accurate and the
  fastest on the simulated trials (``scripts/bench_calibration.py``).
* ``'gn'``: Gauss-Newton on each constraint with random restarts (Hu eq 7-15).
* ``'dwpso'`` / ``'gwo'``: the paper's swarm optimisers (eq 17-24 / 25-29), seeded.

The solvers are imported when :func:`calibrate` runs (CasADi only for ``'ipopt'``), so that this
module's names (:data:`METHODS`, :data:`DEFAULT_METHOD`) cost nothing to import.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from pipeline.errors import InputError

if TYPE_CHECKING:  # the solvers load SciPy and, for IPOPT, CasADi: only when calibrating
    import numpy as np

    from pipeline.calibration.joint_constraints import JointData
    from pipeline.calibration.solvers import CalibrationResult

__all__ = ["DEFAULT_METHOD", "JOINTS", "METHODS", "calibrate"]

METHODS = ("gn", "dwpso", "gwo", "ipopt")
DEFAULT_METHOD = "ipopt"
JOINTS = ("hinge", "spherical")


def calibrate(
    data: JointData,
    joint: str = "hinge",
    method: str = DEFAULT_METHOD,
    *,
    seed: int = 0,
    quat_1: np.ndarray | None = None,
    quat_2: np.ndarray | None = None,
    **options: object,
) -> CalibrationResult:
    """Calibrate a ``'hinge'`` (axes, eq 4-6, and positions, eq 1-3 and 16) or ``'spherical'``
    (positions) joint from two sensors' signals by ``method`` (module docstring).

    ``quat_1``/``quat_2``: the sensors' orientations, when known, make the two axis signs
    consistent. ``options`` go to the method (e.g. ``loss``, ``prior_axis_1`` for IPOPT;
    ``restarts``, ``particles``, ``wolves``, ``iterations`` for the others).
    """
    if joint not in JOINTS:
        raise InputError(f"expected joint in {JOINTS}, got {joint!r}", field="joint")
    if method not in METHODS:
        raise InputError(f"expected method in {METHODS}, got {method!r}", field="method")
    if method == "ipopt":
        from pipeline.calibration.ipopt import calibrate_ipopt  # CasADi only when needed

        return calibrate_ipopt(data, joint, seed=seed, quat_1=quat_1, quat_2=quat_2, **options)
    from pipeline.calibration.solvers import calibrate_classic

    return calibrate_classic(data, joint, method, seed=seed, quat_1=quat_1, quat_2=quat_2,
                             **options)  # fmt: skip
