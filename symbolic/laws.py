"""Contact laws in the contact frame: normal force F_n(delta) and tangential force F_t(delta, xi).

The one source of contact-law physics: the kernels are derived from these expressions, and so
are the functions every other module calls (codegen.law_functions prints them into the kernel
module): normal_force, normal_stiffness dF_n/ddelta, normal_energy (the integral of F_n from
first contact) and coulomb_limit t*. A normal law is one entry of scenes.rules.NORMAL_LAWS
(F_n = k_n delta^p, by its exponent p); everything below follows from it.

All expressions are sympy, in raw units (docs/model.md#units): delta [length] overlap, xi [length] tangential
history, k_n [force / length^p], k_t [force / length^(3/2)], mu [1]. Signs: F_n > 0 pushes the
bodies apart; F_t is the component along the contact tangent s acting on the first body.

The smoothed Mindlin law (paper eq. 5) contains xi |xi|; |xi| is not differentiable at xi = 0, but
xi |xi| is (once), with derivative 2 |xi|. ``signed_square`` carries exactly that derivative, so
the Jacobian is continuous through xi = 0 and never evaluates sign(0).

After differentiation every law is rewritten with u = xi / t*, the history in units of its
Coulomb limit t* = mu F_n / (k_t delta^(1/2)) (Hertz: mu k_n delta / k_t; |u| <= 1 for an
admissible state). Because delta is a positive symbol, sympy then merges delta^(-1/2) xi into
powers of delta times u: for Hertz the derivatives contain only delta^(1/2) and delta^(3/2)
times polynomials in u, bounded as delta -> 0+.
"""
from __future__ import annotations

import sympy as sp

from diskfriction.scenes.rules import NORMAL_LAWS

delta = sp.Symbol("delta", positive=True)
xi = sp.Symbol("xi", real=True)
u = sp.Symbol("u", real=True)
R, k_n, k_t, mu = sp.symbols("R k_n k_t mu", positive=True)



class signed_square(sp.Function):
    """s(x) = x |x|, once differentiable with s'(x) = 2 |x|."""

    def fdiff(self, argindex=1):
        return 2 * sp.Abs(self.args[0])


def normal_force(normal: str) -> sp.Expr:
    """F_n = k_n delta^p [force], p = NORMAL_LAWS[normal] (Hertz: 3/2; Hooke: 1)."""
    p = NORMAL_LAWS[normal]
    return k_n * delta ** sp.Rational(p.numerator, p.denominator)


def normal_stiffness(normal: str) -> sp.Expr:
    """dF_n / ddelta [force / length] (Hertz: 3/2 k_n delta^(1/2))."""
    return sp.diff(normal_force(normal), delta)


def normal_energy(normal: str) -> sp.Expr:
    """U_n = integral of F_n from first contact, delta' = 0 .. delta [energy] (Hertz: 2/5 k_n
    delta^(5/2))."""
    d = sp.Dummy("d", positive=True)
    return sp.integrate(normal_force(normal).subs(delta, d), (d, 0, delta))


def coulomb_limit(normal: str) -> sp.Expr:
    """Coulomb limit of the history t* [length], where the Mindlin force k_t delta^(1/2) |xi|
    of either tangential law reaches mu F_n: t* = mu F_n / (k_t delta^(1/2)) (Hertz: mu k_n
    delta / k_t)."""
    return mu * normal_force(normal) / (k_t * sp.sqrt(delta))


def tangential_force(law: str, normal: str) -> sp.Expr:
    """Tangential force along s on the first body [force], as a function of (delta, xi).

    mindlin-smooth: F_t = -k_t delta^(1/2) (xi + xi |xi| / t* - xi^3 / t*^2)   (paper eq. 5)
    mindlin-linear: F_t = -k_t delta^(1/2) xi   (the cap |xi| <= t* is applied to the history)
    none:           F_t = 0
    with t* the Coulomb limit of the normal law `normal`.
    """
    if law == "mindlin-smooth":
        t_star = coulomb_limit(normal)
        return -k_t * sp.sqrt(delta) * (xi + signed_square(xi) / t_star - xi**3 / t_star**2)
    if law == "mindlin-linear":
        return -k_t * sp.sqrt(delta) * xi
    if law == "none":
        return sp.Integer(0)
    raise ValueError(f"unknown tangential law {law!r}")


def in_coulomb_units(expr: sp.Expr, normal: str) -> sp.Expr:
    """Rewrite an expression in (delta, xi) with u = xi / t*, t* the Coulomb limit of the normal
    law `normal`, and xi |xi| as explicit Abs."""
    expr = expr.replace(signed_square, lambda a: a * sp.Abs(a))
    return sp.expand(expr.subs(xi, u * coulomb_limit(normal)))
