"""Eigenvalue collisions along a branch: births and deaths of complex-conjugate pairs.

A *birth* is a point where two real eigenvalues of the stability matrix A meet and leave the
real axis as a conjugate pair (as the branch is followed in its direction); a *death* is the
reverse. Integer test function: the status of every tracked eigenvalue (0 real, +1 / -1 upper /
lower member of a complex pair, tracking.eigen_status); the number of complex pairs is the count
of +1. Smooth test function of one pair (i, j): its discriminant D_ij = (lambda_i - lambda_j)^2
(tracking.pair_discriminant), > 0 for two real eigenvalues, < 0 for a conjugate pair.

Detection on one step x_a -> x_b (before the step is committed) works on samples (samples.py):
branch points x(s), s in [0, 1], on the step's secant segment (segment.py), with tracked spectra.
Three parts, each a module testable alone, and this module's StepScan, which acts on them:
  * the sampler (samples.py): corrector solve at s (segment.py), eigensystem, labels; a split
    sample is partial where partial_splits.py allows it (only the labels in trouble);
  * the certifier (verdicts.py, over certify.py's models): the verdict on an interval between
    neighbouring samples: events (births and deaths to locate), split (where to sample next,
    and which labels are in trouble) or clean;
  * the locator (locate.py): the collision of an event pair inside its interval.
The detections that combine them are Detector classes (detectors/), looked up by name in
DETECTORS (DetectionParams.mode): "fast" (the default; detectors/fast.py: slopes, Hermite
certification, Newton locator, partial split samples) and "exhaustive" (version 0.1's, kept to
check the fast one; detectors/exhaustive.py). StepScan keeps the step's samples and their labels
and drives the detector: it asks for the verdict on each interval and acts on it (a split: a new
sample, partial where the detector and partial_splits.py allow; events: the detector's resolve).
Refinement ends when every interval is clean or holds only located events (or is narrower than
tol_p, or the step's budget of max_solves samples is spent: remaining events are reported with
resolved=False and a warning).

Guarantee (what "no misses" means). On return every sub-interval of the step is either a
located event's interval or certified: for every pair that could collide (two real eigenvalues,
or a conjugate pair), the model of y = D (or Im^2) through the sample data stays above rho times
its smaller end value with margin (certify.py). A collision in a certified interval needs y to
reach 0, i.e. y would have to vary on a scale shorter than the sample spacing in a way neither
its end values nor its end slopes show. Limits: (a) two collisions closer than tol_p are
invisible; (b) structure finer than the samples that the data do not show can be missed:
shorten the steps (ds_max) if the spectrum varies faster than the branch; (c) eigenvalues are
not smooth at a collision, so the exhaustive stencil never reaches across one (a
previous-step sample is used only if that step had none).
"""
from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from diskfriction.continuation.detection.detectors import DETECTORS, Collision, Detector, Kind, sample_discriminant
from diskfriction.continuation.detection.locate import jordan_chain_near
from diskfriction.continuation.stepping.newton import residual_norm, tangent
from diskfriction.continuation.detection.partial_splits import certificates_survive, clusters, most_clusters, partial_allowed
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.detection.root_ends import scan_ends
from diskfriction.continuation.detection.labels import claimed_outside, continuation_perm, known
from diskfriction.continuation.detection.samples import Sample, partial_sample_at, sample_at
from diskfriction.continuation.stepping.segment import Segment, SegmentSolveError
from diskfriction.continuation.spectra.eigensolvers import DEFAULT, Eigensolver
from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL
from diskfriction.continuation.detection.verdicts import Verdict, VerdictKind, band_side, scaled_slopes

Array = np.ndarray

__all__ = ["Collision", "DetectionParams", "Kind", "ScanResult", "StepScan", "scan_step"]


class BranchJump(SegmentSolveError):
    """The corrector of a step converged on two pieces of the branch on either side of an
    interval of s (known from the samples' tangents, StepScan.jumped, or at the latest when the
    interval is min_ds wide): the branch between the step's ends is not one curve across the
    step's hyperplanes (it turns back in p and forth again, S-shaped), so the step passed over
    folds. Its scan fails, and the continuation tries the step shorter (scans.run_scan), as
    for a corrector that fails (a scan that went on bisecting would report the collisions of
    both pieces as located in an interval of s too narrow to hold them)."""


JUMP_RATIO = 1e3
"""An interval whose ends lie this many times farther apart than their tangents carry the
branch across it is a jump (StepScan.jumped), known before it is bisected down to min_ds
(hundreds of samples)."""


@dataclass(frozen=True)
class DetectionParams:
    """mode: a name in DETECTORS, "fast" or "exhaustive" (module docstring); rel_tol: status threshold
    |Im| > rel_tol * max|lambda| (tracking.py); tol_p: |dp| to which a collision is located (the
    fast locator's last Newton correction, or the exhaustive bracket); rho: certification margin
    (0 < rho < 1, certify.py); max_solves: samples allowed per step; enabled: False skips
    detection (spectra are still computed, tracked and counted, unless spectra is False: then
    no eigenvalue is computed at all, for a caller that needs only the equilibria, e.g.
    models.chain.equilibrium); min_ds: the narrowest interval in s (the segment coordinate's
    resolution, 100 ulp of 1): one that is still not narrow in p and x is a BranchJump;
    locator_iterations: Newton iterations of the fast locator before it falls back to a split;
    partial_from: matrix size n from which a split sample of the fast detection is partial
    (only the eigenvalues near the labels in trouble, nearest.py; 0: always, a value above n:
    never); partial_max_k: the most eigenvalues a partial sample computes (beyond that, or
    when they do not cover the labels, the sample is a full spectrum). Where the scans run
    (inline or on workers) is not a tolerance: continuation(workers=...), scans.py."""

    mode: str = "fast"
    rel_tol: float = DEFAULT_REL_TOL
    tol_p: float = 1e-10
    rho: float = 0.5
    max_solves: int = 500
    enabled: bool = True
    spectra: bool = True
    min_ds: float = 1e-14
    locator_iterations: int = 12
    doubt: float = 0.25
    partial_from: int = 240
    partial_max_k: int = 16

    def __post_init__(self):
        if self.mode not in DETECTORS:
            raise ValueError(f"mode must be one of {tuple(DETECTORS)}, got {self.mode!r}")
        if self.enabled and not self.spectra:
            raise ValueError("collision detection needs the spectra (spectra=False needs enabled=False)")
        if not 0.0 < self.rel_tol < 1e-3:
            raise ValueError(f"rel_tol must be in (0, 1e-3), got {self.rel_tol}")
        if not self.tol_p > 0.0:
            raise ValueError(f"tol_p must be > 0, got {self.tol_p}")
        if not 0.0 < self.rho < 1.0:
            raise ValueError(f"rho must be in (0, 1), got {self.rho}")
        if self.max_solves < 1 or self.locator_iterations < 1:
            raise ValueError("max_solves and locator_iterations must be >= 1")
        if self.partial_from < 0 or self.partial_max_k < 1:
            raise ValueError("partial_from must be >= 0 and partial_max_k >= 1")

    @property
    def detector(self) -> Detector:
        """The Detector of `mode` (detectors/)."""
        return DETECTORS[self.mode]

    @property
    def slopes(self) -> bool:
        """Whether the samples of accepted points carry eigenvalue slopes: the detection is on
        and its detector needs them."""
        return self.enabled and self.detector.slopes


SCAN_MEMORY = 1 << 30
"""Bytes of inner samples' eigenvectors a scan keeps in memory; beyond, the samples farthest
from its work go to disk (StepScan._spill): 3 full samples of the chain of 1000 disks (288 MB
a sample), the whole step at N = 300 (26 MB a sample). A larger budget spills less but lets
the continuation and its two scan workers hold three times it together
(docs/notes/core-refinement.md, "Tried and not adopted")."""


class _Budget(Exception):
    pass


@dataclass
class StepScan:
    """Collision detection on one step (module docstring): the step's samples, their labels and
    the refinement loop; the detector (params.detector) judges the intervals and resolves their
    events. samples: sorted by s; the first with s = 0 is x_a unless a stencil sample from the
    previous step (s < 0; Detector.stencil_from_previous) precedes it; the last is x_b (s = 1).
    eigensolver: the run's, for the full samples it inserts (partial ones are shift-inverts of
    the problem's StructuredMatrix: samples.partial_sample_at)."""

    problem: Problem
    segment: Segment
    samples: list
    params: DetectionParams
    step: int
    ends_at_event: bool = False
    eigensolver: Eigensolver = DEFAULT
    solves: int = 0
    warnings: list = field(default_factory=list)
    located: dict = field(default_factory=dict)
    end_perm: Optional[Array] = None
    _cache: dict = field(default_factory=dict)
    _points: dict = field(default_factory=dict)
    _born: dict = field(default_factory=dict)

    def __post_init__(self):
        self._born = {smp.s: -1 for smp in self.samples}  # insertion order by s (-1: the ends)
        self.end_perm = np.arange(self.samples[-1].eigvals.size)  # x_b's labels: new[i] = old[end_perm[i]]

    @property
    def detector(self) -> Detector:
        return self.params.detector

    @property
    def _start(self) -> int:
        return 1 if self.samples[0].s < 0.0 else 0

    # ---- sampler ---------------------------------------------------------------------------
    def _point(self, s: float) -> tuple[Array, Optional[Array]]:
        """The branch point at s (corrector solve, counted against max_solves) and, for the fast
        detection, its unit tangent; kept, so a partial sample that fails costs no second solve."""
        if s not in self._points:
            if self.solves >= self.params.max_solves:
                raise _Budget
            x = self.segment.point(s)
            self.solves += 1
            t = (tangent(self.problem, x, self.segment.sigma, self.segment.near(s), self.segment.linear_solver)
                 if self.detector.slopes else None)
            self._points[s] = (x, t)
            self.segment.remember(s, x.copy(), self._points[s][1])
        return self._points[s]

    def insert(self, s: float):
        """A full sample at s tracked to its left neighbour; the samples right of it are
        relabelled to continue it. Returns (index, perm or None)."""
        x, t = self._point(s)
        idx = bisect.bisect([smp.s for smp in self.samples], s)
        self.samples.insert(idx, sample_at(self.problem, s, x, self.params.rel_tol, self.samples[idx - 1], t,
                                           eigensolver=self.eigensolver))
        self._born[s] = len(self._born)
        return idx, self._relabel_right(idx)

    def _relabel_right(self, idx: int) -> Optional[Array]:
        """Relabel the samples right of the full samples[idx] to continue it; the perm, None if
        identity. A partial sample among them is then made full, in order (its certificates
        rest on the labels it had: partial_splits.py)."""
        perm = self._continue(idx)
        if perm is not None:
            for k in range(idx + 1, len(self.samples)):
                if self.samples[k].partial:
                    self._make_full(k)
                    self._continue(k)
        return perm

    def _slopes(self, left: Sample, right: Sample) -> Optional[tuple[Array, Array]]:
        """The slopes continuation_perm predicts by from left to its right neighbour: those in
        the segment's coordinate where right is a root end (Sample.root_end: its dlam is not
        along its tangent), else None (its default)."""
        return scaled_slopes(left, right, self.segment) if right.root_end else None

    def _perm(self, left: Sample, right: Sample) -> Array:
        """continuation_perm from left to its right neighbour (_slopes)."""
        return continuation_perm(left, right, self._slopes(left, right))

    def _continue(self, idx: int) -> Optional[Array]:
        """Relabel the samples right of samples[idx] to continue it; the perm, None if identity."""
        perm = self._perm(self.samples[idx], self.samples[idx + 1])
        if np.array_equal(perm, np.arange(perm.size)):
            return None
        for k in range(idx + 1, len(self.samples)):
            self.samples[k] = self.samples[k].relabel(perm)
        self.end_perm = self.end_perm[perm]
        return perm

    def _make_full(self, k: int) -> None:
        """samples[k] recomputed as a full sample tracked to its (full) left neighbour."""
        smp = self.samples[k]
        self.samples[k] = sample_at(self.problem, smp.s, smp.x, self.params.rel_tol, self.samples[k - 1],
                                    smp.tangent, eigensolver=self.eigensolver)

    # ---- partial samples (partial_splits.py) ------------------------------------------------
    def _insert_partial(self, idx: int, s: float, labels: Array) -> bool:
        """Split samples[idx], samples[idx + 1] at s with a partial sample of `labels`; False if
        it cannot be made (too many eigenvalues, not covered), if a label it did not compute
        continues one of its eigenvalues into a full right neighbour (labels.claimed_outside),
        or if it relabels its right neighbour in a way a certificate does not survive
        (partial_splits.certificates_survive)."""
        l, r = self.samples[idx], self.samples[idx + 1]
        reference = next(smp for smp in reversed(self.samples) if smp.s <= l.s and not smp.partial)
        shifts = clusters(l, r, s, np.flatnonzero(labels), reference.eigvals, self.segment,
                          self.params.partial_max_k, most_clusters(l))
        if shifts is None:
            return False
        x, t = self._point(s)
        new = partial_sample_at(self.problem, s, x, l, shifts, t)
        if new is None or (not r.partial and claimed_outside(new, r, self._slopes(new, r))):
            return False
        perm = self._perm(new, r)
        right = self.samples[idx + 1:]
        relabels = not np.array_equal(perm, np.arange(labels.size))
        trial = self.samples[:idx + 1] + [new] + ([smp.relabel(perm) for smp in right] if relabels else right)
        self._born[s] = len(self._born)
        if relabels and not certificates_survive(trial, idx + 1, [self._born[smp.s] for smp in trial],
                                                 lambda a, b: self.detector.judge(a, b, None, self.segment, self.params)):
            del self._born[s]
            return False
        self.samples = trial
        if relabels:
            self.end_perm = self.end_perm[perm]
        return True

    def _upgrade_partials(self, upto: int) -> None:
        """samples[upto] and the partial samples it is tracked through become full: from the
        nearest full sample left of it, each tracked to its full left neighbour, the samples
        right of it relabelled (_relabel_right: a relabelling that reaches a partial sample
        makes it full too)."""
        first = next(k for k in range(upto, -1, -1) if not self.samples[k].partial)
        for k in range(first + 1, upto + 1):
            if self.samples[k].partial:
                self._make_full(k)
                self._relabel_right(k)

    def split(self, idx: int, s: float, labels: Optional[Array] = None) -> None:
        """Sample inside samples[idx], samples[idx + 1] at s: partial if `labels` (in trouble)
        allow it, else full; a full sample is tracked from a full neighbour, so a partial end
        is made full first (with the partial samples it was tracked through; the interval is
        judged again afterwards)."""
        a, b = self.samples[idx], self.samples[idx + 1]
        if (self.detector.partial_splits and partial_allowed(a, b, labels, self.params.partial_from)
                and self._insert_partial(idx, s, labels)):
            return
        if a.partial or b.partial:
            self._upgrade_partials(idx + 1 if b.partial else idx)
            return
        self.insert(s)

    def narrow(self, a: Sample, b: Sample) -> bool:
        """Nothing left to resolve in [a, b]: |dp| <= tol_p and max|dx| <= sqrt(tol_p) (the
        second keeps an interval that straddles a fold, where p_a ~ p_b by symmetry, open).
        An interval that is not, and is min_ds wide in s or jumped (jumped), is a jump of the
        branch (BranchJump)."""
        tol = self.params.tol_p
        dx = float(np.max(np.abs(b.x - a.x)))
        if abs(b.p - a.p) <= tol and dx <= math.sqrt(tol):
            return True
        if b.s - a.s <= self.params.min_ds or self.jumped(a, b):
            raise BranchJump(f"step {self.step}: the branch jumps between s = {a.s:.15g} and "
                             f"{b.s:.15g}, from p = {a.p:.12g} to {b.p:.12g} (max |dx| {dx:.2g})")
        return False

    def jumped(self, a: Sample, b: Sample) -> bool:
        """Whether the ends of [a, b] lie farther apart than JUMP_RATIO times the branch moves
        between them along their tangents: |x_b - x_a| > JUMP_RATIO (s_b - s_a) L / min(sigma
        . t_a, sigma . t_b), L the step's length (dx/ds = L t / (sigma . t)); samples without
        tangents (the exhaustive detection's) are never taken for a jump before min_ds."""
        if a.tangent is None or b.tangent is None:
            return False
        along = min(float(self.segment.sigma @ a.tangent), float(self.segment.sigma @ b.tangent))
        moved = float(np.linalg.norm(b.x - a.x))
        ds = self.segment.real(b.s) - self.segment.real(a.s)
        return along > 0.0 and moved * along > JUMP_RATIO * ds * self.segment.length

    # ---- certifier -------------------------------------------------------------------------
    def verdict(self, idx: int) -> Verdict:
        """The detector's verdict on the interval samples[idx], samples[idx + 1] (cached by
        sample ids)."""
        a, b = self.samples[idx], self.samples[idx + 1]
        c = self.detector.stencil(self, idx)
        key = (a.uid, b.uid, None if c is None else c.uid)
        if key not in self._cache:
            self._cache[key] = self.detector.judge(a, b, c, self.segment, self.params)
        return self._cache[key]

    # ---- driver ----------------------------------------------------------------------------
    def _advance(self) -> bool:
        """Do one refinement action (at least one new sample or one located event); False when
        every interval is final."""
        for idx in range(self._start, len(self.samples) - 1):
            verdict = self.verdict(idx)
            if verdict.kind == VerdictKind.CLEAN or self.narrow(self.samples[idx], self.samples[idx + 1]):
                continue
            if verdict.kind == VerdictKind.SPLIT:
                self.split(idx, verdict.split_at, verdict.labels)
                return True
            if self.detector.resolve(self, idx, verdict):
                return True
        return False

    def release_vectors(self) -> None:
        """Drop the eigenvectors of the inner full samples that no locator can need any more:
        both neighbours full and both intervals final (_settled). That is final: a clean or
        narrow interval is never split, and a relabelling permutes both its ends alike; an
        interval whose events are all located lies left of every interval _advance acts on
        later, and splits and relabellings act right of that. (Next to a partial sample an
        interval is clean only on the labels known at both ends.) Keeps a busy step's peak
        memory down; the scan's results are the same."""
        S = self.samples
        for k in range(self._start + 1, len(S) - 1):
            if (S[k].system is not None and not (S[k - 1].partial or S[k].partial or S[k + 1].partial)
                    and self._settled(k - 1) and self._settled(k)):
                S[k] = S[k].without_vectors()
        self._spill()

    def _spill(self) -> None:
        """Move inner samples' eigenvectors to disk (Sample.spilled), farthest from the first
        unsettled interval first, until those held in memory are at most SCAN_MEMORY. The
        intervals right of the one the scan works on wait with both ends' vectors: at the
        chain of 1000 disks a step of 45 collisions held 40 samples' vectors, 6.1 GB, and the
        steps grow (docs/notes/core-refinement.md, "Memory at N = 1000"). Where the disk
        refuses (no space, no temporary directory) the samples stay in memory."""
        S = self.samples
        inner = range(self._start + 1, len(S) - 1)
        held = sum(S[k].vectors_in_memory for k in inner)
        if held <= SCAN_MEMORY:
            return
        first = next((idx for idx in range(self._start, len(S) - 1) if not self._settled(idx)), len(S) - 1)
        for k in sorted(inner, key=lambda k: -abs(k - first - 0.5)):
            if held <= SCAN_MEMORY:
                break
            if S[k].vectors_in_memory and k not in (first, first + 1):
                try:
                    spilled = S[k].spilled()
                except OSError:
                    return
                held -= S[k].vectors_in_memory
                S[k] = spilled

    def _settled(self, idx: int) -> bool:
        """Whether _advance passes the interval by: clean, narrow, or every event resolved
        (Detector.done)."""
        verdict = self.verdict(idx)
        return (verdict.kind == VerdictKind.CLEAN or self.narrow(self.samples[idx], self.samples[idx + 1])
                or (verdict.kind == VerdictKind.EVENTS and self.detector.done(self, idx, verdict)))

    def run(self) -> list:
        """Refine until every interval is final; return the collisions in branch order."""
        try:
            while self._advance():
                self.detector.settle(self)
        except _Budget:
            self.warnings.append(f"step {self.step}: detection budget of {self.params.max_solves} "
                                 "solves exhausted; remaining events unresolved")
        found = []
        for idx in range(self._start, len(self.samples) - 1):
            verdict = self.verdict(idx)
            a, b = self.samples[idx], self.samples[idx + 1]
            if not verdict.consistent:
                self.warnings.append(f"step {self.step}: status change in p=[{a.p:.12g}, {b.p:.12g}] "
                                     "not explained by births and deaths")
            for i, j, kind in verdict.events:
                located = self.located.get((a.uid, b.uid, i, j))
                if located is not None:
                    found.append(located)
                    continue
                final = self.detector.final(self, a, b, i, j, kind)
                found.append(self.interpolated(a, b, i, j, kind, resolved=verdict.consistent and final))
        return sorted(found, key=lambda c: float(self.segment.sigma @ (np.append(c.u, c.p) - self.segment.x_a)))

    def interpolated(self, a: Sample, b: Sample, i: int, j: int, kind: Kind, resolved: bool) -> Collision:
        """The collision of pair (i, j) bracketed by samples a, b: root of D linear in s."""
        d_a, d_b = sample_discriminant(a, i, j), sample_discriminant(b, i, j)
        t = d_a / (d_a - d_b) if np.isfinite(d_a - d_b) and d_a != d_b else 0.5
        t = min(max(t, 0.0), 1.0)
        x = a.x + t * (b.x - a.x)
        mean_a, mean_b = (a.eigvals[i] + a.eigvals[j]).real / 2, (b.eigvals[i] + b.eigvals[j]).real / 2
        lam = float(mean_a + t * (mean_b - mean_a))
        u, p = x[:-1], float(x[-1])
        v, w, overlap = jordan_chain_near(self.problem.stability_matrix(u, p), lam, self.segment.linear_solver)
        # a sample on the collision itself (real side with D <= 4 thr^2) is its own bracket
        bracket = (min(a.p, b.p), max(a.p, b.p)) if self.narrow(a, b) or not resolved else (p, p)
        return Collision(p=p, kind=kind, eigenvalue=lam, eigenvector=v, generalized_eigenvector=w,
                         left_right_overlap=overlap, bracket=bracket,
                         residual=residual_norm(self.problem, x), u=u.copy(), step=self.step,
                         pair=(i, j), resolved=resolved)


@dataclass(frozen=True)
class ScanResult:
    """What the scan of one step found: its collisions in branch order (pair: labels of the
    step's start sample); end_perm: the labels of x_b's sample after the scan (it continues
    the samples inserted), end.relabel(end_perm); samples solved; warnings; tracked: with a
    spectral window, the mask of the labels (of end.relabel(end_perm)) that no sample of the
    step excluded, whose continuity over the step the detection certified (None without a
    window)."""

    collisions: list
    end_perm: Array
    solves: int
    warnings: list
    tracked: Optional[Array] = None


def scan_step(problem: Problem, segment: Segment, start: Sample, end: Sample,
              params: DetectionParams, step: int, previous: Optional[Sample] = None,
              ends_at_event: bool = False, eigensolver: Eigensolver = DEFAULT) -> ScanResult:
    """Detect and locate the collisions between start (x_a) and end (x_b = segment.x_b).

    start: the sample of x_a (its labels are kept); end: the sample of x_b, labels continuing
    start; previous: the accepted point before x_a, the exhaustive detection's stencil (pass
    None if its step had collisions); ends_at_event: x_b lies just past a contact event (where
    it is a square-root point of the spectrum, root_ends.py treats the end apart);
    eigensolver: the run's, for the samples inside the step (eigensolvers.py).
    """
    if not params.enabled:
        return ScanResult([], np.arange(end.eigvals.size), 0, [])
    if ends_at_event and params.detector.slopes:
        segment, end = scan_ends(problem, segment, end)
    a, b = start.at(0.0), end.at(1.0)
    samples = [a, b]
    if previous is not None and params.detector.stencil_from_previous:
        s_prev = float(segment.sigma @ (previous.x - segment.x_a)) / segment.length
        if s_prev < 0.0:
            samples.insert(0, previous.at(s_prev))
    scan = StepScan(problem, segment, samples, params, step, ends_at_event, eigensolver)
    found = scan.run()
    tracked = None if b.disc is None else certified_tracked(scan.samples[scan._start:])
    return ScanResult(found, scan.end_perm, scan.solves, scan.warnings, tracked)


def certified_tracked(samples: list) -> Array:
    """The labels of a window's step whose continuity the detection certified: never excluded,
    and on no interval between the samples where they are known beyond the certified band on
    one side at both ends (verdicts.beyond_band: not certified there)."""
    tracked = ~np.any([smp.excluded for smp in samples], axis=0)
    last = band_side(samples[0])
    for smp in samples[1:]:
        side, seen = band_side(smp), known(smp)
        tracked &= ~(seen & (side != 0) & (side == last))
        last = np.where(seen, side, last)
    return tracked
