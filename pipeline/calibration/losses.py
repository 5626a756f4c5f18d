"""Robust losses of a squared residual, for the IPOPT formulations (CasADi expressions).

With ``s = e^2`` the squared residual and ``c`` the scale (the residual at which the loss starts
to discount):

* ``'l2'``: ``rho(s) = s``;
* ``'huber'`` (smooth, pseudo-Huber): ``rho(s) = 2 c^2 (sqrt(1 + s / c^2) - 1)``, quadratic for
  ``e << c`` and linear in ``|e|`` for ``e >> c``;
* ``'cauchy'``: ``rho(s) = c^2 log(1 + s / c^2)``, logarithmic for ``e >> c``.

All three equal ``s`` to first order at ``s = 0``, so ``c`` leaves small residuals unweighted.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca

from pipeline.errors import InputError

__all__ = ["LOSSES", "check_loss", "hinge_sample_cost", "robust_loss"]

LOSSES = ("l2", "huber", "cauchy")


def check_loss(loss: str) -> str:
    """``loss`` if it is one of :data:`LOSSES`; raises :class:`InputError` otherwise."""
    if loss not in LOSSES:
        raise InputError(f"expected loss in {LOSSES}, got {loss!r}", field="loss")
    return loss


def robust_loss(sq, loss: str, scale: float):
    """``rho(sq)`` of the module docstring for a squared residual ``sq`` and scale ``c``."""
    c2 = float(scale) ** 2
    if check_loss(loss) == "l2":
        return sq
    if loss == "huber":
        return 2 * c2 * (ca.sqrt(1 + sq / c2) - 1)
    return c2 * ca.log(1 + sq / c2)


@lru_cache(maxsize=8)
def hinge_sample_cost(loss: str, scale: float) -> ca.Function:
    """``w rho(|M u - v|^2)`` of one sample of a hinge knee, ``M`` given by its 9 column-major
    entries: the relative rotation ``M`` misses the hinge by ``|M u - v| = 2 sin(eps / 2)`` when
    ``u`` / ``v`` are the knee axis in the (uncorrected) tibia / femur frames (Wang eq 1-8's
    ``F_R_T``; :mod:`pipeline.calibration.aor_ipopt`)."""
    u, v, m, w = ca.SX.sym("u", 3), ca.SX.sym("v", 3), ca.SX.sym("m", 9), ca.SX.sym("w")
    r = ca.mtimes(ca.reshape(m, 3, 3), u) - v
    return ca.Function("hinge_sample", [u, v, m, w], [w * robust_loss(ca.sumsqr(r), loss, scale)])
