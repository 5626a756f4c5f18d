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

import casadi as ca

from pipeline.errors import InputError

__all__ = ["LOSSES", "check_loss", "robust_loss"]

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
