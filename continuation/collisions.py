"""Eigenvalue collisions along a branch: births and deaths of complex-conjugate pairs.

A *birth* is a point where two real eigenvalues of the stability matrix A meet and leave the
real axis as a conjugate pair (as the branch is followed in its direction); a *death* is the
reverse. Integer test function: the status of every tracked eigenvalue (0 real, +1 / -1 upper /
lower member of a complex pair, see spectra.eigen_status); the number of complex pairs is the
count of +1. Smooth test function of one pair (i, j): its discriminant
    D_ij = (lambda_i - lambda_j)^2 = tr^2 - 4 det  (of the pair's 2x2 invariant subspace),
real, smooth in the branch parameter, > 0 for two real eigenvalues, < 0 for a conjugate pair
(spectra.pair_discriminant). A collision is a sign change of D_ij.

Locating (per step x_a -> x_b, before the step is committed). Points between x_a and x_b are
x(s), s in [0, 1], computed by the corrector on the secant hyperplanes (segment.py). The step is
covered by samples (s, x(s), tracked spectrum); every interval [a, b] between neighbouring
samples gets one verdict:
  * events: eigenvalues whose status goes 0 -> +-1 (births, paired at b) or +-1 -> 0 (deaths,
    paired at a), paired by conjugacy and continuity of the pair's mean
    (spectra.conjugate_pairing); a status +1 <-> -1 or an unpaired change -> split.
  * certification of the unchanged eigenvalues, first by their motion: no eigenvalue real at
    both ends may move by more than rho times its gap to the nearest other real eigenvalue
    (outruns_gaps; label-free, it catches a fast eigenvalue passing through a cluster, where
    D of the pair is a near-parabola touching zero that a quadratic cannot tell from a
    bubble); then with a quadratic model: take the nearest other
    sample c whose status vector equals that of the adjacent end (no status change between c
    and [a, b]); through (a, b, c) fit q(t) = chord + kappa t (t - 1), t = (s - s_a)/(s_b - s_a), for
        every pair of eigenvalues real at a, b:   y = D_ij = (Re lambda_i - Re lambda_j)^2,
        every upper eigenvalue of a kept pair:    y = (Im lambda_i)^2 = -D / 4,
    and split if   |kappa| / 4 > (1 - rho) min(y_a, y_b) + 4 thr^2,
    i.e. if the bending of y over the interval is not small against its smaller end value (a
    bubble, a near miss, a crossing, an end close to a collision; thr = the status threshold,
    below which nothing can be resolved). No stencil c -> split.
  * clean: no events and no split.
A split inserts the midpoint; an events interval is refined by the Illinois method on D_ij of
its first event (each evaluation is a new sample); then all verdicts are recomputed. This ends
when every interval is clean or is an events interval of width |dp| <= tol_p (or whose real
side already has D <= 4 thr^2). The location is the root of D_ij interpolated linearly over that
final bracket; the eigenvalue is the pair's mean there, the eigenvectors come from an SVD of
A - lambda I (right and left null vectors; the generalized vector w solves (A - lambda I) w = v,
w orthogonal to v).

Guarantee (what "no misses" means here). On return, every sub-interval of the step is either
  (1) a bracket |dp| <= tol_p of each reported collision, whose status changes across it, or
  (2) status-unchanged and certified: for every pair that could collide (two real eigenvalues
      or a conjugate pair), y = D (or Im^2) bends by at most (1 - rho) min(y_a, y_b) in the
      three-sample quadratic, so the quadratic stays >= rho min(y_a, y_b) on the interval.
A collision inside a certified interval needs y to reach 0, so the remainder of the three-point
interpolation (cubic and higher terms) would have to exceed rho / (1 - rho) (= 1 for the default
rho = 0.5) times the largest quadratic term: missed only if y varies on a scale shorter than the
sample spacing. This covers a bubble (birth and death inside one step), several pairs born at
one p, narrowly avoided and exact crossings (resolved down to tol_p), and an accepted point that
lands next to a collision (the interval is split until the curvature is small against the
smaller end value). Limits: (a) two collisions closer than tol_p (a bubble narrower than tol_p)
are invisible; (b) y with structure below the sample spacing, invisible to three samples, can
be missed: shorten the steps (ds_max) if the spectrum varies faster than the branch; (c) the
tracking by minimal total displacement can mislabel eigenvalues that move more than their
separation within one interval; labels only serve the certification, and a mislabeling that
changes the status pattern forces splits; (d) eigenvalues are not smooth across a collision,
so a stencil never reaches across one (a previous-step sample is used only if that step had
none); the first step of a branch therefore always costs a midpoint sample; (e) each step
spends at most max_solves corrector solves; beyond that the remaining events are reported with
resolved=False and a warning.
"""
from __future__ import annotations

import bisect
import itertools
from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np

from .newton import residual_norm
from .problem import Problem
from .segment import Segment, refine_sign_change
from .spectra import (DEFAULT_REL_TOL, conjugate_pairing, eigen_status, imag_threshold,
                      match_eigenvalues, pair_discriminant, track)

Array = np.ndarray
_uid = itertools.count()


@dataclass(frozen=True)
class DetectionParams:
    """rel_tol: status threshold |Im| > rel_tol * max|lambda| (spectra.py); tol_p: bracket width
    |dp| of a located collision; rho: certification margin (0 < rho < 1, see module docstring);
    max_solves: corrector solves allowed per step for detection; enabled: False skips detection
    (spectra are still computed, tracked and counted)."""

    rel_tol: float = DEFAULT_REL_TOL
    tol_p: float = 1e-10
    rho: float = 0.5
    max_solves: int = 500
    enabled: bool = True

    def __post_init__(self):
        if not 0.0 < self.rel_tol < 1e-3:
            raise ValueError(f"rel_tol must be in (0, 1e-3), got {self.rel_tol}")
        if not self.tol_p > 0.0:
            raise ValueError(f"tol_p must be > 0, got {self.tol_p}")
        if not 0.0 < self.rho < 1.0:
            raise ValueError(f"rho must be in (0, 1), got {self.rho}")
        if self.max_solves < 1:
            raise ValueError(f"max_solves must be >= 1, got {self.max_solves}")


@dataclass(frozen=True)
class Collision:
    """A located eigenvalue collision.

    p: location; kind: "birth" (real pair -> complex pair along the branch direction) or
    "death"; eigenvalue: the (real) double eigenvalue; eigenvector v (unit, right null vector
    of A - eigenvalue I), generalized_eigenvector w ((A - eigenvalue I) w = v, w orthogonal to
    v: the Jordan chain), left_right_overlap |y . v| for the left null vector y (-> 0 at a
    Jordan block, ~1 at a semisimple double eigenvalue); bracket (p_lo, p_hi) across which
    the status changes; residual max|G| at the located point u; step: index of the accepted
    point that starts the step; pair: tracked eigenvalue indices; resolved: False if the
    step's detection budget ran out or the bracket could not be isolated.
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


@dataclass(frozen=True)
class Sample:
    """A branch point x = (u, p) at segment coordinate s with its tracked spectrum."""

    s: float
    x: Array
    eigvals: Array
    status: Array
    thr: float
    uid: int = field(default_factory=lambda: next(_uid), init=False, repr=False, compare=False)

    @property
    def p(self) -> float:
        return float(self.x[-1])


def make_sample(s: float, x: Array, eigvals: Array, rel_tol: float,
                reference: Optional[Sample] = None) -> Sample:
    """Sample at s; eigenvalues tracked to continue reference's when given."""
    eigvals = np.asarray(eigvals, dtype=complex)
    if reference is not None:
        eigvals = track(reference.eigvals, eigvals)
    return Sample(s, x, eigvals, eigen_status(eigvals, rel_tol), imag_threshold(eigvals, rel_tol))


def relabel(sample: Sample, perm: Array) -> Sample:
    """The same sample with eigenvalue labels permuted: new[i] = old[perm[i]]."""
    return Sample(sample.s, sample.x, sample.eigvals[perm], sample.status[perm], sample.thr)


def sample_discriminant(sample: Sample, i: int, j: int) -> float:
    """D_ij at a sample (spectra.pair_discriminant); nan if i, j cannot collide there."""
    ev, st = sample.eigvals, sample.status
    return float(pair_discriminant(ev[i], ev[j], st[i], st[j]))


def curvature_too_large(y_a: Array, y_b: Array, y_c: Array, t_c: float, rho: float, floor: float) -> bool:
    """True if for some k the quadratic q through (0, y_a), (1, y_b), (t_c, y_c) (t_c outside
    [0, 1]) bends by more than the certification margin:

        q(t) = y_a + (y_b - y_a) t + kappa t (t - 1),
        kappa = (y_c - y_a - (y_b - y_a) t_c) / (t_c (t_c - 1)),
        flag  if  |kappa| / 4 > (1 - rho) min(y_a, y_b) + floor.

    |kappa| / 4 is the largest deviation of q from the chord on [0, 1]; if it is within the
    margin, q >= rho min(y_a, y_b) - floor on the whole interval.
    """
    kappa = (y_c - y_a - (y_b - y_a) * t_c) / (t_c * (t_c - 1.0))
    return bool(np.any(0.25 * np.abs(kappa) > (1.0 - rho) * np.minimum(y_a, y_b) + floor))


def outruns_gaps(ev_a: Array, ev_b: Array, real: Array, rho: float, floor: float) -> bool:
    """True if some eigenvalue real at both ends moves by more than rho times its gap:

        |lambda_i(b) - lambda_i(a)| > rho min(gap_i(a), gap_i(b)) + floor,
        gap_i = min over the other real eigenvalues j of |lambda_i - lambda_j|.

    Two real eigenvalues must meet to collide; if none moves by more than a fraction of the
    distance to its nearest neighbour, none reaches another inside the interval. The test needs
    no correct labels: a tracking that swaps two eigenvalues passing each other shows a
    displacement of about their gap, which fails it. It samples geometrically towards every
    close encounter, so a bubble narrower than the step is entered or narrowed to tol_p.
    """
    if real.size < 2:
        return False
    ra, rb = ev_a.real[real], ev_b.real[real]

    def gaps(r):
        d = np.abs(r[:, None] - r[None, :])
        np.fill_diagonal(d, np.inf)
        return d.min(axis=1)

    return bool(np.any(np.abs(rb - ra) > rho * np.minimum(gaps(ra), gaps(rb)) + floor))


def jordan_vectors(A: Array, lam: float):
    """(v, w, overlap) at a double eigenvalue lam of A.

    v: unit right null vector of A - lam I (smallest singular vector), sign fixed so that its
    largest component is positive; w: least-squares solution of (A - lam I) w = v made
    orthogonal to v (the generalized eigenvector of a Jordan block); overlap = |y . v| with y
    the left null vector (0 for a Jordan block)."""
    M = A - lam * np.eye(A.shape[0])
    U, _, Vt = np.linalg.svd(M)
    v, y = Vt[-1], U[:, -1]
    v = v * np.sign(v[np.argmax(np.abs(v))])
    w = np.linalg.lstsq(M, v, rcond=None)[0]
    w = w - (v @ w) * v
    return v, w, float(abs(y @ v))


class _Budget(Exception):
    pass


_CLEAN, _SPLIT, _EVENTS = "clean", "split", "events"


@dataclass
class StepScan:
    """Collision detection on one step (see the module docstring). samples: sorted by s, the
    first with s = 0 is x_a unless a stencil sample from the previous step (s < 0) precedes it;
    the last is x_b (s = 1)."""

    problem: Problem
    segment: Segment
    samples: list
    params: DetectionParams
    step: int
    solves: int = 0
    warnings: list = field(default_factory=list)
    _cache: dict = field(default_factory=dict)

    @property
    def _start(self) -> int:
        return 1 if self.samples[0].s < 0.0 else 0

    # ---- samples -------------------------------------------------------------------------
    def insert(self, s: float):
        """Corrector solve at s, new sample tracked to its left neighbour; the samples right of
        it are relabelled to continue it. Returns (index, perm or None)."""
        if self.solves >= self.params.max_solves:
            raise _Budget
        x = self.segment.point(s)
        self.solves += 1
        idx = bisect.bisect([smp.s for smp in self.samples], s)
        new = make_sample(s, x, self.problem.spectrum(x[:-1], x[-1]), self.params.rel_tol,
                          reference=self.samples[idx - 1])
        self.samples.insert(idx, new)
        perm = match_eigenvalues(new.eigvals, self.samples[idx + 1].eigvals)
        if np.array_equal(perm, np.arange(perm.size)):
            return idx, None
        for k in range(idx + 1, len(self.samples)):
            self.samples[k] = relabel(self.samples[k], perm)
        return idx, perm

    def _narrow(self, a: Sample, b: Sample) -> bool:
        """Nothing left to resolve in [a, b]: |dp| <= tol_p and max|dx| <= sqrt(tol_p) (the
        second keeps an interval that straddles a fold, where p_a ~ p_b by symmetry, open)."""
        tol = self.params.tol_p
        return (abs(b.p - a.p) <= tol and float(np.max(np.abs(b.x - a.x))) <= np.sqrt(tol)) \
            or b.s - a.s <= 1e-14

    # ---- verdicts ------------------------------------------------------------------------
    def _stencil(self, idx: int) -> Optional[Sample]:
        S = self.samples
        a, b = S[idx], S[idx + 1]
        left = S[idx - 1] if idx >= 1 and np.array_equal(S[idx - 1].status, a.status) else None
        right = S[idx + 2] if idx + 2 < len(S) and np.array_equal(S[idx + 2].status, b.status) else None
        if left is None or right is None:
            return left or right
        return left if a.s - left.s <= right.s - b.s else right

    def _uncertified(self, a: Sample, b: Sample, c: Sample) -> bool:
        """Some pair that could collide bends too much over [a, b] (curvature_too_large)."""
        same = a.status == b.status
        t_c = (c.s - a.s) / (b.s - a.s)
        floor = 4.0 * max(a.thr, b.thr) ** 2
        real = np.flatnonzero(same & (a.status == 0))
        I, J = np.triu_indices(real.size, 1)
        I, J = real[I], real[J]
        upper = np.flatnonzero(same & (a.status > 0))
        y = [np.concatenate([(smp.eigvals.real[I] - smp.eigvals.real[J]) ** 2, smp.eigvals.imag[upper] ** 2])
             for smp in (a, b, c)]
        return (curvature_too_large(*y, t_c, self.params.rho, floor)
                or outruns_gaps(a.eigvals, b.eigvals, real, self.params.rho, 2.0 * max(a.thr, b.thr)))

    @staticmethod
    def status_events(a: Sample, b: Sample):
        """Births (0 -> +-1, paired at b) and deaths (+-1 -> 0, paired at a) on [a, b], and
        whether the status change is fully explained by them."""
        sa, sb = a.status, b.status
        if np.array_equal(sa, sb):
            return [], True
        born, died = (sa == 0) & (sb != 0), (sa != 0) & (sb == 0)
        bu, bl = np.flatnonzero(born & (sb > 0)), np.flatnonzero(born & (sb < 0))
        du, dl = np.flatnonzero(died & (sa > 0)), np.flatnonzero(died & (sa < 0))
        events = [(i, j, "birth") for i, j in conjugate_pairing(b.eigvals, bu, bl, other=a.eigvals)]
        events += [(i, j, "death") for i, j in conjugate_pairing(a.eigvals, du, dl, other=b.eigvals)]
        consistent = bu.size == bl.size and du.size == dl.size and not np.any(sa * sb < 0)
        return events, consistent

    def verdict(self, idx: int):
        """(kind, events, consistent) for the interval samples[idx], samples[idx + 1]; kind is
        _CLEAN, _SPLIT or _EVENTS, consistent tells whether the events explain the status change."""
        a, b = self.samples[idx], self.samples[idx + 1]
        c = self._stencil(idx)
        key = (a.uid, b.uid, None if c is None else c.uid)
        if key not in self._cache:
            events, consistent = self.status_events(a, b)
            if not consistent or c is None or self._uncertified(a, b, c):
                kind = _SPLIT
            else:
                kind = _EVENTS if events else _CLEAN
            self._cache[key] = (kind, events, consistent)
        return self._cache[key]

    def _event_final(self, a: Sample, b: Sample, i: int, j: int, what: str) -> bool:
        """The event's bracket is |dp| <= tol_p, or its real side is already a double eigenvalue."""
        real_side = a if what == "birth" else b
        return self._narrow(a, b) or sample_discriminant(real_side, i, j) <= 4.0 * real_side.thr ** 2

    # ---- driver --------------------------------------------------------------------------
    def _advance(self) -> bool:
        """Do one refinement action (at least one new sample); False when every interval is final."""
        for idx in range(self._start, len(self.samples) - 1):
            kind, events, _ = self.verdict(idx)
            a, b = self.samples[idx], self.samples[idx + 1]
            if kind == _CLEAN or self._narrow(a, b):
                continue
            if kind == _SPLIT:
                self.insert(0.5 * (a.s + b.s))
                return True
            for i, j, what in events:
                if not self._event_final(a, b, i, j, what):
                    n = len(self.samples)
                    self._refine(idx, i, j)
                    if len(self.samples) == n:  # no progress: fall back to bisection
                        self.insert(0.5 * (a.s + b.s))
                    return True
        return False

    def _refine(self, idx: int, i: int, j: int) -> None:
        """Illinois on s -> D_ij(x(s)) over samples[idx], samples[idx + 1]; every evaluation
        stays as a sample. Aborts when the pair loses its labels or its eligibility."""
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

    def run(self) -> list:
        """Refine until every interval is final; return the collisions in branch order."""
        try:
            while self._advance():
                pass
        except _Budget:
            self.warnings.append(f"step {self.step}: detection budget of {self.params.max_solves} "
                                 "solves exhausted; remaining events unresolved")
        found = []
        for idx in range(self._start, len(self.samples) - 1):
            kind, events, consistent = self.verdict(idx)
            a, b = self.samples[idx], self.samples[idx + 1]
            if not consistent:
                self.warnings.append(f"step {self.step}: status change in p=[{a.p:.12g}, {b.p:.12g}] "
                                     "not explained by births and deaths")
            for i, j, what in events:
                final = self._event_final(a, b, i, j, what)
                found.append(self.collision(a, b, i, j, what, resolved=consistent and final))
        return found

    def collision(self, a: Sample, b: Sample, i: int, j: int, kind: str, resolved: bool) -> Collision:
        """The collision of pair (i, j) bracketed by samples a, b: root of D linear in s."""
        d_a, d_b = sample_discriminant(a, i, j), sample_discriminant(b, i, j)
        t = d_a / (d_a - d_b) if np.isfinite(d_a - d_b) and d_a != d_b else 0.5
        t = min(max(t, 0.0), 1.0)
        x = a.x + t * (b.x - a.x)
        mean_a, mean_b = (a.eigvals[i] + a.eigvals[j]).real / 2, (b.eigvals[i] + b.eigvals[j]).real / 2
        lam = float(mean_a + t * (mean_b - mean_a))
        u, p = x[:-1], float(x[-1])
        v, w, overlap = jordan_vectors(self.problem.stability_matrix(u, p), lam)
        # a sample on the collision itself (real side with D <= 4 thr^2) is its own bracket
        bracket = (min(a.p, b.p), max(a.p, b.p)) if self._narrow(a, b) or not resolved else (p, p)
        return Collision(p=p, kind=kind, eigenvalue=lam, eigenvector=v, generalized_eigenvector=w,
                         left_right_overlap=overlap, bracket=bracket,
                         residual=residual_norm(self.problem, x), u=u.copy(), step=self.step,
                         pair=(i, j), resolved=resolved)


def scan_step(problem: Problem, segment: Segment, start: Sample, end_eigvals: Array,
              params: DetectionParams, step: int, previous: Optional[Sample] = None):
    """Detect and locate the collisions between start (x_a) and x_b = segment.x_b.

    start: the sample of x_a (its labels are kept); end_eigvals: spectrum at x_b; previous:
    the accepted point before x_a, used as a stencil (pass None if its step had collisions).
    Returns (collisions, end sample tracked through the inserted samples, solves, warnings).
    """
    a = replace(start, s=0.0)
    b = make_sample(1.0, segment.x_b, end_eigvals, params.rel_tol, reference=a)
    if not params.enabled:
        return [], b, 0, []
    samples = [a, b]
    if previous is not None:
        L = np.linalg.norm(segment.x_b - segment.x_a)
        s_prev = float(segment.sigma @ (previous.x - segment.x_a)) / L
        if s_prev < 0.0:
            samples.insert(0, replace(previous, s=s_prev))
    scan = StepScan(problem, segment, samples, params, step)
    found = scan.run()
    return found, scan.samples[-1], scan.solves, scan.warnings
