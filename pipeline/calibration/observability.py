"""What a calibration trial determines (Hu 2021's observability question, DESIGN §6).

:func:`observability` diagnoses the residual Jacobian of any parameter group at the solution
(rank, condition, predicted SDs); :func:`diagnose` applies it to the axes (eq 6, tangent
coordinates) and positions (eq 3) of a joint calibration and returns an :class:`Observability`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pipeline.calibration.joint_constraints import (
    JointData,
    hinge_jacobian,
    hinge_residual,
    spherical_jacobian,
    spherical_residual,
)
from pipeline.rotations import normalize, tangent_basis

__all__ = ["DirectionDiagnostics", "Observability", "diagnose", "observability"]


@dataclass(frozen=True)
class DirectionDiagnostics:
    """:func:`observability` of one parameter group: the singular values of ``J / sqrt(N)``, their
    condition number, the predicted SD of each parameter (parameter units), the names of the
    undetermined directions and a one-line message."""

    singular_values: np.ndarray
    condition: float
    sd: np.ndarray
    undetermined: tuple[str, ...]
    message: str

    def as_dict(self) -> dict:
        """The JSON layout of ``pipeline calibrate --json``."""
        return {
            "singular_values": self.singular_values,
            "condition": self.condition,
            "sd": self.sd,
            "undetermined": list(self.undetermined),
            "message": self.message,
        }


def observability(
    jacobian: np.ndarray,
    blocks: dict[str, slice],
    *,
    residual: np.ndarray | None = None,
    abs_tol: float = np.inf,
    directions: dict[str, np.ndarray] | None = None,
    rel_tol: float = 0.02,
) -> DirectionDiagnostics:
    """Rank and uncertainty diagnostics of a residual Jacobian (N, P) at the solution.

    With ``J / sqrt(N) = U S V^T``, a right-singular direction ``v_k`` is weakly determined when
    ``s_k / s_max < rel_tol`` (rank), or when its standard deviation under white residuals,
    ``sd_k = rms(residual) / (sqrt(N) s_k)``, exceeds ``abs_tol`` (parameter units). It is named
    after a known direction in ``directions`` (``name -> (P,)``, e.g. the shift of both hinge
    positions along the axis) when ``|v_k . d| > 0.9``, otherwise after the parameter blocks
    (``name -> column slice``) carrying more than a quarter of its weight.
    Returns a :class:`DirectionDiagnostics`.
    """
    J = np.asarray(jacobian, float)
    n = J.shape[0]
    _, s, vt = np.linalg.svd(J / np.sqrt(n), full_matrices=False)
    smax = s[0] if s.size and s[0] > 0 else 1.0
    rms = 0.0 if residual is None else float(np.sqrt(np.mean(np.square(residual))))
    sd_k = rms / (np.sqrt(n) * np.maximum(s, 1e-300))
    weak = [k for k in range(s.size) if s[k] / smax < rel_tol or sd_k[k] > abs_tol]
    names: list[str] = []
    for k in weak:
        hit = [m for m, d in (directions or {}).items() if abs(vt[k] @ normalize(d)) > 0.9]
        if not hit:
            hit = [m for m, sl in blocks.items() if np.sum(vt[k, sl] ** 2) > 0.25]
        names += [m for m in hit if m not in names]
    cond = float(smax / max(s[-1], 1e-300)) if s.size else float("inf")
    sd = np.sqrt(np.einsum("kp,k->p", vt**2, np.minimum(sd_k, 1e6) ** 2))
    if names:
        msg = f"{len(weak)} weakly determined direction(s): " + "; ".join(names)
        msg += " undetermined by this motion"
    else:
        msg = f"all parameters determined (condition number {cond:.1f})"
    return DirectionDiagnostics(s, cond, sd, tuple(names), msg)


@dataclass(frozen=True)
class Observability:
    """What the motion determines (:func:`diagnose`): ``undetermined`` directions (not to be
    trusted), ``expected`` ones (the shift of hinge positions along the axis, fixed by eq 16), the
    diagnostics of the ``axes`` and ``positions`` groups, a ``message`` and, for IPOPT, the
    ``solver_status``."""

    undetermined: tuple[str, ...] = ()
    expected: tuple[str, ...] = ()
    axes: DirectionDiagnostics | None = None
    positions: DirectionDiagnostics | None = None
    message: str = ""
    solver_status: str | None = None

    @property
    def determined(self) -> bool:
        return not self.undetermined

    def as_dict(self) -> dict:
        """The JSON layout of ``pipeline calibrate --json``."""
        out: dict = {"undetermined": list(self.undetermined), "expected": list(self.expected)}
        for name in ("axes", "positions"):
            block = getattr(self, name)
            if block is not None:
                out[name] = block.as_dict()
        out["message"] = self.message
        if self.solver_status is not None:
            out["solver_status"] = self.solver_status
        return out


def diagnose(
    data: JointData,
    j1=None,
    j2=None,
    o1=None,
    o2=None,
    *,
    rel_tol: float = 0.02,
    axis_sd_deg: float = 2.0,
    position_sd_m: float = 0.005,
) -> Observability:
    """Observability at a solution: Jacobians of eq 6 (axes, tangent coordinates) and eq 3
    (positions) (:func:`observability`); a direction is undetermined when rank-deficient
    (``rel_tol``) or when its predicted SD exceeds ``axis_sd_deg`` / ``position_sd_m``. The
    shift of hinge positions along the axis is expected and listed under ``expected``."""
    undetermined: list[str] = []
    expected: list[str] = []
    axes = positions = None
    msgs = []
    if j1 is not None:
        B1, B2 = tangent_basis(j1), tangent_basis(j2)
        J = hinge_jacobian(j1, j2, data.gyr_1, data.gyr_2)
        Jt = np.hstack([J[:, :3] @ B1, J[:, 3:] @ B2])
        blocks = {"axis_1 (sensor 1)": slice(0, 2), "axis_2 (sensor 2)": slice(2, 4)}
        axes = observability(
            Jt,
            blocks,
            residual=hinge_residual(j1, j2, data.gyr_1, data.gyr_2),
            abs_tol=np.deg2rad(axis_sd_deg),
            rel_tol=rel_tol,
        )
        undetermined += axes.undetermined
        msgs.append("axes: " + axes.message)
    if o1 is not None:
        along = "position along the hinge axis"
        dirs = {} if j1 is None else {along: np.concatenate([j1, j2])}
        blocks = {"position_1 (sensor 1)": slice(0, 3), "position_2 (sensor 2)": slice(3, 6)}
        positions = observability(
            spherical_jacobian(o1, o2, data),
            blocks,
            directions=dirs,
            rel_tol=rel_tol,
            residual=spherical_residual(o1, o2, data),
            abs_tol=position_sd_m,
        )
        for n in positions.undetermined:
            (expected if n == along else undetermined).append(n)
        msg = positions.message
        if along in expected:
            msg += " (the shift along a hinge axis is expected; fixed by eq 16)"
        msgs.append("positions: " + msg)
    return Observability(tuple(undetermined), tuple(expected), axes, positions, " | ".join(msgs))
