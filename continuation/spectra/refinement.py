"""Full spectra by eigenpair continuation: the eigensystem at a branch point refined from a
nearby sample's instead of a dense O(n^3) decomposition (eigensolvers.RefinedSpectra).

Where the stability matrix is periodic block-tridiagonal (its StructuredMatrix's block layout:
a ring of cells, each coupled to its two neighbours), every eigenpair (lambda_i, r_i, l_i) of the
reference sample is carried to the new point x:

    predicted   lambda_i + dlambda_i/ds ds,   ds = (x - x_ref) . t_ref  (the slopes along the
                reference's tangent; the reference's own value where it has no slopes),
    refined     by two-sided Rayleigh quotient iteration on the O(N b^3) shifted solves of
                linalg/block_tridiagonal.py (rayleigh.py), each pair alone, then again
                together with its neighbours where it did not converge or its error disc
                meets another's (eigenpairs.refinement_groups),

O(n^2 b^2) for the n = N b pairs against LAPACK's O(n^3).

The result is used only when it is certified. Where it is not, the pairs that fail (a
residual above RESIDUAL R, a pair found twice, a nearly defective pair among meeting discs)
are repaired by shift-invert near their guesses (repaired: ARPACK's k eigenpairs nearest a
real shift on the sparse matrix, nearest.py, those not held by a certified pair given to the
failing ones) and the whole is certified again; otherwise (None) the caller takes the dense
spectrum. The work ledger counts the outcomes (solves.Work: spectra_refined, of them
refinements_repaired, and refinements_declined). Certificate, with rho_i = |A r_i - lambda_i
r_i| (|r_i| = 1), kappa_i = |l_i| |r_i| / |l_i^H r_i| and R = max|lambda| of the reference:
  - every rho_i <= RESIDUAL R (a backward error, relative to the spectral radius);
  - the discs |z - lambda_i| <= kappa_i rho_i (the first-order bound of each eigenvalue's error,
    Wilkinson) are pairwise disjoint: n disjoint discs each hold a different eigenvalue, so the
    n refined values are the whole spectrum, none found twice and none lost. Discs may meet
    only where they belong to a semisimple degenerate eigenvalue: members well conditioned
    (kappa <= KAPPA) with biorthogonal vectors (|l_i^H r_j| <= BIORTHOGONAL), which span as
    many dimensions as there are members (degenerate_only);
  - the trace identities sum lambda_i = tr A and sum lambda_i^2 = tr A^2 (O(N b^2) from the
    blocks) hold within TRACE times their bounds sum kappa_i rho_i + n eps R and sum 2 |lambda_i|
    kappa_i rho_i + n eps R^2.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Optional

import numpy as np

from scipy.optimize import linear_sum_assignment
from scipy.sparse.csgraph import connected_components
import scipy.sparse as sp

from diskfriction.continuation.linalg.block_tridiagonal import PeriodicBlocks
from diskfriction.continuation.linalg.solves import book, row_norms
from diskfriction.continuation.spectra.eigenpairs import close_pairs, meeting_discs, refine_eigenpairs
from diskfriction.continuation.spectra.nearest import ShiftInvertFailed, nearest_eigensystem
from diskfriction.continuation.spectra.rayleigh import polish
from diskfriction.continuation.spectra.tracking import Eigensystem, SpectraDevice, on_gpu

if TYPE_CHECKING:  # pragma: no cover
    from diskfriction.continuation.detection.samples import Sample

Array = np.ndarray

REFINE_FROM = 600
"""Smallest n at which a full spectrum with vectors is refined from the previous sample rather
than decomposed (not where the spectra run on a GPU, tracking.on_gpu, which is faster still):
below it LAPACK's spectra are cheap and the refinement's overhead and its declined samples
weigh more (benchmarks/scaling.py --refine-from compares the two)."""

ITERATIONS = 6
"""Rayleigh quotient steps at most per pair (cubic convergence: 2 or 3 suffice for a step of
a continuation)."""

RESIDUAL = 1e-12
"""Largest residual rho_i accepted, relative to the spectral radius."""

TOLERANCE = 5e-13
"""Residual, relative to the spectral radius, at which a pair's Rayleigh quotient iteration
stops (eigenpairs.refine_eigenpairs: below it a pair is converged, above it it goes on
to the pivoted LU and the groups): half of RESIDUAL. Most pairs converge far below it (median
3e-15 R); it decides the pairs whose iteration stalls in the blocks' LU (pivot growth) at 1e-13
to 1e-12 R, which go on to the pivoted LU only above it."""

TRACE = 10.0
"""Slack of the trace identities over their error bounds."""

KAPPA = 100.0
"""Largest condition number of a member of meeting discs (degenerate_only): a generic
eigenvalue of the chain has kappa 1 to 10, a pair near a collision a diverging one."""

BIORTHOGONAL = 1e-8
"""Largest |l_i^H r_j| (l_i^H r_i = 1) of two members of meeting discs (degenerate_only)."""

REPAIR_LINK = 1e-4
"""Failing pairs whose guesses lie within this many R of each other are repaired by one
shift-invert (repaired)."""

REPAIR_EXTRA = 4
"""Eigenpairs a repair's shift-invert computes beyond the failing pairs and the certified ones
near them (repaired)."""

REPAIR_TRIES = 3
"""Shift-inverts per cluster of failing pairs at most, k doubled each time, until it holds as
many eigenvalues that no certified pair holds as the cluster has pairs (repaired)."""

POLISH = 1e-13
"""Residual (relative to R) above which a repaired pair gets two pivoted Rayleigh quotient steps
(rayleigh.pivoted_rqi): ARPACK's tolerance is relative to the shift-inverted
eigenvalues, and a pair far from the shift came out at 1.07e-12 R, above RESIDUAL (the chain
of 400 disks)."""

EPS = np.finfo(float).eps


def refinable(reference: Optional[Sample], refine_from: Optional[int] = None,
              device: Optional[SpectraDevice] = None) -> bool:
    """Whether a full sample may be refined from `reference`: n >= refine_from (None:
    REFINE_FROM), dense spectra on the CPU (on `device`, None: spectra_on's), and a full
    reference with every eigenvalue's vectors and none excluded (no decoupled or gauge mode,
    no spectral window)."""
    if reference is None or reference.partial or reference.system is None:
        return False
    n = reference.eigvals.size
    system = reference.system
    least = REFINE_FROM if refine_from is None else refine_from
    return (n >= least and not on_gpu(n, device) and system.disc is None and system.guard is None
            and (system.columns is None or bool(np.all(system.columns >= 0)))
            and not np.any(reference.excluded))


def refined_eigensystem(blocks: PeriodicBlocks, x: Array, reference: Sample) -> Optional[Eigensystem]:
    """The eigensystem of the stability matrix at x (= (u, p)), `blocks`, refined from
    `reference`'s (refinable), in the reference's label order, vectors normalised to |r_i| = 1,
    l_i^H r_i = 1; None where the result is not certified (module docstring). Booked as
    spectra_refined or refinements_declined."""
    old = reference.system
    values = np.asarray(reference.eigvals, complex)
    scale = float(np.abs(values).max()) or 1.0
    move = np.zeros(values.size, complex)
    if reference.dlam is not None and reference.tangent is not None:
        move = reference.dlam * float((x - reference.x) @ reference.tangent)
    guess = values + move
    refined = refine_eigenpairs(blocks, guess, old.right, old.left, ITERATIONS, TOLERANCE * scale,
                                old.columns)  # columns: label i's vectors
    system = certified(blocks, *refined, scale)
    if system is None:
        fixed = repaired(blocks, guess, *refined, scale)
        system = None if fixed is None else certified(blocks, *fixed, scale)
        if system is None:
            book("refinements_declined")
            return None
        book("refinements_repaired")
    book("spectra_refined")
    return Eigensystem(system.values, system.right, system.left, np.zeros(values.size, bool))


def certified(blocks, values: Array, right: Array, left: Array, residual: Array,
              scale: float) -> Optional[Eigensystem]:
    """Eigensystem(values, right, left) if it passes the certificate (module docstring) for the
    matrix of `blocks`, with spectral radius `scale`; else None."""
    if not np.all(residual <= RESIDUAL * scale):  # inf: a factorization failed
        return None
    kappa = row_norms(left)  # |l_i| |r_i| / |l_i^H r_i| with |r_i| = 1, l_i^H r_i = 1
    bound = kappa * residual
    if not degenerate_only(*meeting_discs(values, bound, right, left), kappa):
        return None
    trace, trace2 = blocks.traces()
    n = values.size
    if abs(values.sum() - trace) > TRACE * (bound.sum() + n * EPS * scale):
        return None
    if abs((values ** 2).sum() - trace2) > TRACE * (2.0 * (np.abs(values) * bound).sum() + n * EPS * scale ** 2):
        return None
    return Eigensystem(values, right, left)


def degenerate_only(i: Array, j: Array, cross: Array, kappa: Array) -> bool:
    """Whether the pairs (i, j) whose discs meet (eigenpairs.meeting_discs) are all
    members of a semisimple degenerate eigenvalue (a ring's standing waves, a mode repeated by
    symmetry; not_degenerate); their discs then hold as many eigenvalues as they are."""
    return not np.any(not_degenerate(i, j, cross, kappa))


def not_degenerate(i: Array, j: Array, cross: Array, kappa: Array) -> Array:
    """For each meeting pair (i, j): whether it is not two members of a semisimple degenerate
    eigenvalue, which are well conditioned (kappa <= KAPPA) with biorthogonal vectors, cross =
    max(|l_i^H r_j|, |l_j^H r_i|) <= BIORTHOGONAL. A pair found twice (r_i = r_j) fails the
    second, a pair near a collision (kappa diverging) the first."""
    return (kappa[i] > KAPPA) | (kappa[j] > KAPPA) | (cross > BIORTHOGONAL)


def failing(values: Array, right: Array, left: Array, residual: Array, scale: float) -> Array:
    """The pairs (ascending) that fail the certificate's first two tests by themselves: a
    residual above RESIDUAL scale, or a member of meeting discs (those of the pairs within
    the residual) that are not a degenerate eigenvalue's (not_degenerate)."""
    rough = ~(residual <= RESIDUAL * scale)
    kappa = row_norms(left)
    i, j, cross = meeting_discs(values, kappa * np.where(rough, 0.0, residual), right, left)
    bad = not_degenerate(i, j, cross, kappa)
    return np.union1d(np.flatnonzero(rough), np.concatenate([i[bad], j[bad]]))


def left_over(found: Array, values: Array, held: Array, near: Array, sigma: float, radius: float) -> Array:
    """The indices of the eigenvalues `found` (the k nearest sigma, within radius) that no held
    (certified) pair holds: each held pair inside the disc is matched to one of them (least
    total distance), and holds it if it lies within near (10 kappa rho + RESIDUAL R: its own
    value against ARPACK's). The farthest eigenvalue found lies on the disc's edge, so a held
    pair within near outside it counts as inside."""
    inside = np.flatnonzero(held & (np.abs(values - sigma) <= radius + near))
    a, b = linear_sum_assignment(np.abs(values[inside][:, None] - found[None, :]))
    same = np.abs(values[inside[a]] - found[b]) <= near[inside[a]]
    return np.setdiff1d(np.arange(found.size), b[same])


def repaired(blocks, guess: Array, values: Array, right: Array, left: Array, residual: Array,
             scale: float) -> Optional[tuple[Array, Array, Array, Array]]:
    """The refinement (values, right, left, residual: refine_eigenpairs' result in the matrix's
    order) with its failing pairs (failing) replaced by shift-invert, in place, or None where
    it cannot be (none fail and yet the certificate refused, a shift-invert failed, too few
    eigenvalues found). The failing pairs are clustered by their guesses (REPAIR_LINK R apart
    at most); for each cluster, ARPACK's k eigenpairs nearest sigma, the real part of the mean
    guess (nearest.nearest_eigensystem on the sparse matrix, both vectors; k: the certified
    pairs within twice the cluster's spread of sigma, the cluster's, and REPAIR_EXTRA), are
    matched first to the certified pairs inside their disc (left_over); those left over (k
    doubled, up to REPAIR_TRIES runs, until as many are left as the cluster has pairs) go to
    the cluster's pairs by least distance from the guesses, polished where ARPACK left them
    above POLISH R (rayleigh.polish). Where the failing
    pairs were nearly defective pairs that the Rayleigh iterations could not split, or a pair
    found twice, shift-invert sees the eigenvalues themselves. The result is certified again
    as a whole by the caller: a wrong match leaves two pairs on one eigenvalue, whose discs
    meet."""
    bad = failing(values, right, left, residual, scale)
    if bad.size == 0:
        return None
    A = blocks.original()
    held = np.ones(values.size, bool)
    held[bad] = False
    bound = row_norms(left) * np.where(held, residual, 0.0)
    i, j = close_pairs(guess[bad], REPAIR_LINK * scale)
    cluster = connected_components(sp.coo_array((np.ones(i.size), (i, j)), shape=(bad.size, bad.size)),
                                   directed=False)[1]
    for c in range(cluster.max() + 1):
        members = bad[cluster == c]
        sigma = float(guess[members].real.mean())
        reach = 2.0 * float(np.abs(guess[members] - sigma).max())
        k = int(np.count_nonzero(held & (np.abs(values - sigma) <= reach))) + members.size + REPAIR_EXTRA
        for _ in range(REPAIR_TRIES):
            if k >= values.size - 1:
                return None
            try:
                found, radius = nearest_eigensystem(A, sigma, k)
            except ShiftInvertFailed:
                return None
            free = left_over(found.values, values, held, 10.0 * bound + RESIDUAL * scale, sigma, radius)
            if free.size >= members.size:
                break
            k *= 2
        else:
            return None
        free = free[linear_sum_assignment(np.abs(guess[members][:, None] - found.values[free][None, :]))[1]]
        v, r, lft = found.values[free], found.right[:, free], found.left[free]
        norm = np.linalg.norm(r, axis=0)
        r, lft = r / norm, lft * norm[:, None]  # |r| = 1, l^H r = 1
        res = np.linalg.norm(A @ r - r * v, axis=0)
        rough = np.flatnonzero(res > POLISH * scale)
        if rough.size:  # ARPACK's tolerance is relative to the shift-inverted values
            res[rough] = polish(blocks, rough, v, r, lft, res[rough], POLISH * scale)
        values[members], right[:, members], left[members], residual[members] = v, r, lft, res
        held[members] = True
        bound[members] = row_norms(lft) * residual[members]
    return values, right, left, residual
