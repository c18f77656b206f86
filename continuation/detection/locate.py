"""Locating a collision as a defective double eigenvalue, by Newton's method on a minimally
augmented system in (u, p, lambda) (in the spirit of the fold and Hopf locators of MatCont and
AUTO: Govaerts, Numerical Methods for Bifurcations of Dynamical Equilibria, SIAM 2000).

For A = A(x), x = (u, p), and a real lambda, border A - lambda I with two fixed vectors b, c
(approximate left and right null vectors):

    B = [[A - lambda I, b], [c^T, 0]],    B [v; g] = e_(n+1),    B^T [w; g~] = e_(n+1).

Where B is regular, g = 0 exactly when A - lambda I is singular (v its right and w its left null
vector), and by differentiating the bordered system
    g_lambda = w^T v,        g_x . d = -w^T (dA[d]) v           (dA[d]: derivative along d).
A double eigenvalue with a Jordan block (a collision: geometric multiplicity 1) is where the
eigenvalue is a double root of g in lambda, i.e. where also h = g_lambda = w^T v = 0 (left and
right eigenvectors orthogonal). The located point solves the n + 2 equations

    G(x) = 0,    g(x, lambda) = 0,    h(x, lambda) = 0

in the n + 2 unknowns (x, lambda). Newton's step (dx, dlambda) is found by block elimination:
dx = a + beta t with G_x a = -G, t . a = 0 and t the unit tangent (one factorization of the
bordered [[G_u, G_p], [t^T, 0]], which stays regular through folds), then a 2 x 2 system

    [g_x . t   g_lambda] [beta   ]   [-g - g_x . a]
    [h_x . t   h_lambda] [dlambda] = [-h - h_x . a].

The derivatives of h come from the same factorization of B: with B [v_d; .] = -[dA[d] v; 0] and
B^T [w_d; .] = -[dA[d]^T w; 0], h_x . d = w_d . v + w . v_d, and with dA = -I for lambda.
dA[d] v and dA[d]^T w are central differences of A along d (step problem.derivative_step), so
one iteration costs two factorizations, ten solves and four evaluations of A: no eigensolver.
Convergence is quadratic (tested on a 2 x 2 problem with a closed-form collision) as long as the
differences are accurate; the iteration stops when |dp| <= tol_p / 100 and max|G| <= newton_tol.

At the solution, v is the eigenvector and v_lambda (B [v_lambda; gamma] = [v; 0]) solves
(A - lambda I) v_lambda = v: the generalized eigenvector of the Jordan chain.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from diskfriction.continuation.linalg.solves import DIRECT, LinearSolver, RefinedSolve, SingularMatrix, bordered
from diskfriction.continuation.stepping.newton import bordered_matrix
from diskfriction.continuation.problem import Problem

Array = np.ndarray


@dataclass(frozen=True)
class Located:
    """A converged collision: x = (u, p), the double eigenvalue lam, unit right eigenvector v
    (largest component positive), generalized eigenvector w ((A - lam I) w = v, w orthogonal
    to v), overlap |y . v| with the unit left eigenvector y (-> 0 at a Jordan block), the
    residual max|G|, the last Newton correction |dp| (the location's uncertainty), the
    iterations, and the history of |dp| per iteration (quadratic convergence)."""

    x: Array
    lam: float
    v: Array
    w: Array
    overlap: float
    residual: float
    dp: float
    iterations: int
    history: tuple = field(default=())


BORDER_SCALE = 1e-6
"""The borders b, c are unit vectors times BORDER_SCALE max(1, max|A_ij|) at the first iterate:
far below A's entries, SuperLU's partial pivoting never takes a border entry before the last
pivot, which keeps the fill of the two dense borders to their own row and column (unit
borders fill L + U several times over: benchmarks/solve_speed.py). g and h scale with the borders;
their zeros, and so the Newton steps in (x, lambda), do not."""


class LocatorFailed(RuntimeError):
    """Newton did not converge (or met a singular bordered matrix)."""


def _unit(z: Array) -> Array:
    z = np.real(z).astype(float)
    return z / np.linalg.norm(z)


def locate_double_eigenvalue(problem: Problem, x0: Array, lam0: float, right0: Array, left0: Array,
                             tangent0: Array, tol_p: float, newton_tol: float,
                             max_iter: int = 12, linear_solver: LinearSolver = DIRECT) -> Located:
    """Newton on (G, g, h) = 0 from (x0, lam0); right0 and left0 approximate the eigenvectors of
    the colliding pair (their real parts become the fixed borders c and b), tangent0 the branch
    tangent near x0; the bordered systems solved by linear_solver. Raises LocatorFailed."""
    x, lam, t = np.array(x0, dtype=float), float(lam0), _unit(tangent0)
    c, b = _unit(right0), _unit(left0)  # scaled by _border_scale at the first A
    m = c.size  # A is m x m (m may differ from the number of unknowns)
    e = np.zeros(x.size)
    e[-1] = 1.0
    e_m = np.zeros(m + 1)
    e_m[-1] = 1.0
    history = []
    for it in range(1, max_iter + 1):
        u, p = x[:-1], float(x[-1])
        G = problem.residual(u, p)
        try:
            branch = linear_solver.factorize(bordered_matrix(problem, x, t))
            a = branch.solve(np.append(-G, 0.0))
            t_new = branch.solve(e)
            t = t_new / np.linalg.norm(t_new) * np.sign(t_new @ t)
            A = problem.stability_matrix(u, p)
            if it == 1:
                scale = _border_scale(A)
                c, b = scale * c, scale * b
            B = linear_solver.factorize(bordered(A - lam * _identity(A), b, c))
            vg = B.solve(e_m)
            v, g = vg[:m], vg[m]
            w = B.solve(e_m, transpose=True)[:m]
            h = w @ v
            v_l = B.solve(np.append(v, 0.0))[:m]
            w_l = B.solve(np.append(w, 0.0), transpose=True)[:m]
        except SingularMatrix as err:
            raise LocatorFailed(f"singular bordered matrix at p = {p:.12g}: {err}") from None
        h_lam = w_l @ v + w @ v_l

        def along(d: Array) -> tuple[float, float]:
            """(g_x . d, h_x . d) for a direction d in x."""
            norm = np.linalg.norm(d)
            if norm == 0.0:
                return 0.0, 0.0
            dAv, dATw = _derivative_products(problem, x, d / norm, v, w)
            v_d = -B.solve(np.append(dAv, 0.0))[:m]
            w_d = -B.solve(np.append(dATw, 0.0), transpose=True)[:m]
            return -norm * float(w @ dAv), norm * float(w_d @ v + w @ v_d)

        g_a, h_a = along(a)
        g_t, h_t = along(t)
        M = np.array([[g_t, h], [h_t, h_lam]])
        try:
            beta, dlam = np.linalg.solve(M, [-g - g_a, -h - h_a])
        except np.linalg.LinAlgError:
            raise LocatorFailed(f"singular 2 x 2 Newton system at p = {p:.12g}") from None
        dx = a + beta * t
        x, lam = x + dx, lam + dlam
        history.append(abs(dx[-1]))
        if not np.all(np.isfinite(x)):
            raise LocatorFailed("non-finite Newton iterate")
        residual = float(np.max(np.abs(problem.residual(x[:-1], x[-1]))))
        if abs(dx[-1]) <= 0.01 * tol_p and residual <= newton_tol:
            return _finish(problem, x, lam, b, c, residual, abs(dx[-1]), it, tuple(history),
                           linear_solver, B if B.sparse else None)
    raise LocatorFailed(f"no convergence in {max_iter} Newton iterations (|dp| = {history[-1]:.3g})")


def _shifted(A, lam: float, b: Array, c: Array, near, linear_solver: LinearSolver) -> RefinedSolve:
    """B = [[A - lam I, b], [c^T, 0]] as a RefinedSolve on `near` (the last iterate's B)."""
    return RefinedSolve(lambda: bordered(A - lam * _identity(A), b, c),
                        lambda y: np.append(A @ y[:-1] - lam * y[:-1] + b * y[-1], c @ y[:-1]),
                        lambda y: np.append(A.T @ y[:-1] - lam * y[:-1] + c * y[-1], b @ y[:-1]),
                        near, linear_solver.options)


def _border_scale(A) -> float:
    """BORDER_SCALE max(1, max|A_ij|) for a dense or sparse A."""
    return BORDER_SCALE * float(np.max(np.abs(A.data if sp.issparse(A) else A), initial=1.0))


def _identity(A):
    return sp.identity(A.shape[0], format="csr") if sp.issparse(A) else np.eye(A.shape[0])


def _derivative_products(problem: Problem, x: Array, d: Array, v: Array, w: Array):
    """(dA[d] v, dA[d]^T w) by central differences of A along the unit direction d."""
    h = problem.derivative_step(x)
    A_plus = problem.stability_matrix(x[:-1] + h * d[:-1], x[-1] + h * d[-1])
    A_minus = problem.stability_matrix(x[:-1] - h * d[:-1], x[-1] - h * d[-1])
    return (A_plus @ v - A_minus @ v) / (2 * h), (A_plus.T @ w - A_minus.T @ w) / (2 * h)


def _finish(problem, x, lam, b, c, residual, dp, iterations, history, linear_solver, near=None) -> Located:
    """Eigenvector, Jordan vector and left-right overlap at the converged point (near: the last
    iterate's sparse factorization of B, refined on: jordan_chain; a dense one costs less to
    make again than to refine on)."""
    A = problem.stability_matrix(x[:-1], float(x[-1]))
    v, w, overlap = jordan_chain(A, lam, b, c, linear_solver, near)
    return Located(x, float(lam), v, w, overlap, residual, dp, iterations, history)


def jordan_chain(A, lam: float, b: Array, c: Array,
                 linear_solver: LinearSolver = DIRECT, near=None) -> tuple[Array, Array, float]:
    """(v, w, overlap) at a double eigenvalue lam of A (dense or sparse), from the bordered
    matrix B = [[A - lam I, b], [c^T, 0]] (module docstring; one factorization at most, three
    solves):
    the unit right eigenvector v (B [v; g] = e_(n+1), largest component positive), the
    generalized eigenvector w ((A - lam I) w = v up to the border, made orthogonal to v) and
    overlap = |y . v| for the unit left eigenvector y (B^T [y; .] = e_(n+1); -> 0 at a Jordan
    block). linear_solver: the run's (its ordering for a sparse A). near: the factorization of B at a
    point nearby (the locator's last iterate), refined on instead of factorizing (RefinedSolve).
    Raises SingularMatrix if the borders do not make B regular."""
    m = A.shape[0]
    e = np.zeros(m + 1)
    e[-1] = 1.0
    B = _shifted(A, lam, b, c, near, linear_solver)
    v = B.solve(e)[:m]
    y = B.solve(e, transpose=True)[:m]
    scale = np.linalg.norm(v)
    sign = np.sign(v[np.argmax(np.abs(v))])
    v_unit = sign * v / scale
    w = sign * B.solve(np.append(v, 0.0))[:m] / scale
    w = w - (v_unit @ w) * v_unit
    return v_unit, w, float(abs(y @ v_unit) / np.linalg.norm(y))


def jordan_chain_near(A, lam: float, linear_solver: LinearSolver = DIRECT) -> tuple[Array, Array, float]:
    """jordan_chain at lam when no approximate eigenvector is at hand (a collision interpolated
    between samples): a first bordered solve with pseudo-random borders (seeded: runs repeat;
    B is singular only for borders orthogonal to a null vector, a set of measure zero) gives
    the right and left null vectors, which then border B. On a Jordan block with lam 1e-9 off,
    v and w come out within 1e-9, as from least squares on the dense matrix; the random
    borders alone leave w 3e-8 off. Two factorizations, no dense matrix at a sparse A."""
    m = A.shape[0]
    rng = np.random.default_rng(0)
    scale = _border_scale(A)
    e = np.zeros(m + 1)
    e[-1] = 1.0
    B = linear_solver.factorize(bordered(A - lam * _identity(A), scale * _unit(rng.standard_normal(m)),
                                         scale * _unit(rng.standard_normal(m))))
    v, y = B.solve(e)[:m], B.solve(e, transpose=True)[:m]
    return jordan_chain(A, lam, scale * _unit(y), scale * _unit(v), linear_solver)
