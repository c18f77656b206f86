"""Folds and Hopf points of a finished branch, located post hoc.

Both are sign changes of a smooth test function between accepted points k, k+1, refined by
the Illinois method along the step's secant segment (segment.py):
  fold  (limit point):  psi(s) = t_p(s), the p component of the unit tangent at x(s)
                        (bordered with the secant), zero where the branch turns back in p;
  Hopf:                 psi(s) = Re lambda(s) of a complex pair (status +1 at both ends),
                        lambda(s) the upper eigenvalue nearest to the interpolated one.
Post hoc means the problem is evaluated after the whole run: only valid for problems whose
commit hook does nothing (no history carried alongside u).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from .branch import Branch
from .newton import tangent
from .problem import Problem
from .segment import Segment, refine_sign_change
from .spectra import DEFAULT_REL_TOL, eigen_status

Array = np.ndarray


@dataclass(frozen=True)
class SpecialPoint:
    """kind "fold" | "hopf"; p, u at the located point; bracket (p_lo, p_hi) of the final
    Illinois bracket; step k of the branch step containing it; value: 0 for a fold, the
    eigenvalue (~ i omega) for a Hopf point."""

    kind: str
    p: float
    u: Array
    bracket: tuple[float, float]
    step: int
    value: complex


def _locate(problem: Problem, branch: Branch, k: int, psi: Callable[[Segment, Array, float], float],
            done_tol: float, newton_tol: float, max_newton: int, by_x: bool):
    """Refine the sign change of psi over step k; returns (x at the interpolated root, p bracket)."""
    seg = Segment(problem, branch.x[k], branch.x[k + 1], newton_tol, max_newton)
    pts = {0.0: seg.x_a, 1.0: seg.x_b}
    vals = {0.0: psi(seg, seg.x_a, 0.0), 1.0: psi(seg, seg.x_b, 1.0)}

    def f(s: float) -> float:
        pts[s] = seg.point(s)
        vals[s] = psi(seg, pts[s], s)
        return vals[s]

    def done(lo: float, hi: float) -> bool:
        d = pts[hi] - pts[lo]
        return (np.linalg.norm(d) if by_x else abs(d[-1])) <= done_tol or hi - lo <= 1e-14

    lo, hi = refine_sign_change(f, 0.0, vals[0.0], 1.0, vals[1.0], done)
    t = 0.0 if lo == hi else vals[lo] / (vals[lo] - vals[hi])
    x = pts[lo] + t * (pts[hi] - pts[lo])
    return x, (min(pts[lo][-1], pts[hi][-1]), max(pts[lo][-1], pts[hi][-1]))


def locate_folds(problem: Problem, branch: Branch, tol_x: float = 1e-9,
                 newton_tol: float = 1e-12, max_newton: int = 10) -> list[SpecialPoint]:
    """Folds: sign changes of t_p between accepted points, refined until |x_hi - x_lo| <= tol_x.
    Since p is quadratic in arclength at a fold, |p - p_fold| ~ |p''| tol_x^2 / 2."""
    def psi(seg: Segment, x: Array, s: float) -> float:
        return float(tangent(problem, x, seg.sigma)[-1])

    found = []
    for k in np.flatnonzero(np.sign(branch.tangent[:-1, -1]) * np.sign(branch.tangent[1:, -1]) < 0):
        x, bracket = _locate(problem, branch, int(k), psi, tol_x, newton_tol, max_newton, by_x=True)
        found.append(SpecialPoint("fold", float(x[-1]), x[:-1], bracket, int(k), 0.0))
    return found


def locate_hopf(problem: Problem, branch: Branch, tol_p: float = 1e-10, rel_tol: float = DEFAULT_REL_TOL,
                newton_tol: float = 1e-12, max_newton: int = 10) -> list[SpecialPoint]:
    """Hopf points: a tracked eigenvalue with Im > thr at both ends of a step whose real part
    changes sign; refined until |dp| <= tol_p."""
    found = []
    ev = branch.eigenvalues
    for k in range(len(branch) - 1):
        upper = (eigen_status(ev[k], rel_tol) > 0) & (eigen_status(ev[k + 1], rel_tol) > 0)
        for i in np.flatnonzero(upper & (np.sign(ev[k].real) * np.sign(ev[k + 1].real) < 0)):
            lam_a, lam_b = ev[k, i], ev[k + 1, i]

            def pair(x: Array, s: float) -> complex:
                lam = problem.spectrum(x[:-1], x[-1])
                lam = lam[lam.imag > 0]
                return complex(lam[np.argmin(np.abs(lam - (lam_a + s * (lam_b - lam_a))))])

            x, bracket = _locate(problem, branch, k, lambda seg, x, s: pair(x, s).real,
                                 tol_p, newton_tol, max_newton, by_x=False)
            value = pair(x, 0.5)
            found.append(SpecialPoint("hopf", float(x[-1]), x[:-1], bracket, k, value))
    return found
