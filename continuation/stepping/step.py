"""One step of pseudo-arclength continuation and where it ends (arclength.py runs the steps).

From a converged point x_k = (u_k, p_k) with unit tangent t_k:
  predictor  x_pred = x_k + ds t_k
  corrector  Newton on  [G(u, p); t_k . (x - x_pred)] = 0          (newton.bordered_newton)
  tangent    [[G_u, G_p], [t_k^T]] t = e_(n+1),  t_(k+1) = t / |t|  (t_k . t_(k+1) > 0: folds pass)
(attempt; a step whose corrector fails, or whose tangent turns by more than max_angle, is
rejected: StepRejected). A step that lands beyond an end of [p_min, p_max] is re-solved at the
end value. Events (problem.event_functions): if a component changes sign over the step, the
step is cut at the first such change, located on the branch (the step's segment) by
segment.refine_sign_change to |dp| <= event_tol max(1, |p|), and ends on the far side of it
(cut_at_event). A step that passed a fold in p (runs_back) is cut just before it where
stop_at_fold asks (before_fold). Every bordered system is solved by the run's linear solver
(ContinuationParams.linear_solver).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from diskfriction.continuation.linalg.solves import SingularMatrix
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.stepping.newton import NewtonResult, factored_newton, fixed_p_newton, residual_norm, tangent
from diskfriction.continuation.stepping.segment import Segment, SegmentSolveError, refine_sign_change

if TYPE_CHECKING:  # pragma: no cover
    from diskfriction.continuation.stepping.arclength import ContinuationParams

Array = np.ndarray


class StepRejected(Exception):
    """A step that cannot be accepted (str: why, as words); its arclength is halved."""


@dataclass(frozen=True)
class Step:
    """An accepted-to-be step: new point, its tangent, corrector work, whether it ends the run,
    whether it ends on an event, whether it ends at a fold in p (with stop_at_fold: before_fold,
    the run stops there)."""

    x: Array
    tangent: Array
    newton: NewtonResult
    last: bool
    event: bool = False
    fold: bool = False


def crossed(g0: Array, g1: Array) -> Array:
    """Event components that change sign from g0 to g1 (g0 = 0 never; g1 = 0 counts as leaving
    g > 0)."""
    return ((g0 > 0) & (g1 <= 0)) | ((g0 < 0) & (g1 > 0))


def cut_at_event(problem: Problem, x: Array, t: Array, step: Step, g0: Array, par: ContinuationParams):
    """The step from x (unit tangent t) ended on the far side of its first event (located on the
    branch), or the step itself if no event function changes sign over it. Raises
    SegmentSolveError."""
    g1 = problem.event_functions(step.x[:-1], step.x[-1])
    if not crossed(g0, g1).any():
        return step
    seg = Segment(problem, x, step.x, par.newton_tol, par.max_newton, t, step.tangent,
                  linear_solver=par.linear_solver)
    hi, x_hi = 1.0, step.x
    while True:  # locate the first crossing in [0, hi]; one found crossed on the near side wins
        mask = crossed(g0, g1)
        frac = np.full(g0.shape, np.inf)
        frac[mask] = g0[mask] / (g0[mask] - g1[mask])
        c = int(np.argmin(frac))
        pts = {0.0: x, hi: x_hi}

        def f(s: float) -> float:
            pts[s] = seg.point(s)
            return float(problem.event_functions(pts[s][:-1], pts[s][-1])[c])

        def done(lo: float, up: float) -> bool:
            p = abs(pts[up][-1])
            return abs(pts[up][-1] - pts[lo][-1]) <= par.event_tol * max(1.0, p) or up - lo <= 1e-14

        lo, up = refine_sign_change(f, 0.0, g0[c], hi, g1[c], done, tol=_width_in_s(x, x_hi, hi, par))
        g_lo = problem.event_functions(pts[lo][:-1], pts[lo][-1]) if lo > 0.0 else g0
        if not crossed(g0, g_lo).any():  # nothing before lo: events within [lo, up] coincide
            x_e = pts[up]
            break
        hi, x_hi, g1 = lo, pts[lo], g_lo
    t_e = tangent(problem, x_e, step.tangent, seg.near(up), par.linear_solver)
    return Step(x_e, t_e, replace(step.newton, x=x_e, residual=residual_norm(problem, x_e)),
                 False, True)


def _width_in_s(x: Array, x_hi: Array, hi: float, par: ContinuationParams) -> float:
    """Half the bracket width in s that the event's done() accepts, |dp| <= event_tol max(1,
    |p|), where p is linear in s between x (s = 0) and x_hi (s = hi); 0 (no estimate) where p
    does not change."""
    dp = abs(float(x_hi[-1] - x[-1]))
    return 0.5 * par.event_tol * max(1.0, abs(float(x[-1]))) * hi / dp if dp > 0.0 else 0.0


def _angle(t0: Array, t1: Array) -> float:
    return math.acos(min(1.0, max(-1.0, float(t0 @ t1))))


def attempt(problem: Problem, x: Array, t: Array, ds: float, par: ContinuationParams) -> Step:
    """One predictor-corrector step of length ds; raises StepRejected."""
    res, lu = factored_newton(problem, x + ds * t, t, par.newton_tol, par.max_newton,
                              linear_solver=par.linear_solver)
    if not res.converged:
        raise StepRejected(f"corrector failed ({res.failure()})")
    x_new, last = res.x, False
    try:
        t_new = tangent(problem, x_new, t, None if lu is None else (lu, t), par.linear_solver)
        if _angle(t, t_new) > par.max_angle:
            raise StepRejected(f"tangent turned by {_angle(t, t_new):.3g} rad")
        p_new = x_new[-1]
        if not par.p_min < p_new < par.p_max:  # landing exactly on an end also ends the run
            p_end = par.p_max if p_new >= par.p_max else par.p_min
            guess = x + (p_end - x[-1]) / (p_new - x[-1]) * (x_new - x)
            res = fixed_p_newton(problem, guess[:-1], p_end, par.newton_tol, par.max_newton, par.linear_solver)
            if not res.converged:
                raise StepRejected("landing on the end value failed")
            x_new, last = res.x, True
            t_new = tangent(problem, x_new, t, linear_solver=par.linear_solver)
    except np.linalg.LinAlgError:
        raise StepRejected("singular bordered matrix") from None
    return Step(x_new, t_new, res, last)


def runs_back(here, step: Step, params: ContinuationParams) -> bool:
    """Whether p at the end of the step from `here` (its point x and unit tangent t), or its
    tangent there, points back against the run's
    direction: the step passed a fold in p."""
    return min(params.direction * (step.x[-1] - here.x[-1]), params.direction * step.tangent[-1]) < 0


def before_fold(problem: Problem, here, step: Step, params: ContinuationParams):
    """The step from `here` (its point x and unit tangent t) cut just before the fold in p that it passed: the fold is the sign
    change of direction * t_p(s), the p-component of the unit tangent along the step's segment
    (oriented by here's tangent), bracketed by segment.refine_sign_change to ds_min of
    arclength; the step ends at the bracket's near end, on the branch, where p still runs
    forward. None where the tangents at the step's ends do not point forward and back (the step
    went round two folds), where the step lands on the end of the span, or where a point of the
    segment cannot be solved: the caller then halves the step (arclength._towards_fold). The bracket
    takes a few points, without spectra, where closing in by halving takes tens of steps."""
    direction = params.direction
    start, end = direction * float(here.t[-1]), direction * float(step.tangent[-1])
    if step.last or not start > 0.0 > end:  # step.tangent is oriented by here.t, as below
        return None
    seg = Segment(problem, here.x, step.x, params.newton_tol, params.max_newton, here.t, step.tangent,
                  linear_solver=params.linear_solver)
    tangents = {0.0: here.t}

    def f(s: float) -> float:
        tangents[s] = tangent(problem, seg.point(s), here.t, seg.near(s), params.linear_solver)
        return direction * float(tangents[s][-1])

    try:
        lo, _ = refine_sign_change(f, 0.0, start, 1.0, end,
                                   lambda a, b: (b - a) * seg.length <= params.ds_min)
        if lo == 0.0:
            return None
        x = seg.point(lo)
    except (SegmentSolveError, SingularMatrix):
        return None
    return Step(x, tangents[lo], replace(step.newton, x=x, residual=residual_norm(problem, x)),
                 False, False, True)
