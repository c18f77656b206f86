"""The fast detection (the default): samples carry eigenvalue slopes from left and right
eigenvectors; intervals are certified by cubic Hermite models of every pair's discriminant
(certify.worst_uncertified_pair) and the labels by their slopes (certify.inconsistent_labels);
an uncertified interval gets a new sample where the worst pair's model is lowest, partial
(only the eigenvalues near the labels in trouble, partial_splits.py) from n = partial_from on;
events are located by Newton's method on the minimally augmented system (locate.py): linear
solves, no eigensolver. One full spectrum per accepted point."""
from __future__ import annotations

from typing import Optional

import numpy as np

from diskfriction.continuation.detection import certify
from diskfriction.continuation.detection.locate import LocatorFailed, locate_double_eigenvalue
from diskfriction.continuation.detection.labels import known
from diskfriction.continuation.detection.samples import Sample
from diskfriction.continuation.stepping.segment import Segment
from diskfriction.continuation.detection.verdicts import Verdict, event_model, events_in_trouble, judge_fast, scaled_slopes
from diskfriction.continuation.detection.detectors.base import Collision, Detector, Kind


class Fast(Detector):
    """The fast detection (module docstring)."""

    name = "fast"
    slopes = True
    partial_splits = True
    parallel = True
    window = True

    def judge(self, a: Sample, b: Sample, stencil: Optional[Sample], segment: Segment, params) -> Verdict:
        return judge_fast(a, b, segment, params.rho, params.doubt)

    def resolve(self, scan, idx: int, verdict: Verdict) -> bool:
        """Locate the first event of the interval not yet located; where the locator fails,
        split the interval instead (fallback_split), with a partial sample of the events'
        labels and their partners where partial samples are allowed (a full spectrum costs
        O(n^2) to O(n^3), such a sample a few sparse shift-inverts, O(n))."""
        a, b = scan.samples[idx], scan.samples[idx + 1]
        for i, j, kind in verdict.events:
            key = (a.uid, b.uid, i, j)
            if key in scan.located:
                continue
            found = locate(scan, idx, i, j, kind)
            if found is None:
                scan.split(idx, fallback_split(scan, a, b), events_in_trouble(a, b, verdict.events))
            else:
                scan.located[key] = found
            return True
        return False

    def done(self, scan, idx: int, verdict: Verdict) -> bool:
        """Every event of the interval is located."""
        a, b = scan.samples[idx], scan.samples[idx + 1]
        return all((a.uid, b.uid, i, j) in scan.located for i, j, _ in verdict.events)

    def final(self, scan, a: Sample, b: Sample, i: int, j: int, kind: Kind) -> bool:
        return scan.narrow(a, b)

    def settle(self, scan) -> None:
        scan.release_vectors()


def locate(scan, idx: int, i: int, j: int, kind: Kind) -> Optional[Collision]:
    """Newton on the minimally augmented system over scan.samples[idx], scan.samples[idx + 1],
    from the branch point the segment predicts (Segment.predicted, from the solved points
    nearest it) at the cubic model's root; None if it fails or lands outside the interval. (From
    the secant point of the whole step, off the branch, 256 sheared disks saw a spectrum that
    was not the interval's, and Newton converged 13 times on a neighbouring birth 4.1e-7 away.)"""
    a, b = scan.samples[idx], scan.samples[idx + 1]
    segment, params = scan.segment, scan.params
    slopes = scaled_slopes(a, b, segment)
    mean, D = event_model(a, b, i, j, *slopes)
    roots = certify.cubic_roots_in_unit(D)
    t0 = roots[0] if roots else 0.5
    right, left = kind.real_side(a, b).system.vectors(i)
    x0 = segment.predicted(a.s + t0 * (b.s - a.s))
    try:
        found = locate_double_eigenvalue(
            scan.problem, x0, float(certify.cubic_at(mean, t0)), right, left.conj(),
            segment.sigma, params.tol_p, segment.tol, params.locator_iterations, segment.linear_solver)
    except LocatorFailed as err:
        scan.warnings.append(f"step {scan.step}: locator: {err}; splitting")
        return None
    s = segment.coordinate(float(segment.sigma @ (found.x - segment.x_a)) / segment.length)
    lo, hi = min(a.p, b.p), max(a.p, b.p)
    p = float(found.x[-1])
    if not (a.s - 1e-9 <= s <= b.s + 1e-9 and lo - params.tol_p <= p <= hi + params.tol_p):
        return None
    t = (s - a.s) / (b.s - a.s)
    if not belongs_to_pair(a, b, i, j, found.lam, float(certify.cubic_at(mean, t)), t, *slopes):
        scan.warnings.append(f"step {scan.step}: locator: the double eigenvalue {found.lam:.6g} found at "
                             f"p = {p:.12g} is another pair's; splitting")
        return None
    return Collision(p=p, kind=kind, eigenvalue=found.lam, eigenvector=found.v,
                     generalized_eigenvector=found.w, left_right_overlap=found.overlap,
                     bracket=(p - found.dp, p + found.dp), residual=found.residual,
                     u=found.x[:-1].copy(), step=scan.step, pair=(i, j))


def belongs_to_pair(a: Sample, b: Sample, i: int, j: int, lam: float, mean: float, t: float,
                    d_a: np.ndarray, d_b: np.ndarray) -> bool:
    """Whether the double eigenvalue lam, located at t in [0, 1] of the interval, is the
    collision of labels i and j: nearer their mean's cubic model there (mean) than the cubic
    model of any other label tracked at both ends (Hermite in t, from the samples' values and
    their slopes per unit t, d_a and d_b: verdicts.scaled_slopes). A locator started from one pair's model may converge on a neighbouring pair's
    collision in the same interval (256 disks: a birth at lambda = 4.70 located on a death at
    4.50, 2.4e-9 away in strain); that pair's own event is located separately."""
    others = known(a) & known(b) & ~a.excluded & ~b.excluded
    others[[i, j]] = False
    if not others.any():
        return True
    k = np.flatnonzero(others)
    model = certify.cubic_at(certify.hermite_coefficients(a.eigvals[k], b.eigvals[k], d_a[k], d_b[k]), t)
    return abs(lam - mean) < float(np.min(np.abs(lam - model)))


def fallback_split(scan, a: Sample, b: Sample) -> float:
    """Where to sample when the locator failed: the midpoint, except in the last interval of a
    step ending on a contact event, where the spectrum is not smooth (a Hertz stiffness
    ~ delta^(1/2) has an infinite slope at delta = 0), collisions crowd towards the event and
    Newton cannot converge on one sitting at it: there a sample tol_p / 2 before the end
    isolates it (collision at the event within tol_p)."""
    tol_p = scan.params.tol_p
    if scan.ends_at_event and b.s == 1.0 and abs(b.p - a.p) > tol_p:
        return b.s - 0.5 * tol_p / abs(b.p - a.p) * (b.s - a.s)
    return 0.5 * (a.s + b.s)
