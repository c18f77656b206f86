"""Samples: branch points with their tracked spectra, the data collision detection works on.

A sample is a point x = (u, p) of the branch at coordinate s of the step's segment (segment.py),
its eigenvalues in tracked order (label i continues label i of the neighbouring sample), their
status (spectra.eigen_status) and, for the fast detection, their slopes along the branch:

    d lambda_i / d tau = l_i^H (dA/dtau) r_i,      tau the arclength along the unit tangent t,

from the normalised left and right eigenvectors (spectra.eigenvalue_slopes), with dA/dtau
from finite differences of the stability matrix along t (matrix_derivative). On a segment of
length L with unit normal sigma, x'(s) = t L / (sigma . t), so d lambda / ds follows (slopes).
Matching the labels of a new sample uses these slopes: label i goes to the eigenvalue nearest to
the trapezoid prediction lambda_i + (slope_i + slope_new) ds / 2 (spectra.match_eigenvalues on
the predicted values), which follows a fast eigenvalue through a cluster. A spectral window's
samples hold the k eigenvalues nearest its centre, a set that changes along the branch: an
eigenvalue beyond the guard bands may leave it and another join it (window_match).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

from diskfriction.continuation.detection.certify import inconsistent_labels, nearest_gaps
from diskfriction.continuation.linalg.solves import book
from diskfriction.continuation.spectra.nearest import ShiftInvertFailed, nearest_eigensystem
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.spectra.eigensolvers import DEFAULT, Eigensolver
from diskfriction.continuation.detection.spill import is_on_disk, on_disk
from diskfriction.continuation.spectra.tracking import (Eigensystem, eigen_status, eigenvalue_slopes, imag_threshold, match_eigenvalues,
                      status_at)

Array = np.ndarray


@dataclass(frozen=True)
class Sample:
    """A branch point at segment coordinate s: x = (u, p), tracked eigenvalues, status per
    eigenvalue, status threshold thr; excluded modes (never part of a collision); with slopes:
    tangent t (unit, oriented along the branch), dlam = d lambda / d tau along t, the
    eigensystem (vectors in label order) that seeds the collision locator, and gaps: each
    eigenvalue's distance to the nearest other one (a lower bound where not all are known).
    known: None for a full sample; for a partial one (partial_sample_at) the mask of labels
    computed, the others holding nan (status: the left neighbour's). disc: a spectral window's
    (sigma, radius), Eigensystem.disc (None: every eigenvalue computed, or a partial sample).
    uid: the token the scan's caches key on (verdicts, located collisions): a new one whenever
    the point, its labels or its slopes change (at, relabel, moved; any replace() that
    changes the data must pass uid=object()), the same one when only the vectors are released
    (without_vectors). A token of its own, not a number from a shared counter: no state is
    shared between samples, and none collides between a scan worker and this process.
    dA: the stability matrix's derivative d A / d tau along the tangent that gave the slopes
    (dense or sparse), kept with the vectors for pair_coupling. band: a spectral window's
    certified band (lo, hi) of Re lambda, Eigensystem.band (None: every eigenvalue certified).
    root_end: the end sample of a scan whose segment has a root end (Segment.root,
    root_ends.py): its dlam and dA are derivatives in the segment's coordinate w, finite where
    those along the tangent are not."""

    s: float
    x: Array
    eigvals: Array
    status: Array
    thr: float
    excluded: Array
    tangent: Optional[Array] = None
    dlam: Optional[Array] = None
    system: Optional[Eigensystem] = None
    guard: Optional[Array] = None
    gaps: Optional[Array] = None
    known: Optional[Array] = None
    disc: Optional[tuple[float, float]] = None
    dA: object = None
    band: Optional[tuple[float, float]] = None
    root_end: bool = False
    uid: object = field(default_factory=object, repr=False, compare=False)

    @property
    def p(self) -> float:
        return float(self.x[-1])

    def at(self, s: float) -> "Sample":
        """The same point at another segment coordinate (a new step starts at its old end)."""
        return replace(self, s=s, uid=object())

    def moved(self, x: Array, tangent: Optional[Array] = None, dlam: Optional[Array] = None,
              dA=None) -> "Sample":
        """The same spectrum at the point x (where the matrix it is computed from is the same),
        with the slopes dlam along `tangent` from the matrix derivative dA (None: without
        slopes)."""
        return replace(self, x=x, tangent=tangent, dlam=dlam, dA=dA, uid=object())

    def without_vectors(self) -> "Sample":
        """The same sample without its eigenvectors (the slopes stay), under the same uid: the
        verdicts cached on it stay valid (collisions.StepScan.release_vectors)."""
        return replace(self, system=None, dA=None)

    def spilled(self) -> "Sample":
        """The same sample, under the same uid, with its eigenvectors on disk (on_disk):
        the same values, read back on use (collisions.StepScan._spill)."""
        system = self.system
        return replace(self, system=replace(system, right=on_disk(system.right), left=on_disk(system.left)))

    @property
    def vectors_in_memory(self) -> int:
        """Bytes of the eigenvectors held in memory (0 without vectors or spilled)."""
        system = self.system
        if system is None or system.right is None or is_on_disk(system.right):
            return 0
        return system.right.nbytes + system.left.nbytes

    def relabel(self, perm: Array) -> "Sample":
        """Labels permuted: new[i] = old[perm[i]]."""
        take = lambda a: None if a is None else a[perm]  # noqa: E731
        return replace(self, uid=object(), eigvals=self.eigvals[perm], status=self.status[perm],
                       excluded=self.excluded[perm], dlam=take(self.dlam), guard=take(self.guard),
                       gaps=take(self.gaps), known=take(self.known),
                       system=None if self.system is None else self.system.permuted(perm))

    @property
    def partial(self) -> bool:
        return self.known is not None

    @property
    def matrix_size(self) -> int:
        """Rows of the stability matrix (more than the labels when a spectral window is
        tracked)."""
        right = None if self.system is None else self.system.right
        return self.eigvals.size if right is None else right.shape[0]

    def slopes(self, segment) -> Array:
        """d lambda / dw on `segment` (w its coordinate from x_a to x_b, Segment.real):
        dlam L / (sigma . t) ds/dw; a root end's dlam is that derivative itself."""
        if self.root_end:
            return self.dlam
        return self.dlam * (segment.length / float(segment.sigma @ self.tangent)) * segment.ds_dw(self.s)


def matrix_derivative(problem: Problem, x: Array, t: Array, side: int = 0):
    """dA/dtau at x along the unit direction t, by finite differences of problem.stability_matrix
    with step h = problem.derivative_step(x): central (side 0, error O(h^2)), or one-sided
    second order towards side +1 / -1, (-3 A(x) + 4 A(x + h t) - A(x + 2h t)) / 2h, at the end
    of a step where the other side lies beyond a contact event. Dense or sparse as A is."""
    h = problem.derivative_step(x)
    A = lambda y: problem.stability_matrix(y[:-1], y[-1])  # noqa: E731
    if side == 0:
        return (A(x + h * t) - A(x - h * t)) * (0.5 / h)
    d = h * side
    return (A(x + d * t) * 4.0 - A(x) * 3.0 - A(x + 2.0 * d * t)) * (0.5 / d)


def pair_coupling(sample: Sample, I: Array, J: Array) -> Array:
    """m_ij m_ji for the label pairs (I[k], J[k]), m_ij = l_i^H (dA/dtau) r_j the coupling of
    eigenvalue j into i along the branch (in the sample's eigenbasis, with l_i^H r_i = 1); nan
    where the sample holds no vectors or matrix derivative for a label (certify.decoupled)."""
    out = np.full(I.size, np.nan, complex)
    system = sample.system
    if system is None or sample.dA is None or not I.size:
        return out
    labels = np.union1d(I, J)
    columns = labels if system.columns is None else system.columns[labels]
    have = columns >= 0
    if not have.any():
        return out
    right = system.right[:, columns[have]]
    m = system.left[columns[have]] @ (sample.dA @ right)
    at = np.full(labels.size, -1)
    at[have] = np.arange(int(have.sum()))
    i, j = at[np.searchsorted(labels, I)], at[np.searchsorted(labels, J)]
    ok = (i >= 0) & (j >= 0)
    out[ok] = m[i[ok], j[ok]] * m[j[ok], i[ok]]
    return out


def prediction_cost(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                    ds_ref: float, ds_new: float) -> Array:
    """|ref_i + ds_ref ref_dlam_i / 2 - (values_j - ds_new dlam_j / 2)|: how far eigenvalue j
    lies from the trapezoid prediction of reference i (ds_* = the step projected on each end's
    unit tangent). Built COST_ROWS rows at a time: the whole complex difference at n = m =
    3000 is a 144 MB temporary, and the cost took 0.18 s a call in a sweep of 1000 disks
    against 0.02 s in rows (the same values)."""
    return _distances(*_predictions(ref_values, ref_dlam, values, dlam, ds_ref, ds_new))


def _predictions(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                 ds_ref: float, ds_new: float) -> tuple[Array, Array]:
    """The two ends' trapezoid predictions, whose distances are prediction_cost."""
    return ref_values + 0.5 * ds_ref * ref_dlam, values - 0.5 * ds_new * dlam


def _distances(a: Array, z: Array) -> Array:
    """|a_i - z_j| (n, m), COST_ROWS rows at a time."""
    out = np.empty((a.size, z.size))
    for start in range(0, a.size, COST_ROWS):
        np.abs(a[start:start + COST_ROWS, None] - z[None, :], out=out[start:start + COST_ROWS])
    return out


COST_ROWS = 128
"""Rows of prediction_cost computed at once."""


def nearest_predicted(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                      ds_ref: float, ds_new: float) -> Array:
    """For each reference i, the j of least prediction_cost (i, j), the first such j where
    several tie: np.argmin(prediction_cost(...), axis=1) without the n x m matrix (at n = m =
    3000, 0.12 s and 144 MB a call). A k-d tree offers each i its NEAREST_CANDIDATES nearest
    predictions, whose costs are computed as prediction_cost does; a row whose candidates all
    lie within relative 1e-12 of the nearest (the tree's distances may differ from |z| in the
    last bit, so a farther candidate might tie), or any value that is not finite, is computed
    whole."""
    a, z = _predictions(ref_values, ref_dlam, values, dlam, ds_ref, ds_new)
    if z.size <= NEAREST_CANDIDATES or a.size == 0 or not (np.all(np.isfinite(a)) and np.all(np.isfinite(z))):
        return np.argmin(_distances(a, z), axis=1)
    distance, candidates = cKDTree(np.column_stack([z.real, z.imag])).query(
        np.column_stack([a.real, a.imag]), k=NEAREST_CANDIDATES)
    candidates = np.sort(candidates, axis=1)  # ties: the first index, as np.argmin
    nearest = candidates[np.arange(a.size), np.argmin(np.abs(a[:, None] - z[candidates]), axis=1)]
    open_rows = np.flatnonzero(distance[:, -1] <= distance[:, 0] * (1.0 + 1e-12))
    for i in open_rows:
        nearest[i] = np.argmin(np.abs(a[i] - z))
    return nearest


NEAREST_CANDIDATES = 4
"""Predictions nearest_predicted takes from its k-d tree for each reference."""


def predicted_match(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                    ds_ref: float, ds_new: float) -> Array:
    """Labels of `values` continuing `ref_values`: perm minimising sum_i of the
    prediction_cost of (i, perm(i)) (each its nearest where those are all different)."""
    nearest = nearest_predicted(ref_values, ref_dlam, values, dlam, ds_ref, ds_new)
    if np.unique(nearest).size == nearest.size:
        return nearest
    return linear_sum_assignment(prediction_cost(ref_values, ref_dlam, values, dlam, ds_ref, ds_new))[1]


def window_match(left: "Sample", right: "Sample", ds_left: float, ds_right: float,
                 dlam_left: Array, dlam_right: Array) -> Array:
    """Labels of the full window sample `right` continuing `left` (both hold the k eigenvalues
    nearest the window's centre sigma, Eigensystem.disc). An eigenvalue of `left` beyond the
    guard bands may have left the disc |lambda - sigma| < radius_right, and one of `right` may
    have entered it; the pairs (i, j) cost their prediction_cost, and label i leaving costs
    max(0, radius_right - |lambda_i + ds_left slope_i - sigma|) (how far its prediction at
    `right` would have to be off for it to lie outside that disc), eigenvalue j entering
    max(0, radius_left - |lambda_j - ds_right slope_j - sigma|) alike; a tracked eigenvalue
    (not excluded: in the window or its guard bands) never leaves or enters (the disc reaches
    beyond the guard bands, spectral_window.py). The assignment of least total cost (leaving
    and entering as dummy partners) keeps every eigenvalue present at both ends on its label;
    the labels left free take the entered eigenvalues (in the order of least prediction_cost):
    new eigenvalues on them, not continuations. A plain assignment over the pairs alone has
    no such choice: where the set changes it shifts a chain of labels along the real axis (on
    the line, all such chains cost about the same), relabelling eigenvalues in the window.
    dlam_*: the slopes that ds_* multiply (continuation_perm)."""
    nearest = nearest_predicted(left.eigvals, dlam_left, right.eigvals, dlam_right, ds_left, ds_right)
    if np.unique(nearest).size == nearest.size:
        return nearest
    cost = prediction_cost(left.eigvals, dlam_left, right.eigvals, dlam_right, ds_left, ds_right)
    (sigma, radius_left), (_, radius_right) = left.disc, right.disc
    k = cost.shape[0]
    leave = np.where(left.excluded, np.maximum(
        0.0, radius_right - np.abs(left.eigvals + ds_left * dlam_left - sigma)), np.inf)
    enter = np.where(right.excluded, np.maximum(
        0.0, radius_left - np.abs(right.eigvals - ds_right * dlam_right - sigma)), np.inf)
    full = np.full((2 * k, 2 * k), np.inf)
    full[:k, :k] = cost
    full[np.arange(k), k + np.arange(k)] = leave
    full[k + np.arange(k), np.arange(k)] = enter
    full[k:, k:] = 0.0
    cols = linear_sum_assignment(full)[1][:k]
    perm = cols.copy()
    gone, new = np.flatnonzero(cols >= k), np.setdiff1d(np.arange(k), cols)
    perm[gone] = new[linear_sum_assignment(cost[np.ix_(gone, new)])[1]]
    return perm


def continuation_perm(left: Sample, right: Sample, slopes: Optional[tuple[Array, Array]] = None) -> Array:
    """Labels of `right` continuing `left`: by prediction if both carry slopes, else by the
    nearest eigenvalue (spectra.match_eigenvalues). With a partial sample only the labels known
    at both are matched (the others keep theirs). Free disks' modes (excluded, outside a
    spectral window), as many at both ends, are matched among themselves in order of (Re, Im)
    (the optimal match of real values; identical free disks share their eigenvalues, and an
    assignment over all n labels took a third of a sweep at N = 400, eps = 0), the others by
    prediction among themselves. slopes: both ends' slopes per unit of the interval between
    them (verdicts.scaled_slopes), for an interval that ends at a root end (Sample.root_end),
    whose dlam is not along its tangent; default: dlam times the step projected on each
    end's tangent."""
    if left.dlam is None or right.dlam is None:
        return match_eigenvalues(left.eigvals, right.eigvals)
    dlam_left, dlam_right, ds_left, ds_right = _prediction_terms(left, right, slopes)
    common = known(left) & known(right)
    perm = np.arange(left.eigvals.size)
    free_l, free_r = common & left.excluded, common & right.excluded
    if left.guard is None and free_l.any() and free_r.any():
        by_l, by_r = _by_value(left, free_l), _by_value(right, free_r)
        i_l, i_r = order_match(left.eigvals[by_l], right.eigvals[by_r])
        perm[by_l[i_l]] = by_r[i_r]
        # a disk that joined the chain (or left it): its modes go with the chain's
        rest_l = np.union1d(np.flatnonzero(common & ~left.excluded), np.delete(by_l, i_l))
        rest_r = np.union1d(np.flatnonzero(common & ~right.excluded), np.delete(by_r, i_r))
    elif left.disc is not None and right.disc is not None and left.known is None and right.known is None:
        return window_match(left, right, ds_left, ds_right, dlam_left, dlam_right)
    else:
        rest_l = rest_r = np.flatnonzero(common)
    perm[rest_l] = rest_r[predicted_match(left.eigvals[rest_l], dlam_left[rest_l], right.eigvals[rest_r],
                                          dlam_right[rest_r], ds_left, ds_right)]
    return perm


def _prediction_terms(left: Sample, right: Sample, slopes: Optional[tuple[Array, Array]]):
    """(dlam_left, dlam_right, ds_left, ds_right) of continuation_perm's prediction."""
    if slopes is not None:
        return slopes[0], slopes[1], 1.0, 1.0
    step = right.x - left.x
    return left.dlam, right.dlam, float(step @ left.tangent), float(step @ right.tangent)


def claimed_outside(left: Sample, right: Sample, slopes: Optional[tuple[Array, Array]] = None) -> bool:
    """Whether the eigenvalue of the full sample `right` that best continues some label the
    partial sample `left` computed (least prediction_cost among all of right's labels) sits
    on a label that `left` did not compute. continuation_perm matches only the labels known at
    both, so it would give that label another eigenvalue, and the interval between the two
    would never be certified: a scan of 256 disks split it 70 times, each partial sample
    continuing the last one's labels, down to 7e-11 in strain (docs/continuation.md). slopes:
    as continuation_perm's."""
    dlam_left, dlam_right, ds_left, ds_right = _prediction_terms(left, right, slopes)
    mine = np.flatnonzero(known(left))
    nearest = nearest_predicted(left.eigvals[mine], dlam_left[mine], right.eigvals, dlam_right, ds_left, ds_right)
    return bool(np.any(~known(left)[nearest]))


def certified_labels(a: Sample, b: Sample, rho: float) -> Array:
    """Mask of the labels whose eigenvalue at b is certified to continue theirs at a over the
    straight step a -> b, by the label test of the fast detection (certify.inconsistent_labels:
    trapezoid defect |lambda_b - lambda_a - (d_a + d_b) / 2| <= rho min(gap_a, gap_b) + 2 thr,
    d = dlam |x_b - x_a|^2 / ((x_b - x_a) . t) the slope per unit of the step, as
    Sample.slopes on the step's segment). None certified where a tangent does not point along
    the step."""
    step = b.x - a.x
    along = [float(step @ smp.tangent) for smp in (a, b)]
    if min(along) <= 0.0:
        return np.zeros(a.eigvals.size, bool)
    d_a, d_b = (smp.dlam * (float(step @ step) / t) for smp, t in zip((a, b), along))
    return ~inconsistent_labels(a.eigvals, b.eigvals, d_a, d_b, a.gaps, b.gaps, rho,
                                2.0 * max(a.thr, b.thr))


def continued_labels(last: Optional[Sample], sample: Sample, tracked: Optional[Array],
                     rho: float) -> Array:
    """Branch.continued at the accepted point `sample` after the point `last` (None: the
    first): the labels the step's scan kept in the tracked set (ScanResult.tracked; None: not
    known) that are not excluded at `sample`, and those certified_labels certifies."""
    if last is None:
        return np.zeros(sample.eigvals.size, bool)
    continued = certified_labels(last, sample, rho)
    return continued if tracked is None else continued | (tracked & ~sample.excluded)


def order_match(a: Array, b: Array) -> tuple[Array, Array]:
    """The order-keeping match of two value lists, each sorted by (Re, Im), whose sizes differ
    by a few (the free disks' modes before and after a disk joins the chain): indices (i_a,
    i_b) of the matched pairs, minimising sum |a_i - b_j| over them, the surplus of the longer
    list left out. Dynamic programming over the k left out: O(n k) time, O(n k) memory, where
    an assignment over all n labels would take n^2 (at N = 3000, eps = 0: 1.9 GB)."""
    if a.size < b.size:
        i_b, i_a = order_match(b, a)
        return i_a, i_b
    k, m = a.size - b.size, b.size
    if k == 0:
        return np.arange(m), np.arange(m)
    shift = np.arange(k + 1)
    cost = np.full(k + 1, np.inf)
    cost[0] = 0.0  # cost[s]: best after the first i of a, s of them left out
    left_out = np.zeros((a.size, k + 1), bool)
    for i in range(a.size):
        j = i - shift  # the b that a[i] meets when s of a[:i] are left out
        keep = np.where((j >= 0) & (j < m), cost + np.abs(a[i] - b[np.clip(j, 0, max(m - 1, 0))]), np.inf)
        drop = np.concatenate([[np.inf], cost[:-1]])
        left_out[i] = drop < keep
        cost = np.minimum(keep, drop)
    pairs, s = [], k
    for i in range(a.size - 1, -1, -1):
        if left_out[i, s]:
            s -= 1
        else:
            pairs.append((i, i - s))
    pairs = np.array(pairs[::-1], dtype=int).reshape(-1, 2)
    return pairs[:, 0], pairs[:, 1]


def _by_value(sample: Sample, mask: Array) -> Array:
    """The labels in mask in order of (Re, Im) of their eigenvalues, ties in label order."""
    labels = np.flatnonzero(mask)
    return labels[np.lexsort((sample.eigvals.imag[labels], sample.eigvals.real[labels]))]


def known(sample: Sample) -> Array:
    """Mask of the labels computed at the sample (all of a full one)."""
    return np.ones(sample.eigvals.size, bool) if sample.known is None else sample.known


def label_gaps(values: Array, excluded: Array, guard: Optional[Array],
               disc: Optional[tuple[float, float]] = None) -> Array:
    """Each eigenvalue's distance to the nearest one its label could be confused with: among
    the free disks' modes and among the others apart (continuation_perm matches them apart, and
    a free disk's block is exactly decoupled, so a chain eigenvalue passing a free one is no
    encounter), else among all (nearest_gaps). With a spectral window's disc (sigma, radius)
    the eigenvalues beyond it are unknown: the gap is at most radius - |lambda - sigma|, a lower
    bound of the distance to any of them."""
    if disc is not None:
        sigma, radius = disc
        return np.minimum(nearest_gaps(values), radius - np.abs(values - sigma))
    if guard is not None or not excluded.any():
        return nearest_gaps(values)
    gaps = np.empty(values.size)
    for group in (excluded, ~excluded):
        gaps[group] = nearest_gaps(values[group])
    return gaps


def make_sample(s: float, x: Array, system: Eigensystem, rel_tol: float,
                reference: Optional[Sample] = None, tangent: Optional[Array] = None,
                dlam: Optional[Array] = None, dA=None) -> Sample:
    """Sample at s, labels continuing `reference` when given (by prediction when both carry
    slopes, else by nearest eigenvalue: spectra.match_eigenvalues); dA: the matrix derivative
    that gave the slopes."""
    values = np.asarray(system.values, dtype=complex)
    excluded = system.excluded if system.excluded is not None else np.zeros(values.size, bool)
    system = replace(system, values=values, excluded=excluded)
    gaps = None if dlam is None else label_gaps(values, excluded, system.guard, system.disc)
    sample = Sample(s, x, values, eigen_status(values, rel_tol), imag_threshold(values, rel_tol),
                    excluded, tangent, dlam, system if system.right is not None else None,
                    system.guard, gaps, disc=system.disc,
                    dA=dA if system.right is not None else None, band=system.band)
    return sample if reference is None else sample.relabel(continuation_perm(reference, sample))


def sample_at(problem: Problem, s: float, x: Array, rel_tol: float, reference: Optional[Sample],
              tangent: Optional[Array] = None, side: int = 0, eigensolver: Eigensolver = DEFAULT) -> Sample:
    """The sample of the branch point x by `eigensolver` (eigensolvers.py): eigenvalues only
    (tangent None), or the eigensystem with vectors and the slopes along `tangent`
    (matrix_derivative on `side`); that eigensystem refined from `reference`'s where the
    eigensolver can (Eigensolver.refined), else computed anew."""
    u, p = x[:-1], float(x[-1])
    if tangent is None:
        return make_sample(s, x, eigensolver.eigensystem(problem, u, p), rel_tol, reference)
    system = eigensolver.refined(problem, x, reference)
    if system is None:
        system = eigensolver.eigensystem(problem, u, p, vectors=True)
    dA = matrix_derivative(problem, x, tangent, side)
    return make_sample(s, x, system, rel_tol, reference, tangent, eigenvalue_slopes(system, dA), dA)


def partial_sample_at(problem: Problem, s: float, x: Array, left: Sample, clusters: list,
                      tangent: Array) -> Optional[Sample]:
    """A partial sample at the branch point x: only some labels (known at `left`) are
    computed. clusters: [(labels, sigma, k), ...]: each group of labels (int array) from the k
    eigenvalues of the stability matrix nearest the real shift sigma (nearest.py), with vectors
    and slopes along `tangent`; labels continue `left` by the trapezoid prediction
    (predicted_match, rectangular: the k computed eigenvalues are the candidates). The other
    labels hold nan (status, thr, excluded and guard flags and band: left's; they keep their status
    inside the interval being split, collisions.py). gaps: to the nearest of the k eigenvalues,
    at most the distance to the edge of the disc they cover. Vectors only for the labels
    computed (Eigensystem.columns).

    None when a disc does not cover its labels (every eigenvalue within twice its distance to
    a label's prediction must be among the k, so that the match saw every candidate a full
    spectrum would offer), when two groups claim the same eigenvalue, or when a shift-invert
    fails. The shift-inverts take the problem's StructuredMatrix: A, or its deflation."""
    structure = problem.stability_structure(x[:-1], float(x[-1]))
    A, deflated = structure.matrix, structure.deflated
    dA = matrix_derivative(problem, x, tangent)
    step = x - left.x
    ds_left, ds_new = float(step @ left.tangent), float(step @ tangent)
    n = left.eigvals.size
    eigvals, dlam_all = np.full(n, np.nan, complex), np.full(n, np.nan, complex)
    gaps, columns, rights, lefts = np.full(n, np.nan), np.full(n, -1), [], []
    for labels, sigma, k in clusters:
        book("spectra_partial")
        try:
            system, radius = nearest_eigensystem(A, sigma, k, deflated)
        except ShiftInvertFailed:
            return None
        dlam = eigenvalue_slopes(system, dA)
        ref = left.eigvals[labels] + 0.5 * ds_left * left.dlam[labels]
        cols = linear_sum_assignment(np.abs(ref[:, None] - (system.values - 0.5 * ds_new * dlam)[None, :]))[1]
        values = system.values[cols]
        predicted = ref + 0.5 * ds_new * dlam[cols]
        if np.any(np.abs(predicted - sigma) + 2.0 * np.abs(values - predicted) >= radius):
            return None
        distance = np.abs(values[:, None] - system.values[None, :])
        distance[np.arange(cols.size), cols] = np.inf
        eigvals[labels], dlam_all[labels] = values, dlam[cols]
        gaps[labels] = np.minimum(distance.min(axis=1), radius - np.abs(values - sigma))
        columns[labels] = np.arange(cols.size) + sum(len(rows) for rows in lefts)
        rights.append(system.right[:, cols])
        lefts.append(system.left[cols])
    known = ~np.isnan(eigvals)
    values = eigvals[known]
    if np.any(nearest_gaps(values) <= left.thr):  # one eigenvalue matched to two labels
        return None
    status = left.status.copy()
    status[known] = status_at(values, left.thr)
    excluded = left.excluded.copy()
    guard = None if left.guard is None else left.guard.copy()
    return Sample(s, x, eigvals, status, left.thr, excluded, tangent, dlam_all,
                  Eigensystem(eigvals, np.hstack(rights), np.vstack(lefts), excluded, guard, columns,
                              band=left.band),
                  guard, gaps, known, dA=dA, band=left.band)
