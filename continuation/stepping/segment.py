"""Points of the branch between two accepted points, and bracket refinement on them.

Between converged points x_a and x_b the branch is parametrised by s in [0, 1]: the point
x(s) solves
    G(u, p) = 0,    sigma . (x - ((1 - s) x_a + s x_b)) = 0,    sigma = (x_b - x_a) / |x_b - x_a|,
i.e. the branch cut by the hyperplane normal to the secant through the secant point at s.
x(0) = x_a and x(1) = x_b; s is monotone along the arc as long as the tangent turns by less
than 90 degrees over the step (the step angle check keeps it far below). Unlike a fixed-p
corrector this works through folds. Between accepted points the problem must be in the
state committed at x_a (events are located before the step is committed).

The corrector at s starts from the point predicted by the solved points nearest s on either
side (the ends and every point solved or remembered since): the cubic Hermite interpolant
where both carry tangents, else the straight line between them. Both lie on the hyperplane at
s (sigma . x is linear in s along the branch). A bracket refined to 1e-13 then costs its late
points one Newton update each instead of the three or four a start from the secant point
needs; a bracket's nearest points are a better guide than farther ones with tangents.

A segment with a root end (Segment.root = s_e: a contact opens at s_e, just before 1, and the
stability matrix goes as the square root of the distance to it; root_ends.py) is addressed by
the coordinate w in [0, 1] instead, s = s_e (1 - (1 - w)^2), w = 1 the end x_b: eigenvalues
~ (s_e - s)^(1/2) are smooth in w. Every method taking a position (point, predicted,
remember) takes that coordinate; without a root end w = s.
"""
from __future__ import annotations

import bisect
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.linalg.solves import DIRECT, LinearSolver
from diskfriction.continuation.stepping.newton import chord_newton, factored_newton
from diskfriction.continuation.problem import Problem

Array = np.ndarray


HERMITE_ALONG = 0.1
"""The Hermite prediction is used where both tangents make sigma . t at least this (the branch
runs along the secant); otherwise the straight line between the two points."""


CHORD_KEPT = 8
"""Factorizations a Segment keeps (the most recent of its Newton solves): for the chord method
(chord=True) and the tangents at its points (Segment.near)."""


class SegmentSolveError(RuntimeError):
    """The corrector failed at an intermediate point of a step."""


@dataclass(frozen=True)
class Segment:
    """The branch between x_a (s = 0) and x_b (s = 1), with the unit tangents there if known
    (t_a, t_b, oriented along the branch); see the module docstring. polish: a predicted point
    gets at least one Newton update (bordered_newton's polish), for brackets of an event
    function; not for the brackets of a branch point, where the bordered matrix is nearly
    singular and an update from a point already within tol kicks it off the branch (the
    Brusselator chain's 17 branch points were lost so). root: s_e of a root end (module
    docstring), None: the coordinate is s itself. chord: a point is first solved by the chord
    method from the factorization kept at the nearest point Newton solved (newton.chord_newton;
    the last CHORD_KEPT are kept), Newton where that does not converge fast; for the collision
    scans only (scans.run_scan): the continuation's own event and fold points move the branch
    after them if they move by rounding. linear_solver: the run's, for the bordered systems of
    its points and their tangents (Segment.near)."""

    problem: Problem
    x_a: Array
    x_b: Array
    tol: float
    max_iter: int
    t_a: Optional[Array] = None
    t_b: Optional[Array] = None
    polish: bool = True
    root: Optional[float] = None
    chord: bool = False
    linear_solver: LinearSolver = DIRECT
    _known: dict = field(default_factory=dict, compare=False, repr=False)
    _factors: dict = field(default_factory=dict, compare=False, repr=False)

    @cached_property
    def sigma(self) -> Array:
        """The unit direction of x_b - x_a (of p for a zero-length step: the segment is one
        point, any direction will do)."""
        d = self.x_b - self.x_a
        norm = np.linalg.norm(d)
        if norm == 0.0:
            d, norm = np.eye(d.size)[-1], 1.0
        return d / norm

    @property
    def length(self) -> float:
        """|x_b - x_a|."""
        return float(np.linalg.norm(self.x_b - self.x_a))

    def real(self, w: float) -> float:
        """s at the coordinate w: s_e (1 - (1 - w)^2), 1 at w = 1 (the end x_b stands for the
        root s_e, its spectrum the limit there); w itself without a root end."""
        if self.root is None:
            return w
        return 1.0 if w >= 1.0 else self.root * (1.0 - (1.0 - w) ** 2)

    def coordinate(self, s: float) -> float:
        """w at s (real's inverse; 1 from s_e on)."""
        if self.root is None:
            return s
        return 1.0 - float(np.sqrt(max(0.0, 1.0 - s / self.root)))

    def ds_dw(self, w: float) -> float:
        """ds / dw = 2 s_e (1 - w); 1 without a root end."""
        return 1.0 if self.root is None else 2.0 * self.root * (1.0 - w)

    def secant_point(self, s: float) -> Array:
        """(1 - s) x_a + s x_b."""
        return self.x_a + s * (self.x_b - self.x_a)

    def remember(self, w: float, x: Array, t: Optional[Array] = None) -> None:
        """Keep x(w) (and its unit tangent t, if known) for the predictions of later points."""
        self._keep(self.real(w), x, t)

    def _keep(self, s: float, x: Array, t: Optional[Array] = None) -> None:
        if 0.0 < s < 1.0:
            self._known[s] = (x, t)

    def predicted(self, w: float) -> Array:
        """x(w) predicted from the two solved points nearest it on either side (module
        docstring): the cubic Hermite interpolant in s where both carry tangents along the
        secant, else the straight line between them."""
        return self._predicted_at(self.real(w))

    def _predicted_at(self, s: float) -> Array:
        known = {0.0: (self.x_a, self.t_a), 1.0: (self.x_b, self.t_b), **self._known}
        nodes = sorted(known)
        i = bisect.bisect(nodes, s)
        (s1, (x1, t1)), (s2, (x2, t2)) = (nodes[i - 1], known[nodes[i - 1]]), (nodes[i], known[nodes[i]])
        tau, chord = (s - s1) / (s2 - s1), x2 - x1
        line = x1 + tau * chord
        if t1 is None or t2 is None:
            return line
        along = (float(self.sigma @ t1), float(self.sigma @ t2))
        if min(along) < HERMITE_ALONG:
            return line
        # dx/ds = t |x_b - x_a| / (sigma . t): sigma . x grows by |x_b - x_a| per unit s
        D = (s2 - s1) * self.length
        m1, m2 = t1 * (D / along[0]), t2 * (D / along[1])
        return line + (tau * (1.0 - tau)) * ((1.0 - tau) * (m1 - chord) - tau * (m2 - chord))

    def point(self, w: float) -> Array:
        """x(w) on the branch, remembered; the ends return their points without a solve."""
        s = self.real(w)
        if s == 0.0:
            return self.x_a.copy()
        if s == 1.0:
            return self.x_b.copy()
        if s in self._known:
            return self._known[s][0].copy()
        target, start = self.secant_point(s), self._predicted_at(s)
        res, near = None, self.near(w)
        if self.chord and near is not None:  # the chord from the factorization of the nearest point solved anew
            res = chord_newton(self.problem, target, self.sigma, self.tol, near[0], start, self.polish)
        if res is None:
            res, lu = factored_newton(self.problem, target, self.sigma, self.tol, self.max_iter, start,
                                      self.polish, self.linear_solver)
            if lu is not None:
                self._factors[s] = lu
                if len(self._factors) > CHORD_KEPT:
                    del self._factors[next(iter(self._factors))]
        if not res.converged:
            raise SegmentSolveError(f"corrector failed at s={s:.6g} ({res.failure()})")
        self._keep(s, res.x.copy())
        return res.x

    def near(self, w: float) -> Optional[tuple]:
        """(lu, sigma): the factorization kept from the Newton solve nearest x(w) and its
        border, for the tangent there (newton.tangent's near), or None where none is kept."""
        if not self._factors:
            return None
        s = self.real(w)
        return self._factors[min(self._factors, key=lambda known: abs(known - s))], self.sigma


def refine_sign_change(f: Callable[[float], Optional[float]], a: float, fa: float, b: float, fb: float,
                       done: Callable[[float, float], bool], max_eval: int = 200, tol: float = 0.0):
    """Shrink a bracket [a, b] of a sign change of f (fa * fb < 0).

    Each new point is the inverse quadratic interpolant through the bracket's ends and the end
    it last replaced, where it lies inside the bracket and the three values differ, else the
    regula falsi point; a bisection is forced when two updates did not halve the bracket
    (Brent's safeguard). With tol > 0 (the bracket width in s that done() accepts, as the caller
    estimates it) a new point keeps at least tol from either end: a converged estimate then
    closes the bracket with one evaluation beyond it instead of creeping on the root from one
    side. Stops when done(a, b), when f(s) == 0 (returns [s, s]), when f returns None (the
    caller could not evaluate, e.g. the structure changed), or after max_eval evaluations.
    Returns the final bracket (a, b).
    """
    widths = [np.inf, np.inf]
    c = fc = None  # the end replaced last
    for _ in range(max_eval):
        if done(a, b):
            break
        w = b - a
        s = _interpolated(a, fa, b, fb, c, fc)
        if w > 0.5 * widths[-2] or not (a < s < b):
            s = 0.5 * (a + b)
        if 0.0 < tol < 0.25 * w:
            s = min(max(s, a + tol), b - tol)
        widths.append(w)
        fs = f(s)
        if fs is None:
            break
        if fs == 0.0:
            return s, s
        if np.sign(fs) == np.sign(fb):
            c, fc, b, fb = b, fb, s, fs
        else:
            c, fc, a, fa = a, fa, s, fs
    return a, b


def _interpolated(a: float, fa: float, b: float, fb: float, c: Optional[float],
                  fc: Optional[float]) -> float:
    """The root of the inverse quadratic through (a, fa), (b, fb), (c, fc) where the three
    values differ, else of the line through the bracket's ends (regula falsi)."""
    if c is not None and fc != fa and fc != fb:
        return (a * fb * fc / ((fa - fb) * (fa - fc)) + b * fa * fc / ((fb - fa) * (fb - fc))
                + c * fa * fb / ((fc - fa) * (fc - fb)))
    return (a * fb - b * fa) / (fb - fa)
