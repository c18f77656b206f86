"""Points of the branch between two accepted points, and bracket refinement on them.

Between converged points x_a and x_b the branch is parametrised by s in [0, 1]: the point
x(s) solves
    G(u, p) = 0,    sigma . (x - ((1 - s) x_a + s x_b)) = 0,    sigma = (x_b - x_a) / |x_b - x_a|,
i.e. the branch cut by the hyperplane normal to the secant through the secant point at s.
x(0) = x_a and x(1) = x_b; s is monotone along the arc as long as the tangent turns by less
than 90 degrees over the step (the step angle check keeps it far below). Unlike a fixed-p
corrector this works through folds. Between accepted points the problem must be in the
state committed at x_a (events are located before the step is committed).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable, Optional

import numpy as np

from .newton import bordered_newton
from .problem import Problem

Array = np.ndarray


class SegmentSolveError(RuntimeError):
    """The corrector failed at an intermediate point of a step."""


@dataclass(frozen=True)
class Segment:
    """The branch between x_a (s = 0) and x_b (s = 1); see the module docstring."""

    problem: Problem
    x_a: Array
    x_b: Array
    tol: float
    max_iter: int

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

    def secant_point(self, s: float) -> Array:
        """(1 - s) x_a + s x_b."""
        return self.x_a + s * (self.x_b - self.x_a)

    def point(self, s: float) -> Array:
        """x(s) on the branch; s = 0 and 1 return the end points without a solve."""
        if s == 0.0:
            return self.x_a.copy()
        if s == 1.0:
            return self.x_b.copy()
        res = bordered_newton(self.problem, self.secant_point(s), self.sigma, self.tol, self.max_iter)
        if not res.converged:
            raise SegmentSolveError(f"corrector failed at s={s:.6g} ({res.failure()})")
        return res.x


def refine_sign_change(f: Callable[[float], Optional[float]], a: float, fa: float, b: float, fb: float,
                       done: Callable[[float, float], bool], max_eval: int = 200):
    """Shrink a bracket [a, b] of a sign change of f (fa * fb < 0) by the Illinois method.

    Illinois = regula falsi s = (a fb - b fa) / (fb - fa), where the end value kept twice in
    a row is halved, so both ends converge (order ~1.44); a bisection step is forced when two
    updates did not halve the bracket. Stops when done(a, b), when f(s) == 0 (returns
    [s, s]), when f returns None (the caller could not evaluate, e.g. the structure changed),
    or after max_eval evaluations. Returns the final bracket (a, b).
    """
    side = 0
    widths = [np.inf, np.inf]
    for _ in range(max_eval):
        if done(a, b):
            break
        w = b - a
        s = (a * fb - b * fa) / (fb - fa)
        if w > 0.5 * widths[-2] or not (a < s < b):
            s = 0.5 * (a + b)
        widths.append(w)
        fs = f(s)
        if fs is None:
            break
        if fs == 0.0:
            return s, s
        if np.sign(fs) == np.sign(fb):
            b, fb = s, fs
            if side == -1:
                fa *= 0.5
            side = -1
        else:
            a, fa = s, fs
            if side == +1:
                fb *= 0.5
            side = +1
    return a, b
