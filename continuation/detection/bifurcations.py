"""Folds, branch points and Hopf points of a finished branch, located post hoc.

Both are sign changes of a smooth test function between accepted points k, k+1, refined by
segment.refine_sign_change along the step's secant segment (segment.py):
  fold  (limit point):  psi(s) = t_p(s), the p component of the unit tangent at x(s)
                        (bordered with the secant), zero where the branch turns back in p;
  branch point:         psi(s) = det [[G_u, G_p], [sigma^T]] at x(s), sigma the step's
                        secant, zero where a second branch crosses (branch_point_brackets);
  Hopf:                 psi(s) = Re lambda(s) of a complex pair (status +1 at both ends),
                        lambda(s) the upper eigenvalue nearest to the interpolated one;
                        only where Re goes from clearly below the imaginary axis to clearly
                        above it or back (relative to max|lambda|, as Im tells complex from
                        real), and never on a spectrum symmetric under lambda -> -lambda.
Post hoc means the problem is evaluated after the whole run: only valid for problems whose
commit hook does nothing (no history carried alongside u).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.linalg.solves import DIRECT, LinearSolver, dense, log_determinant
from diskfriction.continuation.stepping.newton import bordered_matrix, tangent
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.spectra.eigensolvers import DEFAULT, Eigensolver
from diskfriction.continuation.stepping.segment import Segment, refine_sign_change
from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL, eigen_status, imag_threshold, status_at

Array = np.ndarray


@dataclass(frozen=True)
class SpecialPoint:
    """kind "fold" | "hopf" | "branch" (a simple branch point); p, u at the located point;
    bracket (p_lo, p_hi) of the final bracket; step k of the branch step containing
    it; value: 0 for a fold or a branch point, the eigenvalue (~ i omega) for a Hopf point."""

    kind: str
    p: float
    u: Array
    bracket: tuple[float, float]
    step: int
    value: complex


def _locate(problem: Problem, x_a: Array, x_b: Array, psi: Callable[[Segment, Array, float], float],
            done_tol: float, newton_tol: float, max_newton: int, by_x: bool,
            span: tuple[float, float] = (0.0, 1.0), linear_solver: LinearSolver = DIRECT):
    """Refine the sign change of psi over the step from x_a to x_b (accepted points), between
    segment coordinates span (default the whole step); returns (x at the interpolated root, p
    bracket)."""
    seg = Segment(problem, x_a, x_b, newton_tol, max_newton, polish=False,
                  linear_solver=linear_solver)
    pts, vals = {}, {}

    def f(s: float) -> float:
        pts[s] = seg.point(s)
        vals[s] = psi(seg, pts[s], s)
        return vals[s]

    def done(lo: float, hi: float) -> bool:
        d = pts[hi] - pts[lo]
        return (np.linalg.norm(d) if by_x else abs(d[-1])) <= done_tol or hi - lo <= 1e-14

    lo, hi = refine_sign_change(f, span[0], f(span[0]), span[1], f(span[1]), done)
    t = 0.0 if lo == hi else vals[lo] / (vals[lo] - vals[hi])
    x = pts[lo] + t * (pts[hi] - pts[lo])
    return x, (min(pts[lo][-1], pts[hi][-1]), max(pts[lo][-1], pts[hi][-1]))


def bordered_determinant(problem: Problem, x: Array, border: Array) -> float:
    """det [[G_u, G_p], [b^T]] at x = (u, p), as sign |det|^(1 / (n + 1)): a continuous
    function of x with the determinant's signs and zeros, of moderate size whatever n."""
    sign, logabs = log_determinant(bordered_matrix(problem, x, border))
    return float(sign * np.exp(logabs / x.size))


def branch_point_brackets(problem: Problem, branch: Branch, newton_tol: float = 1e-12,
                          max_newton: int = 10, rel_tol: float = DEFAULT_REL_TOL,
                          linear_solver: LinearSolver = DIRECT) -> list[tuple[int, float, float]]:
    """Where the branch passes simple branch points: (step k, s_lo, s_hi), a bracket in the
    step's segment coordinate over which the determinant of [[G_u, G_p], [sigma^T]] (sigma the
    step's unit secant) changes sign. On a regular branch it is (sigma . t) det [[G_u, G_p],
    [t^T]] with t the oriented unit tangent, of one sign along the branch and through a fold
    (where det G_u changes sign); it changes sign where a second branch crosses (dim ker
    [G_u, G_p] = 2). Two branch points in one step leave the ends' signs alike: where the
    tracked spectrum has two or more real eigenvalues changing sign over the step (Turing
    points of neighbouring modes), the determinant is also taken between their estimated
    crossings (linear in the step), and each sign change there is a bracket."""
    x, lam = branch.x, branch.eigenvalues
    found = []
    for k in range(len(branch) - 1):
        seg = Segment(problem, x[k], x[k + 1], newton_tol, max_newton, polish=False,
                      linear_solver=linear_solver)
        ends = lam[k:k + 2]
        real = (eigen_status(ends[0], rel_tol) == 0) & (eigen_status(ends[1], rel_tol) == 0)
        re0, re1 = ends[0].real[real], ends[1].real[real]
        turning = re0 * re1 < 0.0
        crossings = np.sort(re0[turning] / (re0[turning] - re1[turning]))
        nodes = np.concatenate([[0.0], 0.5 * (crossings[1:] + crossings[:-1]), [1.0]])
        signs = [np.sign(bordered_determinant(problem, seg.point(s), seg.sigma)) for s in nodes]
        found += [(k, float(nodes[m]), float(nodes[m + 1])) for m in range(nodes.size - 1)
                  if signs[m] * signs[m + 1] < 0]
    return found


def locate_branch_points(problem: Problem, branch: Branch, brackets: list[tuple[int, float, float]],
                         tol_x: float = 1e-12, newton_tol: float = 1e-12, max_newton: int = 10,
                         linear_solver: LinearSolver = DIRECT) -> list[SpecialPoint]:
    """Branch points: the sign change of bordered_determinant over each of `brackets`
    (branch_point_brackets), refined until |x_hi - x_lo| <= tol_x (kind "branch", value 0)."""
    def psi(seg: Segment, x: Array, s: float) -> float:
        return bordered_determinant(problem, x, seg.sigma)

    found = []
    for k, s_lo, s_hi in brackets:
        x, bracket = _locate(problem, *branch.x[k:k + 2], psi, tol_x, newton_tol, max_newton, by_x=True,
                             span=(s_lo, s_hi), linear_solver=linear_solver)
        found.append(SpecialPoint("branch", float(x[-1]), x[:-1], bracket, int(k), 0.0))
    return found


def other_direction(problem: Problem, point: SpecialPoint, along: Array) -> Array:
    """The unit direction in x = (u, p) of the second branch through the branch point `point`:
    the null space of [G_u, G_p] there is two-dimensional (its two right singular vectors of
    smallest singular value), and the direction in it orthogonal to `along`, the tangent of
    the branch that found the point. As AUTO and BifurcationKit start their branch switching:
    exact for a pitchfork (the branches cross at right angles in the metric of x), the start of
    a corrector that lands on the other branch for a transcritical crossing."""
    u, p = point.u, point.p
    G_x = np.column_stack([dense(problem.jacobian(u, p)), problem.dG_dp(u, p)])
    kernel = np.linalg.svd(G_x)[2][-2:]  # rows: the two right singular vectors nearest null
    c = kernel @ along
    phi = kernel.T @ np.array([-c[1], c[0]])
    return phi / np.linalg.norm(phi)


def locate_folds(problem: Problem, branch: Branch, tol_x: float = 1e-9,
                 newton_tol: float = 1e-12, max_newton: int = 10,
                 skip: tuple[int, ...] = (), linear_solver: LinearSolver = DIRECT) -> list[SpecialPoint]:
    """Folds: sign changes of t_p between accepted points, refined until |x_hi - x_lo| <= tol_x.
    Since p is quadratic in arclength at a fold, |p - p_fold| ~ |p''| tol_x^2 / 2. Steps in
    `skip` are left out: a branch point where the branch also turns in p (a pitchfork seen
    from its symmetric branch) is a branch point, not a fold."""
    def psi(seg: Segment, x: Array, s: float) -> float:
        return float(tangent(problem, x, seg.sigma, linear_solver=linear_solver)[-1])

    found = []
    turns = np.flatnonzero(np.sign(branch.tangent[:-1, -1]) * np.sign(branch.tangent[1:, -1]) < 0)
    for k in (k for k in turns if k not in skip):
        x, bracket = _locate(problem, *branch.x[k:k + 2], psi, tol_x, newton_tol, max_newton, by_x=True,
                             linear_solver=linear_solver)
        found.append(SpecialPoint("fold", float(x[-1]), x[:-1], bracket, int(k), 0.0))
    return found


SYMMETRY_TOL = 1e-6
"""A spectrum is taken as symmetric under lambda -> -lambda when every eigenvalue has a partner
-lambda within SYMMETRY_TOL max|lambda|: above the rounding of a double eigenvalue on the
imaginary axis (about sqrt(machine epsilon) = 1.5e-8 of the scale, a Jordan block's), far
below any real part a physical spectrum would call small."""


def real_signs(eigvals: Array, rel_tol: float = DEFAULT_REL_TOL) -> Array:
    """Per eigenvalue: +1 if Re > thr, -1 if Re < -thr, 0 on the imaginary axis up to rounding,
    thr = rel_tol max|lambda| (the threshold that tells complex from real, spectra/tracking.py)."""
    return status_at(1j * np.asarray(eigvals), imag_threshold(eigvals, rel_tol))  # Im(i lambda) = Re lambda


def symmetric(eigvals: Array, tol: float = SYMMETRY_TOL) -> bool:
    """Whether lambda -> -lambda maps the spectrum onto itself within tol max|lambda|: the
    spectrum of a conservative (Hamiltonian or reversible) system written as first order."""
    lam = np.asarray(eigvals, dtype=complex)
    lam = lam[np.isfinite(lam)]
    thr = tol * max(float(np.abs(lam).max(initial=0.0)), np.finfo(float).tiny)
    gap = np.abs(lam[:, None] + lam[None, :])  # |lambda_i - (-lambda_j)|
    return bool((gap.min(axis=1) <= thr).all())


def conservative(eigenvalues: Array) -> bool:
    """Whether the branch's spectrum is symmetric under lambda -> -lambda at every point: there
    a pair leaves the imaginary axis only by colliding with another (flutter), never by
    crossing it, so a Hopf point is not defined."""
    return all(symmetric(row) for row in eigenvalues)


CONSERVATIVE = ("the tracked spectrum is symmetric under lambda -> -lambda at every point (a "
                "conservative or reversible system written as first order): a pair leaves the "
                "imaginary axis only by colliding with another, not by a Hopf crossing, so no "
                "Hopf point is reported; to locate those collisions track the second-order "
                "matrix (M^-1 K), whose eigenvalues omega^2 collide on the real axis")
"""Why locate_hopf reports nothing on a conservative spectrum (a warning of the run)."""


def hopf_steps(eigenvalues: Array, rel_tol: float = DEFAULT_REL_TOL) -> list[tuple[int, int]]:
    """(step k, column i) of every crossing of Re = 0 by tracked eigenvalue i: the upper member
    of a complex pair at every point from one real part clearly on one side of the imaginary
    axis (real_signs) to the next clearly on the other; k is the first step of that span over
    which Re changes sign. Sign changes of real parts within rounding of zero are none."""
    ev = np.asarray(eigenvalues)
    upper = np.array([eigen_status(row, rel_tol) > 0 for row in ev])
    signs = np.array([real_signs(row, rel_tol) for row in ev])
    found = []
    for i in range(ev.shape[1]):
        last = None  # (point, sign) of the last clear real part while the pair lasts
        for k in range(ev.shape[0]):
            if not upper[k, i]:
                last = None
            elif signs[k, i] != 0:
                if last is not None and last[1] != signs[k, i]:
                    re = ev[last[0]:k + 1, i].real
                    found.append((last[0] + int(np.flatnonzero(re[:-1] * re[1:] <= 0)[0]), i))
                last = (k, signs[k, i])
    return sorted(found)


def crossing_steps(eigenvalues: Array, growth: Callable[[Array], Array],
                   rel_tol: float = DEFAULT_REL_TOL) -> list[tuple[int, int, bool]]:
    """(step k, column i, rising) of every sign change of growth(lambda) along tracked
    eigenvalue i: from a point where it is clearly on one side of zero (|growth| > rel_tol
    sqrt(max|lambda|) there: growth in units of a frequency) to the next clearly on the other;
    k is the first step of that span over which the sign changes, rising where it turns
    positive. growth maps an array of eigenvalues to their growth rates elementwise; nan
    eigenvalues (untracked) break a span. Of a complex pair crossing together (its two members,
    conjugate, have one growth rate) only the member with Im lambda >= 0 where growth > 0 is
    kept."""
    ev = np.asarray(eigenvalues, dtype=complex)
    g = np.asarray(growth(ev), dtype=float)
    scale = np.sqrt(np.nanmax(np.abs(ev), axis=1, initial=0.0))[:, None]
    signs = np.where(np.abs(g) > rel_tol * scale, np.sign(g), 0.0)
    found = []
    for i in range(ev.shape[1]):
        last = None  # (point, sign) of the last clear value
        for k in range(ev.shape[0]):
            if not np.isfinite(g[k, i]):
                last = None
            elif signs[k, i] != 0:
                if last is not None and last[1] != signs[k, i]:
                    span = g[last[0]:k + 1, i]
                    step = last[0] + int(np.flatnonzero(span[:-1] * span[1:] <= 0)[0])
                    rising = bool(signs[k, i] > 0)
                    if ev[step + 1 if rising else step, i].imag >= 0:
                        found.append((step, i, rising))
                last = (k, signs[k, i])
    return sorted(found)


def locate_hopf(problem: Problem, branch: Branch, tol_p: float = 1e-10, rel_tol: float = DEFAULT_REL_TOL,
                newton_tol: float = 1e-12, max_newton: int = 10, linear_solver: LinearSolver = DIRECT,
                eigensolver: Eigensolver = DEFAULT) -> list[SpecialPoint]:
    """Hopf points: a tracked complex pair whose real part crosses zero (hopf_steps), refined
    until |dp| <= tol_p, the spectra by `eigensolver` (locate_crossing with growth Re lambda).
    None on a conservative spectrum (conservative: see CONSERVATIVE)."""
    ev = branch.eigenvalues
    if conservative(ev):
        return []
    found = (locate_crossing(problem, branch.x[k], branch.x[k + 1], ev[k, i], ev[k + 1, i], _real_part, k,
                             tol_p, newton_tol, max_newton, linear_solver, eigensolver)
             for k, i in hopf_steps(ev, rel_tol))
    return [point for point in found if point is not None]


def _real_part(lam: complex) -> float:
    """Re lambda: the growth rate of a first-order system's mode e^(lambda t)."""
    return lam.real


def locate_crossing(problem: Problem, x_a: Array, x_b: Array, lam_a: complex, lam_b: complex,
                    growth: Callable[[complex], float], step: int, tol_p: float = 1e-10,
                    newton_tol: float = 1e-12, max_newton: int = 10, linear_solver: LinearSolver = DIRECT,
                    eigensolver: Eigensolver = DEFAULT, upper: bool = True,
                    kind: str = "hopf",
                    nearest: Optional[Callable[[Problem, Array, complex], complex]] = None
                    ) -> Optional[SpecialPoint]:
    """Where the growth rate growth(lambda) of one tracked eigenvalue changes sign over the step
    from the accepted point x_a (its eigenvalue lam_a) to x_b (lam_b), refined along the step's
    secant segment until |dp| <= tol_p. lambda(s) at the segment coordinate s is the eigenvalue
    (by `eigensolver`) nearest to the interpolant lam_a + s (lam_b - lam_a), among the upper
    members of complex pairs where `upper` (a Hopf point: growth = Re lambda), among all where
    not (a crossing that may follow an eigenvalue through its pair's birth). Returns the point
    (`kind`, value lambda there); `step` is the branch step it lies in. None where `problem`
    gives the growth one sign at both ends: the sign then changed where the spectrum jumps at an
    end, not inside the step (a problem whose matrix changes from one step to the next, as a
    packing's at a contact event). nearest(problem, x, target): the eigenvalue at x nearest
    target, where a caller has a cheaper way to it than the whole spectrum (not with `upper`)."""
    def pair(x: Array, s: float) -> complex:
        target = lam_a + s * (lam_b - lam_a)
        if nearest is not None and not upper:
            return complex(nearest(problem, x, target))
        lam = eigensolver.eigensystem(problem, x[:-1], x[-1]).values
        lam = lam[lam.imag > 0] if upper else lam
        return complex(lam[np.argmin(np.abs(lam - target))])

    ends = {0.0: pair(x_a, 0.0), 1.0: pair(x_b, 1.0)}  # taken once: the refinement starts from them
    if not growth(ends[0.0]) * growth(ends[1.0]) < 0.0:
        return None

    def psi(seg: Segment, x: Array, s: float) -> float:
        return growth(ends[s] if s in ends else pair(x, s))

    x, bracket = _locate(problem, x_a, x_b, psi, tol_p, newton_tol, max_newton, by_x=False,
                         linear_solver=linear_solver)
    return SpecialPoint(kind, float(x[-1]), x[:-1], bracket, step, pair(x, 0.5))
