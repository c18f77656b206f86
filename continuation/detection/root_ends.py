"""Steps that end where a contact opens or closes: the square-root ends of a collision scan.

A Hertz contact's stiffness goes as delta^(1/2) (dF_n / d delta = 3/2 k_n delta^(1/2), and
Mindlin's k_t delta^(1/2)), so where a step ends on the event delta = 0 of a contact
(Problem.root_events), the stability matrix goes as A_0 + (s_e - s)^(1/2) A_1 + O(s_e - s)
near the event's place s_e, and the eigenvalues with it: their slopes along the branch
diverge there, and no cubic Hermite model in s follows them (a scan splits such a step over
and over).

- Opening (g > 0 along the step, just below 0 at its end x_b): the scan addresses the step
  by w, s = s_e (1 - (1 - w)^2) (Segment.root), in which (s_e - s)^(1/2) = s_e^(1/2) (1 - w)
  is smooth, and the end sample's slopes are d lambda / dw there (root_slopes).
- Closing (g < 0 along the step, the contact forms at its end): the spectrum is smooth along
  the step, but the end sample lies just past the event, where the new contact's stiffness
  already goes as delta^(1/2): its slopes, one-sided into the step, straddle the event (3e3
  to 8e4 times those at the step's start in three steps of 256 disks). They are taken on the step's side of it instead
  (open_side).

s_e comes from the event function's value and slope at x_b (root_place): the event is located
to |dp| <= event_tol, so x_b lies about 1e-8 of the step past it, and the square root's centre
is placed there rather than at x_b (a model centred at x_b would be off by |d lambda / dw|
(1 - s_e)^(1/2) near the end).
"""
from __future__ import annotations

from dataclasses import replace
import numpy as np

from diskfriction.continuation.problem import Problem
from diskfriction.continuation.detection.samples import Sample, matrix_derivative
from diskfriction.continuation.stepping.segment import Segment
from diskfriction.continuation.spectra.tracking import eigenvalue_slopes

Array = np.ndarray

ROOT_STEP = 1e-2
"""h of the one-sided second-order difference in v = 1 - w of a root end's slopes
(root_slopes): its points lie h^2 and 4 h^2 of the step before the event. A(v) = A_0 + v A_1 +
v^2 A_2 + v^3 A_3 ..., and the difference is exact up to v^2 (the smooth part of A is of order
v^2), so its error is about h^2 |A_3| / |A_1|, 1e-4 relative for a contact whose overlap
varies on the scale of the step."""
PLACE_STEP = 1e-4
"""Step in s of the event function's backward difference at x_b (root_place)."""


def scan_ends(problem: Problem, segment: Segment, end: Sample) -> tuple[Segment, Sample]:
    """The segment and end sample a scan of a step ending on an event works on: as they are,
    or for a step ending where a contact opens, the segment addressed by w (Segment.root) and
    the end's slopes d lambda / dw (root_slopes); where one forms, the end's slopes from the
    step's side of the event (open_side). The end sample needs its vectors and tangent."""
    roots = problem.root_events()
    if roots is None or end.system is None or end.tangent is None:
        return segment, end
    x_a, x_b = segment.x_a, segment.x_b
    g_a, g_b = problem.event_functions(x_a[:-1], x_a[-1]), problem.event_functions(x_b[:-1], x_b[-1])
    opening = roots & (g_a > 0.0) & (g_b <= 0.0)
    closing = roots & (g_a < 0.0) & (g_b > 0.0)
    if not (opening.any() or closing.any()):
        return segment, end
    dx_ds = end.tangent * (segment.length / float(segment.sigma @ end.tangent))
    s_e = root_place(problem, x_b, dx_ds, g_b, opening if opening.any() else closing)
    if opening.any():
        rooted = replace(segment, root=s_e)
        return rooted, root_slopes(problem, rooted, end, dx_ds)
    return segment, open_side(problem, end, x_b - 2.0 * (1.0 - s_e) * dx_ds)


def root_place(problem: Problem, x_b: Array, dx_ds: Array, g_b: Array, crossed: Array) -> float:
    """s_e, the place of the first root event among `crossed` (x_b at s = 1 lies just past it):
    1 - g(x_b) / (dg/ds), dg/ds by a backward difference of PLACE_STEP along dx_ds; 1 where
    that slope does not point to a zero behind x_b."""
    back = x_b - PLACE_STEP * dx_ds
    g_back = problem.event_functions(back[:-1], back[-1])
    c = np.flatnonzero(crossed)
    slope = (g_b[c] - g_back[c]) / PLACE_STEP
    with np.errstate(divide="ignore", invalid="ignore"):
        before = np.where(g_b[c] * slope > 0.0, g_b[c] / slope, 0.0)
    return 1.0 - float(min(np.max(before), 0.5))


def root_slopes(problem: Problem, segment: Segment, end: Sample, dx_ds: Array) -> Sample:
    """The end sample of a segment with a root end, its slopes d lambda / dw at w = 1 (s_e):
    dA/dw = -dA/dv, v = 1 - w, by (-3 A(0) + 4 A(h) - A(2 h)) / 2h with h = ROOT_STEP, A(v) at
    x_e - s_e v^2 dx/ds on the tangent line (x_e = x_b - (1 - s_e) dx/ds, the event's place)."""
    s_e = segment.root
    x_e = end.x - (1.0 - s_e) * dx_ds
    def A(v: float):
        y = x_e - s_e * v * v * dx_ds
        return problem.stability_matrix(y[:-1], y[-1])

    h = ROOT_STEP
    dA = (A(0.0) * 3.0 - A(h) * 4.0 + A(2.0 * h)) * (0.5 / h)
    return replace(end, dlam=eigenvalue_slopes(end.system, dA), dA=dA, root_end=True, uid=object())


def open_side(problem: Problem, end: Sample, x_c: Array) -> Sample:
    """The end sample with its slopes, one-sided into the step, taken at x_c, on the step's
    side of the event that x_b lies just past."""
    dA = matrix_derivative(problem, x_c, end.tangent, -1)
    return end.moved(end.x, end.tangent, eigenvalue_slopes(end.system, dA), dA)
