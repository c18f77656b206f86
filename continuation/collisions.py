"""Eigenvalue collisions along a branch: births and deaths of complex-conjugate pairs.

A *birth* is a point where two real eigenvalues of the stability matrix A meet and leave the
real axis as a conjugate pair (as the branch is followed in its direction); a *death* is the
reverse. Integer test function: the status of every tracked eigenvalue (0 real, +1 / -1 upper /
lower member of a complex pair, spectra.eigen_status); the number of complex pairs is the count
of +1. Smooth test function of one pair (i, j): its discriminant D_ij = (lambda_i - lambda_j)^2
(spectra.pair_discriminant), > 0 for two real eigenvalues, < 0 for a conjugate pair.

Detection on one step x_a -> x_b (before the step is committed) works on samples (samples.py):
branch points x(s), s in [0, 1], on the step's secant segment (segment.py), with tracked spectra.
Three parts, each a module testable alone, and this module's StepScan, which acts on them:
  * the sampler (samples.py): corrector solve at s (segment.py), eigensystem, labels; a split
    sample is partial where partial_splits.py allows it (only the labels in trouble);
  * the certifier (verdicts.py, over certify.py's models): the verdict on an interval between
    neighbouring samples: events (births and deaths to locate), split (where to sample next,
    and which labels are in trouble) or clean;
  * the locator (locate.py): the collision of an event pair inside its interval.
Two detections combine them (DetectionParams.mode):
  "fast" (default): samples carry eigenvalue slopes from left and right eigenvectors; intervals
      are certified by cubic Hermite models of every pair's D (certify.worst_uncertified_pair) and
      the labels by their slopes (certify.inconsistent_labels); an uncertified interval gets a
      new sample where the worst pair's model is lowest; events are located by Newton's method
      on the minimally augmented system (locate.py): linear solves, no eigensolver. One full
      spectrum per accepted point; a split sample computes, from n = partial_from on, only the
      eigenvalues near the labels in trouble (partial samples: partial_splits.py), else a full
      spectrum.
  "exhaustive" (version 0.1): samples without slopes; intervals certified by the three-sample
      quadratic of every pair's D and the motion of every real eigenvalue against its gap
      (certify.curvature_too_large, certify.outruns_gaps); splits at midpoints; events located
      by the Illinois method on D, every evaluation a new sample with its full spectrum. Kept
      to check the fast one (tests/test_detection.py).
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

from . import certify
from .locate import LocatorFailed, jordan_chain_near, locate_double_eigenvalue
from .newton import residual_norm, tangent
from .partial_splits import certificates_survive, clusters, partial_allowed
from .problem import Problem
from .samples import Sample, continuation_perm, partial_sample_at, sample_at
from .segment import Segment, refine_sign_change
from .spectra import DEFAULT_REL_TOL, pair_discriminant
from .verdicts import Verdict, event_model, judge, scaled_slopes

Array = np.ndarray

MODES = ("fast", "exhaustive")


@dataclass(frozen=True)
class DetectionParams:
    """mode: "fast" or "exhaustive" (module docstring); rel_tol: status threshold
    |Im| > rel_tol * max|lambda| (spectra.py); tol_p: |dp| to which a collision is located (the
    fast locator's last Newton correction, or the exhaustive bracket); rho: certification margin
    (0 < rho < 1, certify.py); max_solves: samples allowed per step; enabled: False skips
    detection (spectra are still computed, tracked and counted, unless spectra is False: then
    no eigenvalue is computed at all, for a caller that needs only the equilibria, e.g.
    continuation.equilibrium); min_ds: intervals narrower
    than this in s are final (the segment coordinate's resolution, 100 ulp of 1);
    locator_iterations: Newton iterations of the fast locator before it falls back to a split;
    partial_from: matrix size n from which a split sample of the fast detection is partial
    (only the eigenvalues near the labels in trouble, nearest.py; 0: always, a value above n:
    never); partial_max_k: the most eigenvalues a partial sample computes (beyond that, or
    when they do not cover the labels, the sample is a full spectrum); workers: processes that
    scan steps while the continuation goes on (scans.py; 0: every scan inline; None: 2 for the
    fast detection from n = scans.PARALLEL_FROM on, on Linux with 2 cores, else 0:
    scans.default_workers)."""

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
    workers: Optional[int] = None

    def __post_init__(self):
        if self.mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, got {self.mode!r}")
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
        if self.workers is not None and self.workers < 0:
            raise ValueError(f"workers must be >= 0 (or None: automatic), got {self.workers}")

    @property
    def slopes(self) -> bool:
        """Whether samples carry eigenvalue slopes (the fast detection needs them)."""
        return self.enabled and self.mode == "fast"


@dataclass(frozen=True)
class Collision:
    """A located eigenvalue collision.

    p: location; kind: "birth" (real pair -> complex pair along the branch direction) or
    "death"; eigenvalue: the (real) double eigenvalue; eigenvector v (unit, right null vector
    of A - eigenvalue I), generalized_eigenvector w ((A - eigenvalue I) w = v, w orthogonal to
    v: the Jordan chain), left_right_overlap |y . v| for the unit left null vector y (-> 0 at a
    Jordan block, ~1 at a semisimple double eigenvalue); bracket (p_lo, p_hi): p is within it
    (fast: p +- the last Newton correction; exhaustive: the final bracket across which the
    status changes); residual max|G| at the located point u; step: index of the accepted point
    that starts the step; pair: tracked eigenvalue indices; resolved: False if the step's
    detection budget ran out or the bracket could not be isolated.
    """

    p: float
    kind: str
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
    """D_ij at a sample (spectra.pair_discriminant); nan if i, j cannot collide there."""
    ev, st = sample.eigvals, sample.status
    return float(pair_discriminant(ev[i], ev[j], st[i], st[j]))


class _Budget(Exception):
    pass


@dataclass
class StepScan:
    """Collision detection on one step (module docstring). samples: sorted by s; the first with
    s = 0 is x_a unless an exhaustive stencil sample from the previous step (s < 0) precedes it;
    the last is x_b (s = 1)."""

    problem: Problem
    segment: Segment
    samples: list
    params: DetectionParams
    step: int
    ends_at_event: bool = False
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
            self._points[s] = (x, tangent(self.problem, x, self.segment.sigma) if self.params.slopes else None)
        return self._points[s]

    def insert(self, s: float):
        """A full sample at s tracked to its left neighbour; the samples right of it are
        relabelled to continue it. Returns (index, perm or None)."""
        x, t = self._point(s)
        idx = bisect.bisect([smp.s for smp in self.samples], s)
        self.samples.insert(idx, sample_at(self.problem, s, x, self.params.rel_tol, self.samples[idx - 1], t))
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

    def _continue(self, idx: int) -> Optional[Array]:
        """Relabel the samples right of samples[idx] to continue it; the perm, None if identity."""
        perm = continuation_perm(self.samples[idx], self.samples[idx + 1])
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
                                    smp.tangent)

    # ---- partial samples (partial_splits.py) ------------------------------------------------
    def _insert_partial(self, idx: int, s: float, labels: Array) -> bool:
        """Split samples[idx], samples[idx + 1] at s with a partial sample of `labels`; False if
        it cannot be made (too many eigenvalues, not covered) or relabels its right neighbour
        in a way a certificate does not survive (partial_splits.certificates_survive)."""
        l, r = self.samples[idx], self.samples[idx + 1]
        reference = next(smp for smp in reversed(self.samples) if smp.s <= l.s and not smp.partial)
        shifts = clusters(l, r, s, np.flatnonzero(labels), reference.eigvals, self.segment,
                          self.params.partial_max_k)
        if shifts is None:
            return False
        x, t = self._point(s)
        new = partial_sample_at(self.problem, s, x, l, shifts, t)
        if new is None:
            return False
        perm = continuation_perm(new, r)
        right = self.samples[idx + 1:]
        relabels = not np.array_equal(perm, np.arange(labels.size))
        trial = self.samples[:idx + 1] + [new] + ([smp.relabel(perm) for smp in right] if relabels else right)
        self._born[s] = len(self._born)
        if relabels and not certificates_survive(trial, idx + 1, [self._born[smp.s] for smp in trial],
                                                 lambda a, b: self._judge(a, b, None)):
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

    def _split(self, idx: int, s: float, labels: Optional[Array] = None) -> None:
        """Sample inside samples[idx], samples[idx + 1] at s: partial if `labels` (in trouble)
        allow it, else full; a full sample is tracked from a full neighbour, so a partial end
        is made full first (with the partial samples it was tracked through; the interval is
        judged again afterwards)."""
        a, b = self.samples[idx], self.samples[idx + 1]
        if (self.params.slopes and partial_allowed(a, b, labels, self.params.partial_from)
                and self._insert_partial(idx, s, labels)):
            return
        if a.partial or b.partial:
            self._upgrade_partials(idx + 1 if b.partial else idx)
            return
        self.insert(s)

    def _narrow(self, a: Sample, b: Sample) -> bool:
        """Nothing left to resolve in [a, b]: |dp| <= tol_p and max|dx| <= sqrt(tol_p) (the
        second keeps an interval that straddles a fold, where p_a ~ p_b by symmetry, open)."""
        tol = self.params.tol_p
        return (abs(b.p - a.p) <= tol and float(np.max(np.abs(b.x - a.x))) <= math.sqrt(tol)) \
            or b.s - a.s <= self.params.min_ds

    # ---- certifier -------------------------------------------------------------------------
    def verdict(self, idx: int) -> Verdict:
        """The verdict on the interval samples[idx], samples[idx + 1] (cached by sample ids)."""
        a, b = self.samples[idx], self.samples[idx + 1]
        c = None if self.params.slopes else self._stencil(idx)
        key = (a.uid, b.uid, None if c is None else c.uid)
        if key not in self._cache:
            self._cache[key] = self._judge(a, b, c)
        return self._cache[key]

    def _judge(self, a: Sample, b: Sample, c: Optional[Sample]) -> Verdict:
        """verdicts.judge with this scan's segment and tolerances (c: the exhaustive stencil)."""
        return judge(a, b, c, self.segment, self.params.rho, self.params.doubt, self.params.slopes)

    def _stencil(self, idx: int) -> Optional[Sample]:
        """Exhaustive: the nearest sample beyond [a, b] with the status of the adjacent end."""
        S = self.samples
        a, b = S[idx], S[idx + 1]
        left = S[idx - 1] if idx >= 1 and np.array_equal(S[idx - 1].status, a.status) else None
        right = S[idx + 2] if idx + 2 < len(S) and np.array_equal(S[idx + 2].status, b.status) else None
        if left is None or right is None:
            return left or right
        return left if a.s - left.s <= right.s - b.s else right

    # ---- locators --------------------------------------------------------------------------
    def _locate_fast(self, idx: int, i: int, j: int, kind: str) -> Optional[Collision]:
        """Newton on the minimally augmented system from the cubic model's root; None if it
        fails or lands outside the interval."""
        a, b = self.samples[idx], self.samples[idx + 1]
        h = b.s - a.s
        mean, D = event_model(a, b, i, j, *scaled_slopes(a, b, self.segment))
        roots = certify.cubic_roots_in_unit(D)
        t0 = roots[0] if roots else 0.5
        real_side = a if kind == "birth" else b
        right, left = real_side.system.vectors(i)
        x0 = self.segment.secant_point(a.s + t0 * h)
        try:
            found = locate_double_eigenvalue(
                self.problem, x0, float(certify.cubic_at(mean, t0)), right, left.conj(),
                self.segment.sigma, self.params.tol_p, self.segment.tol,
                self.params.locator_iterations)
        except LocatorFailed as err:
            self.warnings.append(f"step {self.step}: locator: {err}; splitting")
            return None
        s = float(self.segment.sigma @ (found.x - self.segment.x_a)) / self.segment.length
        lo, hi = min(a.p, b.p), max(a.p, b.p)
        p = float(found.x[-1])
        if not (a.s - 1e-9 <= s <= b.s + 1e-9 and lo - self.params.tol_p <= p <= hi + self.params.tol_p):
            return None
        return Collision(p=p, kind=kind, eigenvalue=found.lam, eigenvector=found.v,
                         generalized_eigenvector=found.w, left_right_overlap=found.overlap,
                         bracket=(p - found.dp, p + found.dp), residual=found.residual,
                         u=found.x[:-1].copy(), step=self.step, pair=(i, j))

    def _fallback_split(self, a: Sample, b: Sample) -> float:
        """Where to sample when the fast locator failed: the midpoint, except in the last
        interval of a step ending on a contact event, where the spectrum is not smooth (a
        Hertz stiffness ~ delta^(1/2) has an infinite slope at delta = 0), collisions crowd
        towards the event and Newton cannot converge on one sitting at it: there a sample
        tol_p / 2 before the end isolates it (collision at the event within tol_p)."""
        if self.ends_at_event and b.s == 1.0 and abs(b.p - a.p) > self.params.tol_p:
            return b.s - 0.5 * self.params.tol_p / abs(b.p - a.p) * (b.s - a.s)
        return 0.5 * (a.s + b.s)

    def _event_final(self, a: Sample, b: Sample, i: int, j: int, what: str) -> bool:
        """Exhaustive: the event's bracket is |dp| <= tol_p, or its real side is already a double
        eigenvalue."""
        real_side = a if what == "birth" else b
        return self._narrow(a, b) or sample_discriminant(real_side, i, j) <= 4.0 * real_side.thr ** 2

    def _refine(self, idx: int, i: int, j: int) -> None:
        """Exhaustive: Illinois on s -> D_ij(x(s)) over samples[idx], samples[idx + 1]; every
        evaluation stays as a sample. Aborts when the pair loses its labels or eligibility."""
        a, b = self.samples[idx], self.samples[idx + 1]
        at = {a.s: a, b.s: b}

        def f(s: float):
            k, perm = self.insert(s)
            if perm is not None and set(perm[[i, j]].tolist()) != {i, j}:
                return None
            at[s] = self.samples[k]
            d = sample_discriminant(at[s], i, j)
            return None if np.isnan(d) else d

        refine_sign_change(f, a.s, sample_discriminant(a, i, j), b.s, sample_discriminant(b, i, j),
                           lambda lo, hi: self._narrow(at[lo], at[hi]))

    # ---- driver ----------------------------------------------------------------------------
    def _advance(self) -> bool:
        """Do one refinement action (at least one new sample or one located event); False when
        every interval is final."""
        for idx in range(self._start, len(self.samples) - 1):
            verdict = self.verdict(idx)
            a, b = self.samples[idx], self.samples[idx + 1]
            if verdict.kind == "clean" or self._narrow(a, b):
                continue
            if verdict.kind == "split":
                self._split(idx, verdict.split_at, verdict.labels)
                return True
            for i, j, what in verdict.events:
                if self.params.slopes:
                    key = (a.uid, b.uid, i, j)
                    if key in self.located:
                        continue
                    found = self._locate_fast(idx, i, j, what)
                    if found is None:
                        self._split(idx, self._fallback_split(a, b))
                    else:
                        self.located[key] = found
                    return True
                if not self._event_final(a, b, i, j, what):
                    n = len(self.samples)
                    self._refine(idx, i, j)
                    if len(self.samples) == n:  # no progress: fall back to bisection
                        self.insert(0.5 * (a.s + b.s))
                    return True
        return False

    def _release_vectors(self) -> None:
        """Drop the eigenvectors of the inner full samples that no locator can need any more:
        both neighbours full and both intervals clean or narrow. That is final: a clean or
        narrow interval is never split, and a relabelling permutes both its ends alike. (Next
        to a partial sample an interval is clean only on the labels known at both ends.) Keeps
        a busy step's peak memory down; the scan's results are the same."""
        S = self.samples
        for k in range(self._start + 1, len(S) - 1):
            if (S[k].system is not None and not (S[k - 1].partial or S[k].partial or S[k + 1].partial)
                    and self._settled(k - 1) and self._settled(k)):
                S[k] = S[k].without_vectors()

    def _settled(self, idx: int) -> bool:
        verdict = self.verdict(idx)
        return verdict.kind == "clean" or self._narrow(self.samples[idx], self.samples[idx + 1])

    def run(self) -> list:
        """Refine until every interval is final; return the collisions in branch order."""
        try:
            while self._advance():
                if self.params.slopes:
                    self._release_vectors()
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
            for i, j, what in verdict.events:
                located = self.located.get((a.uid, b.uid, i, j))
                if located is not None:
                    found.append(located)
                    continue
                final = self._narrow(a, b) if self.params.slopes else self._event_final(a, b, i, j, what)
                found.append(self.interpolated(a, b, i, j, what, resolved=verdict.consistent and final))
        return sorted(found, key=lambda c: float(self.segment.sigma @ (np.append(c.u, c.p) - self.segment.x_a)))

    def interpolated(self, a: Sample, b: Sample, i: int, j: int, kind: str, resolved: bool) -> Collision:
        """The collision of pair (i, j) bracketed by samples a, b: root of D linear in s."""
        d_a, d_b = sample_discriminant(a, i, j), sample_discriminant(b, i, j)
        t = d_a / (d_a - d_b) if np.isfinite(d_a - d_b) and d_a != d_b else 0.5
        t = min(max(t, 0.0), 1.0)
        x = a.x + t * (b.x - a.x)
        mean_a, mean_b = (a.eigvals[i] + a.eigvals[j]).real / 2, (b.eigvals[i] + b.eigvals[j]).real / 2
        lam = float(mean_a + t * (mean_b - mean_a))
        u, p = x[:-1], float(x[-1])
        v, w, overlap = jordan_chain_near(self.problem.stability_matrix(u, p), lam)
        # a sample on the collision itself (real side with D <= 4 thr^2) is its own bracket
        bracket = (min(a.p, b.p), max(a.p, b.p)) if self._narrow(a, b) or not resolved else (p, p)
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
              ends_at_event: bool = False) -> ScanResult:
    """Detect and locate the collisions between start (x_a) and end (x_b = segment.x_b).

    start: the sample of x_a (its labels are kept); end: the sample of x_b, labels continuing
    start; previous: the accepted point before x_a, the exhaustive detection's stencil (pass
    None if its step had collisions); ends_at_event: x_b lies just past a contact event.
    """
    a, b = start.at(0.0), end.at(1.0)
    if not params.enabled:
        return ScanResult([], np.arange(b.eigvals.size), 0, [])
    samples = [a, b]
    if previous is not None and not params.slopes:
        s_prev = float(segment.sigma @ (previous.x - segment.x_a)) / segment.length
        if s_prev < 0.0:
            samples.insert(0, previous.at(s_prev))
    scan = StepScan(problem, segment, samples, params, step, ends_at_event)
    found = scan.run()
    tracked = None
    if b.disc is not None:
        tracked = ~np.any([smp.excluded for smp in scan.samples[scan._start:]], axis=0)
    return ScanResult(found, scan.end_perm, scan.solves, scan.warnings, tracked)
