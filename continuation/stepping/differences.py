"""Derivatives a problem does not give: dG/du and dG/dp of G(u, p) by differences.

Two methods, one partial derivative per unknown x_j of x = (u, p) (dG/du column by column):

  central       dG/dx_j = [8 (G(x + h e_j) - G(x - h e_j)) - (G(x + 2h e_j) - G(x - 2h e_j))] / 12h,
                h = eps^(1/5) max(1, |x_j|) (7.4e-4 for |x_j| <= 1; rounded so that x_j + h is
                exact): the fourth-order five-point stencil, four evaluations of G per column.
                Its error is the truncation h^4 |G^(5)| / 30 plus the rounding ~1.5 eps |G| / h,
                about eps^(4/5) = 3e-13 relative to the scale of G when G's fifth derivatives
                are of the order of G itself: variables of order 1, no feature of G shorter
                than h. (The second-order stencil's error, eps^(2/3) = 4e-11, is noise to the
                collision locator, whose Newton stops at |dp| <= 1e-12: on FitzHugh-Nagumo it
                did not converge and fell back to bisection, 3x slower, collisions 1e-11 off.)
  complex-step  dG/dx_j = Im G(x + i h e_j) / h,  h = 1e-30 max(1, |x_j|)
                (Squire and Trapp, SIAM Review 40, 110, 1998): no subtraction, so the error is
                the rounding of G itself, ~eps, for one evaluation per column. Valid only for a
                G that is real-analytic AND written so that complex numbers flow through it: no
                abs, min, max, comparisons, np.real, conj or float() on u or p.
                check_complex_step tests this at one point.

What the error costs downstream (docs/api.md, "Derivatives"): the branch itself is exact to
the Newton tolerance whatever dG/du is (it only steers Newton); a tracked matrix that IS the
differenced dG/du carries the error into the spectrum, and the collisions, folds and Hopf
points move by about that error relative to their scale (FitzHugh-Nagumo: collisions within
1e-13, Hopf points within 1e-12 of the closed forms; tests/test_gallery.py).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

Array = np.ndarray

METHODS = ("central", "complex-step")
EPS = np.finfo(float).eps
CENTRAL_STEP = EPS ** (1.0 / 5.0)
"""Relative step of central differences: balances truncation (h^4) against rounding (eps / h)."""
COMPLEX_STEP = 1e-30
"""Relative step of the complex step: any tiny value works, there is no cancellation."""
AGREEMENT = 1e-6
"""check_complex_step: the complex step and central differences must agree to this, relative
(both are good to ~1e-12 where the complex step is valid; where it is not, it is off by O(1))."""
ACCURACY = {"central": "to about 1e-12 relative if u and p are of order 1 and G is smooth on "
                       "the scale 1e-3 (fourth-order stencil, step eps^(1/5) max(1, |x|))",
            "complex-step": "to rounding (~1e-16 relative)"}


class DerivativeWarning(UserWarning):
    """A derivative is computed by differences, with the accuracy the message states."""


def partial(f: Callable[[float], Array], x: float, method: str) -> Array:
    """d f / d x at x (f: a real number -> an array) by `method` (module docstring)."""
    scale = max(1.0, abs(x))
    if method == "complex-step":
        h = COMPLEX_STEP * scale
        return np.imag(np.asarray(f(complex(x, h)))) / h
    h = (x + CENTRAL_STEP * scale) - x  # exactly representable step
    g = {k: np.asarray(f(x + k * h), dtype=float) for k in (-2, -1, 1, 2)}
    return (8.0 * (g[1] - g[-1]) - (g[2] - g[-2])) / (12.0 * h)


def _replaced(u: Array, j: int, z) -> Array:
    """u with component j set to z (complex if z is)."""
    v = u.astype(np.result_type(u, type(z)), copy=True)
    v[j] = z
    return v


@dataclass(frozen=True)
class StateDerivative:
    """dG/du (n x n) of G by differences: column j is partial(G(u with u_j = z, p), u_j)."""

    G: Callable[[Array, float], Array]
    method: str = "central"

    def __call__(self, u: Array, p: float) -> Array:
        u = np.asarray(u, dtype=float)
        cols = [partial(lambda z, j=j: self.G(_replaced(u, j, z), p), float(u[j]), self.method)
                for j in range(u.size)]
        return np.column_stack(cols) if cols else np.zeros((0, 0))


@dataclass(frozen=True)
class ParameterDerivative:
    """dG/dp (n,) of G by differences: partial(G(u, z), p)."""

    G: Callable[[Array, float], Array]
    method: str = "central"

    def __call__(self, u: Array, p: float) -> Array:
        return partial(lambda z: self.G(u, z), float(p), self.method).reshape(-1)


def differences_line(names: list[str], method: str) -> str:
    """What a DerivativeWarning says: the derivatives computed by `method`, their accuracy."""
    return (f"{' and '.join(names)} not given: computed by {method} differences, "
            f"accurate {ACCURACY[method]} (docs/api.md, Derivatives)")


def warn_differences(names: list[str], method: str) -> None:
    """One DerivativeWarning naming the derivatives computed by `method` and their accuracy."""
    if names:
        warnings.warn(differences_line(names, method), DerivativeWarning, stacklevel=3)


def differenced(problem) -> Optional[str]:
    """The DerivativeWarning's line of a problem whose dG/du or dG/dp are computed by
    differences (problem_from_functions without them), or None."""
    found = [(name, f.method) for name, f in (("dG/du", getattr(problem, "G_u", None)),
                                              ("dG/dp", getattr(problem, "G_p", None)))
             if isinstance(f, (StateDerivative, ParameterDerivative))]
    return differences_line([n for n, _ in found], found[0][1]) if found else None


def check_complex_step(G: Callable[[Array, float], Array], u: Array, p: float) -> None:
    """Raise ValueError if the complex step is not valid for G at (u, p): G fails on complex
    input or drops its imaginary part, or the complex-step dG/du and dG/dp disagree with
    central differences by more than AGREEMENT relative."""
    u = np.asarray(u, dtype=float)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error", np.exceptions.ComplexWarning)
            pairs = [(StateDerivative(G, m)(u, p), ParameterDerivative(G, m)(u, p)) for m in METHODS]
    except Exception as error:  # noqa: BLE001 - any failure of the user's G on complex input
        raise ValueError(f"the complex step needs G to accept complex u and p "
                         f"({type(error).__name__}: {error})") from None
    (J_c, p_c), (J_z, p_z) = pairs
    scale = max(float(np.max(np.abs(J_c), initial=0.0)), float(np.max(np.abs(p_c), initial=0.0)), 1e-300)
    worst = max(float(np.max(np.abs(J_z - J_c), initial=0.0)), float(np.max(np.abs(p_z - p_c), initial=0.0)))
    if not worst <= AGREEMENT * scale:
        raise ValueError(f"the complex step disagrees with central differences by {worst / scale:.2g} "
                         "relative: G is not complex-analytic as written (abs, min, max, comparisons, "
                         "np.real or conj on u or p?)")
