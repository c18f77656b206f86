"""Every eigenpair of a periodic block-tridiagonal matrix refined from guesses (a nearby
sample's eigenpairs): each pair alone by two-sided Rayleigh quotient iteration (rayleigh.py),
then the pairs that did not converge, or whose error discs meet, again together with their
neighbours (refinement_groups), and a pair found twice once more with the others deflated
(refine_eigenpairs). The certificate of the result is refinement.py's.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from diskfriction.continuation.linalg.block_tridiagonal import PeriodicBlocks
from diskfriction.continuation.linalg.solves import row_norms
from diskfriction.continuation.spectra.rayleigh import pivoted_rqi, refine_cluster, rqi_many

Array = np.ndarray


def close_pairs(points: Array, radius: float) -> tuple[Array, Array]:
    """Index pairs (i < j) of the complex points within `radius` of each other (a k-d tree)."""
    if points.size < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    pairs = cKDTree(np.column_stack([points.real, points.imag])).query_pairs(radius, output_type="ndarray")
    return pairs[:, 0], pairs[:, 1]


NEAR_REAL = 1e-9
"""A guess without a conjugate partner whose imaginary part is within this many times the
spectral radius (the complex status threshold, tracking.py) is refined in real arithmetic, from
its vectors made real (Guesses.made_real): complex arithmetic leaves a real eigenvalue's vectors
with a complex phase and its value with an imaginary part of rounding size, and without this
the pair would stay in complex arithmetic, four times dearer, at every later refinement."""

LARGEST_CLUSTER = 16
"""Largest group of pairs refined again together (refine_eigenpairs, refinement_groups); a
larger one is left as it is, to the certificate."""

PARTNERS = 2
"""Pairs whose guesses are nearest a pair still above the tolerance, refined again with it
(refinement_groups). With one, the two real guesses of a pair born inside the step (a complex
pair now) may each be grouped with a third eigenvalue nearer it than its partner, and neither
group spans the pair."""

PARTNER_REACH = 4.0
"""A partner beyond the nearest joins only within this many times the nearest one's distance
(a far one would only slow the group's shifted iteration): the two members of the pairs above
were 1.5 to 2.9 times farther apart than the nearest third guess."""


def refine_eigenpairs(blocks: PeriodicBlocks, values: Array, right: Array, left: Array,
                      iterations: int = 6, tol: float = 0.0, columns: Optional[Array] = None
                      ) -> tuple[Array, Array, Array, Array]:
    """Every eigenpair of `blocks`' matrix refined from the guesses: values (n,), right vectors
    as columns and left vectors as rows l_i^H (l_i^H r_i = 1: tracking.Eigensystem's layout) in
    the matrix's own order (PeriodicBlocks.order takes block unknowns to it), pair i's in column
    (and row) columns[i] (None: i). Each pair alone by at most `iterations` two-sided Rayleigh
    quotient steps (fewer once its residual is <= tol): in real arithmetic where guess and
    vectors are real, the lower member of a complex-conjugate pair as the conjugate of the upper
    one. Any pair still above tol gets `iterations` more steps alone with a pivoted banded LU
    (pivoted_rqi; again a lower member as its upper one's conjugate). Pairs whose error discs
    kappa_i rho_i then meet (a degenerate or nearly degenerate eigenvalue: alone, two pairs may
    land on one eigenpair, or on vectors of one eigenspace that are not biorthogonal), and each
    pair still above tol with the pair whose guess is nearest (refinement_groups), are refined
    again together from their guesses, in groups of at most LARGEST_CLUSTER (refine_cluster:
    one shift, the projected problem). Where two pairs still converged to one eigenpair
    (_found_twice), one of them starts again from its guess with the converged pairs near it
    deflated, for twice the iterations (up to ROUNDS times). The guesses are read, never copied
    whole. Returns new (values, right, left, residual) in the matrix's order, pair i in column
    and row i: |r_i| = 1, l_i^H r_i = 1, residual_i = |A r_i - lambda_i r_i| (inf where a
    factorization failed)."""
    n = values.size
    every = np.arange(n)
    guess = Guesses(np.asarray(values, np.complex128), right, left,
                    every if blocks.order is None else np.asarray(blocks.order),
                    every if columns is None else np.asarray(columns))
    out = RefinedPairs.empty(guess.rows)
    vectors_real = ~np.any(right.imag, axis=0) & ~np.any(left.imag, axis=1)
    real = every[(guess.values.imag == 0.0) & vectors_real[guess.source]]
    upper, lower = conjugate_pairs(guess.values, np.setdiff1d(every, real))
    single = np.setdiff1d(np.setdiff1d(every, real), np.concatenate([upper, lower]))
    out.rqi(blocks, guess, real, np.full(real.size, -1), iterations, tol, real=True)
    # a real eigenvalue whose vectors carry a complex phase (left by complex arithmetic: a
    # pair that died, a group, the pivoted LU, a repair) is refined in real arithmetic too
    near_real = single[np.abs(guess.values[single].imag) <= NEAR_REAL * np.abs(guess.values).max()]
    if near_real.size:
        out.rqi(blocks, guess.made_real(near_real), near_real, np.full(near_real.size, -1), iterations, tol,
                real=True)
        single = np.setdiff1d(single, near_real)
    # a real matrix: the lower member of a complex pair is the upper one's conjugate
    out.rqi(blocks, guess, np.concatenate([upper, single]), np.concatenate([lower, np.full(single.size, -1)]),
            iterations, tol)
    out.residual[lower], out.kappa[lower] = out.residual[upper], out.kappa[upper]
    rough = np.flatnonzero(out.residual > tol)  # a far guess, or pivot growth in the blocks' LU
    rough = rough[~np.isin(rough, lower)]  # a lower member follows its upper one
    if rough.size:
        started = np.isfinite(out.residual[rough])  # from the guess where the blocks' LU failed
        v, r, lft = out.take(rough)
        v[~started], r[:, ~started], lft[~started] = guess.take(rough[~started])
        out.put(rough, v, r, lft, pivoted_rqi(blocks, v, r, lft, iterations, tol), better=True)
        mirrored = np.isin(upper, rough)
        v, r, lft = out.take(upper[mirrored])
        out.put(lower[mirrored], v.conj(), r.conj(), lft.conj(), out.residual[upper[mirrored]])
    for group in refinement_groups(guess.values, out.values, out.residual, out.kappa, tol):
        if group.size <= LARGEST_CLUSTER:
            v, r, lft = guess.take(group)
            res = refine_cluster(blocks, v, r, lft, iterations, tol)
            if np.all(np.isfinite(res)):  # else left as it was
                # the whole group where it converged, else only the members it improved
                out.put(group, v, r, lft, res, better=bool(np.any(res > tol)))
    for _ in range(ROUNDS):
        twice = _found_twice(guess.values, out)
        for p in twice:
            # from its guess again, the pairs found near it deflated: it finds the eigenvalue lost
            near = np.argsort(np.abs(out.values - guess.values[p]))
            near = near[(near != p) & np.isfinite(out.residual[near])][:DEFLATED]
            v, r, lft = guess.take(np.array([p]))
            _, known_r, known_l = out.take(near)
            out.put(np.array([p]), v, r, lft, pivoted_rqi(blocks, v, r, lft, 2 * iterations, tol, (known_r, known_l)))
        if not twice.size:
            break
    return out.values, out.right, out.left, out.residual


@dataclass(frozen=True)
class Guesses:
    """The guesses refine_eigenpairs starts from: values (n,), right (n, m) columns and left (m,
    n) rows in the matrix's order, rows[t] the row of block unknown t, source[i] pair i's
    column of right and row of left."""

    values: Array
    right: Array
    left: Array
    rows: Array
    source: Array

    def made_real(self, pairs: Array) -> "Guesses":
        """The guesses with the pairs' values real and their vectors real: each rotated by the
        phase of its largest entry and its real part taken (a real eigenvalue's vectors are
        real up to a phase), as new columns and rows that source points to."""
        cols = self.source[pairs]
        right, left = self.right[:, cols], self.left[cols]
        right = _unphased(right.T).T
        left = _unphased(left)
        source = self.source.copy()
        source[pairs] = np.arange(pairs.size)
        values = self.values.copy()
        values[pairs] = values[pairs].real
        return Guesses(values, np.asfortranarray(right), np.ascontiguousarray(left), self.rows, source)

    def take(self, pairs: Array) -> tuple[Array, Array, Array]:
        """Copies of the pairs' (values, right columns, left rows) in block order, complex."""
        cols = self.source[pairs]
        return (self.values[pairs].copy(), self.right[np.ix_(self.rows, cols)].astype(np.complex128),
                self.left[np.ix_(cols, self.rows)].astype(np.complex128))


def _unphased(rows: Array) -> Array:
    """The real parts of the rows (k, n) each rotated by the phase of its largest entry."""
    rows = np.asarray(rows, np.complex128)
    top = rows[np.arange(rows.shape[0]), np.argmax(np.abs(rows), axis=1)]
    return (rows * np.exp(-1j * np.angle(top))[:, None]).real


@dataclass(frozen=True)
class RefinedPairs:
    """refine_eigenpairs' result as it is built: values (n,), right (n, n), left (n, n) in the
    matrix's order (pair i in column and row i), residual and kappa = |l_i| (nan where none)."""

    values: Array
    right: Array
    left: Array
    residual: Array
    kappa: Array
    rows: Array

    @classmethod
    def empty(cls, rows: Array) -> "RefinedPairs":
        n = rows.size
        # the right vectors column by column, the left ones row by row, as LAPACK leaves them:
        # each pair's reads and writes are contiguous. Not zeroed: rqi_many writes every
        # column and row (refine_eigenpairs gives it every pair), and zeroing 288 MB at
        # N = 1000 cost as much as writing them
        return cls(np.zeros(n, np.complex128), np.empty((n, n), np.complex128, order="F"),
                   np.empty((n, n), np.complex128), np.full(n, np.inf), np.full(n, np.nan), rows)

    def rqi(self, blocks: PeriodicBlocks, guess: Guesses, pairs: Array, mirror: Array, iterations: int,
            tol: float, real: bool = False) -> None:
        """rqi_many on `pairs` from their guesses, written here (with each conjugate into its
        mirror's column and row, mirror -1: none); real: in real arithmetic."""
        values, right, left = guess.values[pairs], guess.right, guess.left
        if real:
            values, right, left = values.real.copy(), right.real, left.real
        else:
            right, left = np.asarray(right, np.complex128), np.asarray(left, np.complex128)
        self.residual[pairs], self.kappa[pairs] = rqi_many(
            blocks.diag, blocks.lower, blocks.upper, values, right, left, self.rows, guess.source[pairs], pairs,
            mirror, self.values, self.right, self.left, iterations, tol)

    def take(self, pairs: Array) -> tuple[Array, Array, Array]:
        """Copies of the pairs' (values, right columns, left rows) in block order."""
        return (self.values[pairs].copy(), self.right[np.ix_(self.rows, pairs)],
                self.left[np.ix_(pairs, self.rows)])

    def put(self, pairs: Array, values: Array, right: Array, left: Array, residual: Array,
            better: bool = False) -> None:
        """The pairs set to (values, right, left) in block order with their residuals; better:
        only those whose residual is below the present one."""
        keep = residual < self.residual[pairs] if better else np.ones(pairs.size, bool)
        pairs = pairs[keep]
        self.values[pairs], self.residual[pairs] = values[keep], residual[keep]
        self.right[np.ix_(self.rows, pairs)] = right[:, keep]
        self.left[np.ix_(pairs, self.rows)] = left[keep]
        self.kappa[pairs] = row_norms(left[keep])


def refinement_groups(guess: Array, values: Array, residual: Array, kappa: Array, tol: float) -> list[Array]:
    """The groups (two or more, ascending) of pairs to refine again together: converged pairs
    (rho_i <= tol) linked by meeting error discs |z - lambda_i| <= kappa_i rho_i, and each pair
    still above tol linked to the pair whose guess is nearest its own, and to the others of
    its PARTNERS nearest within PARTNER_REACH times that distance (near a collision two
    eigenvalues are nearly defective, and alone their Rayleigh iterations converge slowly or
    land on one eigenvalue; together they span an invariant subspace that is well
    conditioned)."""
    n = values.size
    converged = residual <= tol  # a rough pair's wide disc would link it to pairs it does not concern
    i, j = touching(values, error_bounds(np.where(converged, residual, np.inf), kappa))
    keep = converged[i] & converged[j]
    rough = np.flatnonzero(~converged)
    if rough.size and n > 1:
        points = np.column_stack([guess.real, guess.imag])
        k = min(PARTNERS + 1, n)
        distance, nearest = (a.reshape(rough.size, k) for a in cKDTree(points).query(points[rough], k=k))
        links = nearest != rough[:, None]  # ties: not itself
        first = np.where(links[:, 0], distance[:, 0], distance[:, 1])  # the nearest other guess's
        links &= distance <= PARTNER_REACH * first[:, None]
        i = np.concatenate([i[keep], np.repeat(rough, k)[links.ravel()]])
        j = np.concatenate([j[keep], nearest[links]])
    else:
        i, j = i[keep], j[keep]
    if not i.size:
        return []
    graph = sp.coo_array((np.ones(i.size), (i, j)), shape=(n, n))
    root = connected_components(graph, directed=False)[1]
    members = np.argsort(root, kind="stable")
    groups = np.split(members, np.flatnonzero(np.diff(root[members])) + 1)
    return [g for g in groups if g.size > 1]


def error_bounds(residual: Array, kappa: Array) -> Array:
    """kappa_i rho_i, each eigenvalue's first-order error bound (kappa_i = |l_i| with |r_i| = 1,
    l_i^H r_i = 1; rho_i the residual); 0 where the pair did not converge (rho_i inf)."""
    done = np.isfinite(residual)
    return np.where(done, kappa * np.where(done, residual, 0.0), 0.0)


DEFLATED = 16
"""Pairs deflated when a pair found twice is refined again (refine_eigenpairs): the converged
pairs nearest its guess."""

ROUNDS = 3
"""Rounds of refining again the pairs found twice (one may land on a third pair's eigenvalue)."""


def _found_twice(guess: Array, out: RefinedPairs) -> Array:
    """Of every two pairs converged to one eigenpair (meeting discs kappa rho, |l_i^H r_j| >
    1/2: one eigenvalue found twice, another lost), the one whose guess is farther from it."""
    values = out.values
    i, j, cross = meeting_discs(values, error_bounds(out.residual, out.kappa), out.right, out.left)
    i, j = i[cross > 0.5], j[cross > 0.5]
    farther = np.where(np.abs(guess[i] - values[i]) >= np.abs(guess[j] - values[j]), i, j)
    return np.unique(farther)


def conjugate_pairs(values: Array, candidates: Array) -> tuple[Array, Array]:
    """(upper, lower): the candidates with Im > 0 and, for each, the candidate whose value is
    nearest its conjugate, where that match is mutual (each is the other's nearest) and
    nearer than any other candidate; the others are in neither."""
    if candidates.size < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    z = values[candidates]
    distance = np.abs(z[:, None] - z.conj()[None, :])  # |z_a - conj(z_b)|
    nearest = np.argmin(distance, axis=1)
    mutual = (nearest[nearest] == np.arange(z.size)) & (z.imag > 0) & (z[nearest].imag < 0)
    return candidates[mutual], candidates[nearest[mutual]]


def touching(values: Array, bounds: Array) -> tuple[Array, Array]:
    """Index pairs (i < j) whose discs |z - values_i| <= bounds_i meet."""
    values, bounds = np.asarray(values, np.complex128), np.asarray(bounds, float)
    i, j = close_pairs(values, 2.0 * float(np.max(bounds, initial=0.0)))
    meet = np.abs(values[i] - values[j]) <= bounds[i] + bounds[j]
    return i[meet], j[meet]


def meeting_discs(values: Array, bounds: Array, right: Array, left: Array) -> tuple[Array, Array, Array]:
    """(i, j, cross): the pairs whose error discs |z - values_i| <= bounds_i meet (touching),
    and for each the larger of |l_i^H r_j| and |l_j^H r_i| (l_i^H r_i = 1): near 1 where both
    converged to one eigenpair, near 0 for two eigenpairs of a semisimple eigenvalue."""
    i, j = touching(values, bounds)
    cross = np.maximum(np.abs(np.sum(left[i] * right[:, j].T, axis=1)),
                       np.abs(np.sum(left[j] * right[:, i].T, axis=1)))
    return i, j, cross
