"""Bordered Newton solves on the extended state x = (u, p) in R^(n+1).

Every solve of the core is one bordered system

    F(x) = [ G(u, p)            ]  = 0,      dF/dx = [ G_u   G_p ]
           [ b . (x - x_target) ]                    [ b^T       ]

with a border vector b in R^(n+1): b = tangent (pseudo-arclength corrector), b = secant
(points between two accepted points), b = e_p (fixed p). The tangent t at x solves
dF/dx t = e_(n+1), normalised to |t| = 1; with b = the previous tangent this gives
b . t > 0, so the orientation is kept and folds are passed.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from diskfriction.continuation.linalg.solves import DIRECT, LinearSolver, RefinedSolve, SingularMatrix, bordered
from diskfriction.continuation.problem import ROUNDING, Problem

Array = np.ndarray


@dataclass(frozen=True)
class NewtonResult:
    """x: last iterate; iterations: Newton updates made; residual: max|G(x)|; rounding: what
    G rounds to at x, ROUNDING times the size of its terms (term_size; 0 if not evaluated)."""

    x: Array
    iterations: int
    residual: float
    converged: bool
    rounding: float = 0.0

    def failure(self) -> str:
        """Why the corrector failed, in words: its residual, and, where that is within 10 times
        what G rounds to, that the tolerance is below G's rounding."""
        line = f"residual {self.residual:.3g}"
        if 0.0 < self.residual <= 10.0 * self.rounding:
            line += (f", at the rounding of G's terms there (about {self.rounding:.2g}): "
                     f"newton_tol asks more than G can be computed to")
        return line


def bordered_matrix(problem: Problem, x: Array, border: Array):
    """[[G_u, G_p], [b^T]] at x = (u, p), shape (n+1, n+1); dense or sparse as G_u is."""
    u, p = x[:-1], x[-1]
    return bordered(problem.jacobian(u, p), problem.dG_dp(u, p), border[:-1], border[-1])


def residual_norm(problem: Problem, x: Array) -> float:
    """max_i |G_i(u, p)| at x = (u, p)."""
    return float(np.max(np.abs(problem.residual(x[:-1], x[-1])), initial=0.0))


def bordered_newton(problem: Problem, x_target: Array, border: Array, tol: float, max_iter: int,
                    start: Optional[Array] = None, polish: bool = False,
                    linear_solver: LinearSolver = DIRECT) -> NewtonResult:
    """Solve G(u, p) = 0, b . (x - x_target) = 0 by Newton from x_target, or from `start` (a
    prediction on the hyperplane b . (x - x_target) = 0). polish: update at least once, so that
    a start already within tol ends as accurate as a corrector from afar (a function of the
    point, evaluated along a bracket, then does not carry tol's noise).

    Converged when max|G| <= tol (the border row is linear, so it holds to rounding after
    the first update and exactly at the start), or, for a problem with `rounding` > 0, when
    max|G| <= rounding * term_size: where G is as close to zero as its evaluation rounds.
    Fails on max_iter updates without convergence (saying what G rounds to there,
    NewtonResult.failure), a non-finite residual or a singular bordered matrix. The bordered
    matrices are factorized by linear_solver.
    """
    return factored_newton(problem, x_target, border, tol, max_iter, start, polish, linear_solver)[0]


def factored_newton(problem: Problem, x_target: Array, border: Array, tol: float, max_iter: int,
                    start: Optional[Array] = None, polish: bool = False,
                    linear_solver: LinearSolver = DIRECT):
    """bordered_newton's (result, the factorization of its last update's bordered matrix, or
    None where it made none): for chord_newton at points nearby."""
    x = np.array(x_target if start is None else start, dtype=float)
    first, lu = (1 if polish else 0), None
    for it in range(max_iter + 1):
        G = problem.residual(x[:-1], x[-1])
        r = float(np.max(np.abs(G), initial=0.0))
        if not np.isfinite(r):
            return NewtonResult(x, it, r, False), lu
        if r <= tol and it >= first:
            return NewtonResult(x, it, r, True), lu
        M = bordered_matrix(problem, x, border)
        if problem.rounding and it >= first and r <= problem.rounding * term_size(M, x):
            return NewtonResult(x, it, r, True), lu  # G is not computed closer to 0 than this
        if it == max_iter:
            return NewtonResult(x, max_iter, r, False, ROUNDING * term_size(M, x)), lu
        rhs = np.append(G, border @ (x - x_target))
        try:
            lu = linear_solver.factorize(M)
            x = x - lu.solve(rhs)
        except SingularMatrix:
            return NewtonResult(x, it, r, False), None
    # the loop returns at it == max_iter at the latest


CHORD_STEPS = 4
"""The most updates chord_newton makes before it gives up."""
CHORD_RATE = 0.1
"""chord_newton gives up where an update leaves the residual above this fraction of the last."""


def chord_newton(problem: Problem, x_target: Array, border: Array, tol: float, lu, start: Array,
                 polish: bool = False) -> Optional[NewtonResult]:
    """bordered_newton's system solved from `start` with a fixed factorization `lu` of the
    bordered matrix at a point nearby (the chord method: no new factorization, convergence
    linear at a rate of the order of the points' distance), or None where it does not converge
    to tol within CHORD_STEPS updates each shrinking the residual by CHORD_RATE (the caller
    then runs bordered_newton). polish as in bordered_newton."""
    x, first, last = np.array(start, dtype=float), (1 if polish else 0), np.inf
    for it in range(CHORD_STEPS + 1):
        G = problem.residual(x[:-1], x[-1])
        r = float(np.max(np.abs(G), initial=0.0))
        if not np.isfinite(r) or r > CHORD_RATE * last:
            return None
        if r <= tol and it >= first:
            return NewtonResult(x, it, r, True)
        if it == CHORD_STEPS:
            return None
        try:
            x, last = x - lu.solve(np.append(G, border @ (x - x_target))), r
        except SingularMatrix:
            return None
    return None


def term_size(M, x: Array) -> float:
    """max_i sum_j |dG_i/dx_j| |x_j| from the bordered matrix M's first n rows [G_u, G_p]: the
    size of the terms that cancel in G_i (exact for a linear G) [units of G]."""
    n = x.size - 1
    size = (abs(M) @ np.abs(x))[:n]
    return float(np.max(size, initial=0.0))


def fixed_p_newton(problem: Problem, u0: Array, p: float, tol: float, max_iter: int,
                   linear_solver: LinearSolver = DIRECT) -> NewtonResult:
    """Solve G(u, p) = 0 at fixed p from u0 (the border is e_p)."""
    return factored_fixed_p(problem, u0, p, tol, max_iter, linear_solver)[0]


def factored_fixed_p(problem: Problem, u0: Array, p: float, tol: float, max_iter: int,
                     linear_solver: LinearSolver = DIRECT):
    """fixed_p_newton's (result, near): near = (the factorization of its last update's
    bordered matrix, the border e_p), None where it made no update: for tangent(near=...)."""
    x0 = np.append(np.asarray(u0, dtype=float), p)
    e_p = np.zeros_like(x0)
    e_p[-1] = 1.0
    res, lu = factored_newton(problem, x0, e_p, tol, max_iter, linear_solver=linear_solver)
    return res, (None if lu is None else (lu, e_p))


def tangent(problem: Problem, x: Array, border: Array, near: Optional[tuple] = None,
            linear_solver: LinearSolver = DIRECT) -> Array:
    """Unit tangent t of the branch at x: [[G_u, G_p], [b^T]] t = e_(n+1), t / |t|.

    b . t > 0, so passing the previous tangent as b keeps the orientation.
    near = (lu, b_lu): the factorization of the bordered matrix with border b_lu at a point
    nearby (the corrector's last update: Newton's penultimate iterate). If it is sparse, t is
    then refined on it (solves.solve_near; a change of border by Sherman-Morrison,
    _Rebordered), and factorized afresh only where that does not converge: the same tangent
    to rounding for a solve and a product per correction instead of an LU. A dense near is
    not used: the dense matrices (the chain's, n < 240) keep their sweeps bit for bit, and
    cost little either way.
    Raises solves.SingularMatrix (a numpy.linalg.LinAlgError) if the bordered matrix is singular.
    """
    rhs = np.zeros(x.size)
    rhs[-1] = 1.0
    t = _tangent_system(problem, x, border, near, linear_solver).solve(rhs)
    return t / np.linalg.norm(t)


def _tangent_system(problem: Problem, x: Array, border: Array, near: Optional[tuple],
                    linear_solver: LinearSolver) -> RefinedSolve:
    """The bordered matrix at x with border b as a RefinedSolve on near = (lu, b_lu) (tangent)."""
    u, p = x[:-1], x[-1]
    G_u, G_p = problem.jacobian(u, p), problem.dG_dp(u, p)
    lu = None
    if near is not None and near[0].sparse:
        lu, b_lu = near
        if not np.array_equal(b_lu, border):
            lu = _Rebordered.of(lu, b_lu, border)
    return RefinedSolve(lambda: bordered(G_u, G_p, border[:-1], border[-1]),
                        lambda y: np.append(G_u @ y[:-1] + G_p * y[-1], border @ y), None, lu,
                        linear_solver.options)


class _Rebordered:
    """A factorization lu of M_0 = [[G_u, G_p], [b_lu^T]] as a solver of M = [[G_u, G_p],
    [b^T]], which differs from it by the rank one e_(n+1) d^T, d = b - b_lu (Sherman-Morrison):

        M^-1 r = y - z (d . y) / (1 + d . z),    y = M_0^-1 r,  z = M_0^-1 e_(n+1).

    1 + d . z = b . z, regular where b is not orthogonal to the branch's tangent (z is along
    it, with b_lu . z = 1). One solve more than lu, once."""

    def __init__(self, lu, d: Array, z: Array, denominator: float):
        self.lu, self.d, self.z, self.denominator = lu, d, z, denominator

    @classmethod
    def of(cls, lu, b_lu: Array, b: Array) -> Optional["_Rebordered"]:
        """The solver, or None where lu's own solve is not finite or 1 + d . z is 0 (M is
        then factorized)."""
        e = np.zeros(b.size)
        e[-1] = 1.0
        try:
            z = lu.solve(e)
        except SingularMatrix:
            return None
        d = b - b_lu
        denominator = 1.0 + float(d @ z)
        if not np.isfinite(denominator) or denominator == 0.0:
            return None
        return cls(lu, d, z, denominator)

    def solve(self, r: Array, transpose: bool = False) -> Array:
        if transpose:
            raise NotImplementedError("_Rebordered solves with M only")
        y = self.lu.solve(r)
        return y - self.z * (float(self.d @ y) / self.denominator)
