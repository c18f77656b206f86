"""Small problems of the continuation core with known answers, for its tests
(tests/continuation/test_core_*.py).

Families G(u, p) = A(p) u with the equilibrium u = 0 have the spectrum of A(p) along the whole
branch; 2x2 blocks [[a, 1], [c(p), a]] have eigenvalues a +- sqrt(c(p)), so a pair is complex
exactly where c(p) < 0 and every collision is a root of c.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from diskfriction.continuation import ContinuationParams, FunctionProblem, continuation, count_complex_pairs
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra


TOL_P = 1e-10


def block_diag(*blocks) -> np.ndarray:
    """scipy.linalg.block_diag of float blocks, the same matrix without scipy's argument
    handling: 0.17 ms a call there, most of the time of the dense grids of
    assert_count_changes_only_at_collisions (20 000 and more matrices each)."""
    blocks = [np.atleast_2d(np.asarray(b, dtype=float)) for b in blocks]
    out = np.zeros((sum(b.shape[0] for b in blocks), sum(b.shape[1] for b in blocks)))
    r = c = 0
    for b in blocks:
        out[r:r + b.shape[0], c:c + b.shape[1]] = b
        r, c = r + b.shape[0], c + b.shape[1]
    return out


def linear_family(A, dA):
    """G(u, p) = A(p) u: G_u = A(p), G_p = A'(p) u."""
    return FunctionProblem(G=lambda u, p: A(p) @ u, G_u=lambda u, p: A(p), G_p=lambda u, p: dA(p) @ u)


def pair_block(a, c):
    """[[a, 1], [c, a]]: eigenvalues a +- sqrt(c)."""
    return np.array([[a, 1.0], [c, a]])


def blocks_family(blocks):
    """Block-diagonal family from [(a, c, dc), ...], c(p) and dc(p) callables."""
    A = lambda p: block_diag(*[pair_block(a, c(p)) for a, c, _ in blocks])
    dA = lambda p: block_diag(*[np.array([[0.0, 0.0], [dc(p), 0.0]]) for _, _, dc in blocks])
    return linear_family(A, dA)


def run(problem, n, p_min=0.0, p_max=1.0, ds=0.05, ds_max=None, u0=None, direction=1):
    par = ContinuationParams(ds=ds, ds_min=1e-9, ds_max=ds if ds_max is None else ds_max,
                             newton_tol=1e-12, p_min=p_min, p_max=p_max, direction=direction)
    return continuation(problem, np.zeros(n) if u0 is None else u0, p_min if direction > 0 else p_max, par)


def spectrum(problem, u, p):
    """Every eigenvalue of the problem's stability matrix at (u, p) (DenseSpectra)."""
    return DenseSpectra().eigensystem(problem, u, p).values


def located(branch, kind):
    return sorted(c.p for c in branch.collisions if c.kind == kind)


def assert_count_changes_only_at_collisions(problem, branch, p_lo, p_hi, n_grid=4001):
    """On a dense grid plus points 1e-9 outside every bracket, the count of complex pairs
    (at u = 0) changes between neighbours by exactly births - deaths located in between
    (for a branch monotone in p; kinds follow the branch direction)."""
    extra = [q for c in branch.collisions for q in (c.bracket[0] - 1e-9, c.bracket[1] + 1e-9)]
    grid = np.unique(np.clip(np.concatenate([np.linspace(p_lo, p_hi, n_grid), extra]), p_lo, p_hi))
    n = branch.u.shape[1]
    counts = np.array([count_complex_pairs(spectrum(problem, np.zeros(n), q)) for q in grid])
    up = 1 if branch.p[-1] > branch.p[0] else -1
    sign = {"birth": up, "death": -up}
    for g0, g1, c0, c1 in zip(grid[:-1], grid[1:], counts[:-1], counts[1:]):
        inside = [c for c in branch.collisions if g0 < c.p <= g1]
        assert c1 - c0 == sum(sign[c.kind] for c in inside), (g0, g1, c0, c1, inside)
    for c in branch.collisions:  # the count changes across every bracket (by all it holds)
        lo, hi = c.bracket[0] - 1e-9, c.bracket[1] + 1e-9
        before = count_complex_pairs(spectrum(problem, np.zeros(n), lo))
        after = count_complex_pairs(spectrum(problem, np.zeros(n), hi))
        assert after - before == sum(sign[d.kind] for d in branch.collisions if lo < d.p < hi) != 0


def brusselator(a):
    """x' = a - (b + 1) x + x^2 y, y' = b x - x^2 y with p = b; steady state (a, b / a);
    Jacobian [[b - 1, a^2], [-b, -a^2]]: Hopf at b = 1 + a^2, complex pair for
    (a - 1)^2 < b < (a + 1)^2."""
    def G(u, b):
        x, y = u
        return np.array([a - (b + 1) * x + x * x * y, b * x - x * x * y])

    def J(u, b):
        x, y = u
        return np.array([[-(b + 1) + 2 * x * y, x * x], [b - 2 * x * y, -x * x]])

    return FunctionProblem(G, J, lambda u, b: np.array([-u[0], u[0]]))


P0 = 1 / np.pi


def bubble_problem(p1, p2):
    """[[a, 1], [c, a]] with c = (p - p1)(p - p2) e^p (complex only on (p1, p2)), plus a third
    coordinate u3 = sin(3 p) that makes the branch curved, so arclength is not linear in p."""
    a = -0.7

    def c(p):
        return (p - p1) * (p - p2) * np.exp(p)

    def dc(p):
        return ((2 * p - p1 - p2) + (p - p1) * (p - p2)) * np.exp(p)

    def A(p):
        return block_diag(pair_block(a, c(p)), [[1.0]])

    def G(u, p):
        return np.append(pair_block(a, c(p)) @ u[:2], u[2] - np.sin(3 * p))

    def G_p(u, p):
        return np.array([0.0, dc(p) * u[0], -3 * np.cos(3 * p)])

    return FunctionProblem(G, lambda u, p: A(p), G_p)


def fast_eigenvalue_through_a_cluster(v=10.0, c=1e-3):
    """A fast eigenvalue f(p) = v p sweeps past slow ones at 1, 2 and 3: an exact crossing
    with 1 (no coupling), a narrow bubble with 2 (skew coupling c: complex while
    |f - 2| < 2c, width ~4c / v) and an avoided crossing with 3 (symmetric coupling c).
    The coupled 3x3 block has det(lambda - A) = (lambda - f)(lambda - 2)(lambda - 3) - c^2; the
    collisions are the roots of that cubic's discriminant, found here by brentq."""
    def A(p):
        M = np.diag([v * p, 1.0, 2.0, 3.0])
        M[0, 2], M[2, 0] = c, -c
        M[0, 3] = M[3, 0] = c
        return M

    def discriminant(p):
        f = v * p
        b, k, d = -(f + 5.0), 5.0 * f + 6.0, -(6.0 * f + c * c)
        return 18 * b * k * d - 4 * b**3 * d + b * b * k * k - 4 * k**3 - 27 * d * d

    dA = lambda p: np.diag([v, 0.0, 0.0, 0.0])
    exact = tuple(brentq(discriminant, (2 + sign * c) / v, (2 + sign * 3 * c) / v, xtol=1e-15)
                  for sign in (-1, 1))
    return linear_family(A, dA), exact
