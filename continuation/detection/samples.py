"""Samples: branch points with their tracked spectra, the data collision detection works on.

A sample is a point x = (u, p) of the branch at coordinate s of the step's segment (segment.py),
its eigenvalues in tracked order (label i continues label i of the neighbouring sample), their
status (tracking.eigen_status) and, for the fast detection, their slopes along the branch:

    d lambda_i / d tau = l_i^H (dA/dtau) r_i,      tau the arclength along the unit tangent t,

from the normalised left and right eigenvectors (tracking.eigenvalue_slopes), with dA/dtau
from finite differences of the stability matrix along t (matrix_derivative). On a segment of
length L with unit normal sigma, x'(s) = t L / (sigma . t), so d lambda / ds follows (slopes).
The labels of a new sample continue its neighbour's by these slopes (labels.py:
continuation_perm).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Optional

import numpy as np
from scipy.optimize import linear_sum_assignment

from diskfriction.continuation.detection.certify import inconsistent_labels, nearest_gaps
from diskfriction.continuation.detection.labels import continuation_perm
from diskfriction.continuation.linalg.solves import book
from diskfriction.continuation.spectra.nearest import ShiftInvertFailed, nearest_eigensystem
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.spectra.eigensolvers import DEFAULT, Eigensolver
from diskfriction.continuation.detection.spill import is_on_disk, on_disk
from diskfriction.continuation.spectra.tracking import (Eigensystem, eigen_status, eigenvalue_slopes, imag_threshold,
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
    slopes, else by nearest eigenvalue: tracking.match_eigenvalues); dA: the matrix derivative
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
