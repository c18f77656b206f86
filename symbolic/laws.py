"""Contact laws in the contact frame: normal force F_n(delta) and tangential force F_t(delta, xi).

All expressions are sympy, in raw units (docs/model.md#units): delta [length] overlap, xi [length] tangential
history, k_n [force / length^(3/2)], k_t [force / length^(3/2)], mu [1]. Signs: F_n > 0 pushes the
bodies apart; F_t is the component along the contact tangent s acting on the first body.

The smoothed Mindlin law (paper eq. 5) contains xi |xi|; |xi| is not differentiable at xi = 0, but
xi |xi| is (once), with derivative 2 |xi|. ``signed_square`` carries exactly that derivative, so
the Jacobian is continuous through xi = 0 and never evaluates sign(0).

After differentiation every law is rewritten with u = xi / t*, t* = mu k_n delta / k_t, the
history in units of its Coulomb limit (|u| <= 1 for an admissible state). Because delta is a
positive symbol, sympy then merges delta^(-1/2) xi into delta^(1/2) u: the derivatives contain
only delta^(1/2) and delta^(3/2) times polynomials in u, bounded as delta -> 0+.
"""
from __future__ import annotations

import sympy as sp

delta = sp.Symbol("delta", positive=True)
xi = sp.Symbol("xi", real=True)
u = sp.Symbol("u", real=True)
R, k_n, k_t, mu = sp.symbols("R k_n k_t mu", positive=True)

t_star = mu * k_n * delta / k_t
"""Coulomb limit of the history, t* = mu k_n delta / k_t [length]: |F_t(t*)| = mu F_n."""


class signed_square(sp.Function):
    """s(x) = x |x|, once differentiable with s'(x) = 2 |x|."""

    def fdiff(self, argindex=1):
        return 2 * sp.Abs(self.args[0])


def normal_force() -> sp.Expr:
    """Hertz: F_n = k_n delta^(3/2) [force]."""
    return k_n * delta ** sp.Rational(3, 2)


def tangential_force(law: str) -> sp.Expr:
    """Tangential force along s on the first body [force], as a function of (delta, xi).

    mindlin-smooth: F_t = -k_t delta^(1/2) (xi + xi |xi| / t* - xi^3 / t*^2)   (paper eq. 5)
    mindlin-linear: F_t = -k_t delta^(1/2) xi   (the cap |xi| <= t* is applied to the history)
    none:           F_t = 0
    """
    if law == "mindlin-smooth":
        return -k_t * sp.sqrt(delta) * (xi + signed_square(xi) / t_star - xi**3 / t_star**2)
    if law == "mindlin-linear":
        return -k_t * sp.sqrt(delta) * xi
    if law == "none":
        return sp.Integer(0)
    raise ValueError(f"unknown tangential law {law!r}")


def in_coulomb_units(expr: sp.Expr) -> sp.Expr:
    """Rewrite an expression in (delta, xi) with u = xi / t*, and xi |xi| as explicit Abs."""
    expr = expr.replace(signed_square, lambda a: a * sp.Abs(a))
    return sp.expand(expr.subs(xi, u * t_star))
