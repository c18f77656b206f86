"""What a collision detection is made of: the located Collision, its Kind, and the Detector
interface that StepScan (collisions.py) drives.

A detector is one method of finding and locating the collisions of a step: what its samples
carry (slopes), the verdict it gives an interval, and what it does with an interval that holds
events. StepScan owns the samples (their store and their labels); a detector only reads them
and asks the scan for new ones (StepScan.insert, StepScan.split). The detectors are listed in
DETECTORS (detectors/__init__.py) by name, the `mode` of DetectionParams and the value of
`bifurcate --detection`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np

from diskfriction.continuation.detection.samples import Sample
from diskfriction.continuation.stepping.segment import Segment
from diskfriction.continuation.spectra.tracking import Kind, pair_discriminant
from diskfriction.continuation.detection.verdicts import Verdict

Array = np.ndarray


@dataclass(frozen=True)
class Collision:
    """A located eigenvalue collision.

    p: location; kind: Kind.BIRTH (real pair -> complex pair along the branch direction) or
    Kind.DEATH; eigenvalue: the (real) double eigenvalue; eigenvector v (unit, right null vector
    of A - eigenvalue I), generalized_eigenvector w ((A - eigenvalue I) w = v, w orthogonal to
    v: the Jordan chain), left_right_overlap |y . v| for the unit left null vector y (-> 0 at a
    Jordan block, ~1 at a semisimple double eigenvalue); bracket (p_lo, p_hi): p is within it
    (fast: p +- the last Newton correction; exhaustive: the final bracket across which the
    status changes); residual max|G| at the located point u; step: index of the accepted point
    that starts the step; pair: tracked eigenvalue indices; resolved: False if the step's
    detection budget ran out or the bracket could not be isolated.
    """

    p: float
    kind: Kind
    eigenvalue: float
    eigenvector: Array
    generalized_eigenvector: Array
    left_right_overlap: float
    bracket: tuple[float, float]
    residual: float
    u: Array
    step: int
    pair: tuple[int, int]
    resolved: bool = True


def sample_discriminant(sample: Sample, i: int, j: int) -> float:
    """D_ij at a sample (tracking.pair_discriminant); nan if i, j cannot collide there."""
    ev, st = sample.eigvals, sample.status
    return float(pair_discriminant(ev[i], ev[j], st[i], st[j]))


class Detector:
    """One detection method (module docstring). Class attributes:
    name: its key in DETECTORS; slopes: its samples carry eigenvalue slopes (and so each sample
    point its unit tangent); partial_splits: a split may be a partial sample (partial_splits.py;
    needs slopes); stencil_from_previous: it judges an interval with a third sample, which at a
    step's start may be a sample of the previous step, so its scans run in order, inline;
    parallel: the scans of different steps are independent and may run on workers (scans.py);
    window: it can follow a spectral window (spectra/window.py; needs slopes).
    Methods act on a StepScan `scan` (collisions.py) and its samples."""

    name: str = ""
    slopes: bool = False
    partial_splits: bool = False
    stencil_from_previous: bool = False
    parallel: bool = False
    window: bool = False

    def stencil(self, scan, idx: int) -> Optional[Sample]:
        """The third sample the verdict on [samples[idx], samples[idx + 1]] uses (None: none)."""
        return None

    def judge(self, a: Sample, b: Sample, stencil: Optional[Sample], segment: Segment, params) -> Verdict:
        """The verdict on [a, b] (verdicts.py) under the tolerances `params` (DetectionParams)."""
        raise NotImplementedError

    def resolve(self, scan, idx: int, verdict: Verdict) -> bool:
        """One action on the interval samples[idx], samples[idx + 1] whose verdict holds events
        (locate one, or sample inside it); False if all of them are already final."""
        raise NotImplementedError

    def done(self, scan, idx: int, verdict: Verdict) -> bool:
        """Whether resolve has nothing left to do on the interval samples[idx], samples[idx + 1]
        whose verdict holds events, without acting (default: not known, False)."""
        return False

    def final(self, scan, a: Sample, b: Sample, i: int, j: int, kind: Kind) -> bool:
        """Whether the event (i, j, kind) of [a, b], not located by resolve, is bracketed
        finely enough to be reported as resolved (by interpolation: StepScan.interpolated)."""
        raise NotImplementedError

    def settle(self, scan) -> None:
        """After each action of the scan: release what no later action needs (default nothing)."""
