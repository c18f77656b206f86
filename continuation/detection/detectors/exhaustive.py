"""The exhaustive detection (version 0.1's, kept to check the fast one: tests/continuation/detection/test_detection.py):
samples without slopes; intervals certified by the three-sample quadratic of every pair's
discriminant and the motion of every real eigenvalue against its gap (certify.curvature_too_large,
certify.outruns_gaps), the third sample the nearest beyond the interval with the status of the
adjacent end (at a step's start, possibly a sample of the previous step); splits at midpoints;
events located by segment.refine_sign_change on D, every evaluation a new sample with its full
spectrum. Eigenvalues are not smooth at a collision, so the stencil never reaches across one."""
from __future__ import annotations

from typing import Optional

import numpy as np

from diskfriction.continuation.detection.samples import Sample
from diskfriction.continuation.stepping.segment import Segment, refine_sign_change
from diskfriction.continuation.detection.verdicts import Verdict, judge_exhaustive
from diskfriction.continuation.detection.detectors.base import Detector, Kind, sample_discriminant


class Exhaustive(Detector):
    """The exhaustive detection (module docstring)."""

    name = "exhaustive"
    stencil_from_previous = True

    def stencil(self, scan, idx: int) -> Optional[Sample]:
        """The nearest sample beyond [a, b] with the status of the adjacent end."""
        S = scan.samples
        a, b = S[idx], S[idx + 1]
        left = S[idx - 1] if idx >= 1 and np.array_equal(S[idx - 1].status, a.status) else None
        right = S[idx + 2] if idx + 2 < len(S) and np.array_equal(S[idx + 2].status, b.status) else None
        if left is None or right is None:
            return left or right
        return left if a.s - left.s <= right.s - b.s else right

    def judge(self, a: Sample, b: Sample, stencil: Optional[Sample], segment: Segment, params) -> Verdict:
        return judge_exhaustive(a, b, stencil, params.rho)

    def resolve(self, scan, idx: int, verdict: Verdict) -> bool:
        """Refine the first event whose bracket is not final (bisection if that made no sample)."""
        a, b = scan.samples[idx], scan.samples[idx + 1]
        for i, j, kind in verdict.events:
            if not self.final(scan, a, b, i, j, kind):
                n = len(scan.samples)
                refine(scan, idx, i, j)
                if len(scan.samples) == n:  # no progress: fall back to bisection
                    scan.insert(0.5 * (a.s + b.s))
                return True
        return False

    def final(self, scan, a: Sample, b: Sample, i: int, j: int, kind: Kind) -> bool:
        """The event's bracket is |dp| <= tol_p, or its real side is already a double eigenvalue."""
        real_side = kind.real_side(a, b)
        return scan.narrow(a, b) or sample_discriminant(real_side, i, j) <= 4.0 * real_side.thr ** 2


def refine(scan, idx: int, i: int, j: int) -> None:
    """refine_sign_change on s -> D_ij(x(s)) over scan.samples[idx], scan.samples[idx + 1]; every
    evaluation stays as a sample. Aborts when the pair loses its labels or eligibility."""
    a, b = scan.samples[idx], scan.samples[idx + 1]
    at = {a.s: a, b.s: b}

    def f(s: float):
        k, perm = scan.insert(s)
        if perm is not None and set(perm[[i, j]].tolist()) != {i, j}:
            return None
        at[s] = scan.samples[k]
        d = sample_discriminant(at[s], i, j)
        return None if np.isnan(d) else d

    refine_sign_change(f, a.s, sample_discriminant(a, i, j), b.s, sample_discriminant(b, i, j),
                       lambda lo, hi: scan.narrow(at[lo], at[hi]))
