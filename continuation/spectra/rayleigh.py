"""Two-sided Rayleigh quotient iteration on a periodic block-tridiagonal matrix (Ostrowski;
Parlett 1974), the kernel of the eigenpair refinement (eigenpairs.py, refinement.py). From a
guess (lambda, r, l) with l^H r = 1:

    M = A - lambda I,   r <- M^-1 r,   l <- M^-H l,   scale so |r| = 1 and l^H r = 1,
    lambda <- l^H A r,

cubically convergent for a simple eigenvalue. Each iteration is one factorization and two
solves of linalg/block_tridiagonal.py, O(N b^3) per eigenpair; BATCH eigenpairs at a time in
one compiled loop (rqi_many). Where the blocks' LU without pivoting between blocks loses
accuracy, pivoted_rqi solves with LAPACK's pivoted banded LU; refine_cluster iterates a group
of nearly degenerate pairs together. The residual |A r - lambda r| (|r| = 1) and kappa = |l|
|r| / |l^H r| bound the eigenvalue's error to first order by kappa |A r - lambda r|
(Wilkinson).
"""
from __future__ import annotations

from typing import Optional

import numba
import numpy as np
import scipy.sparse as sp
from scipy.linalg.lapack import dgbtrf, dgbtrs, zgbtrf, zgbtrs

from diskfriction.continuation.linalg.block_tridiagonal import (PeriodicBlocks, Shifted, factor_shifted, folded,
                                                               matvec_blocks, modulus_squared, solve_shifted,
                                                               work_arrays)

Array = np.ndarray


@numba.njit(cache=True)
def _sums(r, lc, square, overlap):
    """For each slot s of the (N, b, K) arrays: square[s] = sum |r[..., s]|^2 and overlap[s] =
    sum lc[..., s] r[..., s], the slots innermost."""
    N, b, K = r.shape
    for s in range(K):
        square[s] = 0.0
        overlap[s] = 0.0
    for k in range(N):
        for i in range(b):
            for s in range(K):
                square[s] += modulus_squared(r[k, i, s])
                overlap[s] += lc[k, i, s] * r[k, i, s]


@numba.njit(cache=True)
def _scale(r, norm, lc, overlap):
    """r[..., s] /= norm[s] and lc[..., s] /= overlap[s] for each slot s."""
    N, b, K = r.shape
    for k in range(N):
        for i in range(b):
            for s in range(K):
                r[k, i, s] /= norm[s]
                lc[k, i, s] /= overlap[s]


@numba.njit(cache=True)
def _rayleigh(r, lc, ax, lam, res, size):
    """For each slot s: lam[s] = lc^H-row times A r (ax = A r; l^H r = 1), res[s] = |A r - lam r|^2
    and size[s] = |lc|^2, the slots innermost."""
    N, b, K = r.shape
    for s in range(K):
        lam[s] = 0.0
        res[s] = 0.0
        size[s] = 0.0
    for k in range(N):
        for i in range(b):
            for s in range(K):
                lam[s] += lc[k, i, s] * ax[k, i, s]
    for k in range(N):
        for i in range(b):
            for s in range(K):
                res[s] += modulus_squared(ax[k, i, s] - lam[s] * r[k, i, s])
                size[s] += modulus_squared(lc[k, i, s])


STALLED = 0.1
"""rqi_many stops a pair whose residual fell by less than this factor in a step (cubic
convergence falls by orders of magnitude): the blocks' LU has reached its accuracy (pivot
growth, module docstring), and the pivoted LU takes the pair over: more steps with the
blocks' LU would cost time and not lower the residual."""

BATCH = 16
"""Pairs refined side by side by rqi_many (each with its own shift, every per-block loop over
them innermost; 16 was the fastest of 8, 16, 32, 64 at N = 1000)."""


@numba.njit(cache=True)
def rqi_many(diag, lower, upper, guess, right, left, rows, source, target, mirror, values_out, right_out,
              left_out, iterations, tol):
    """Two-sided Rayleigh quotient iteration of each pair alone, in the dtype of `guess` (real
    pairs in real arithmetic, four times cheaper; then `right` and `left` are the real parts of
    the complex vectors). Pair p starts from guess[p] with the right vector right[rows, source[p]]
    and the left row left[source[p], rows] (conj(l) entries, l^H x = sum(left[j] * x)): rows[t]
    is the row of block unknown t (PeriodicBlocks.order). Its result goes to values_out[target[p]],
    right_out[rows, target[p]] and left_out[target[p], rows], and, where mirror[p] >= 0, its
    complex conjugate to column and row mirror[p] (the lower member of a conjugate pair). A pair
    stops at tol, after `iterations` steps, or where its residual stalled (STALLED). BATCH
    pairs at a time, each with its own shift, side by side in every loop (a slot whose pair is
    done takes the next one). Returns the residuals |A r - lambda r| (|r| = 1) and the norms |l|
    (l^H r = 1), inf and nan where a factorization failed (its vectors written as zeros)."""
    N, b = diag.shape[0], diag.shape[1]
    n, k = N * b, guess.size
    residual = np.full(k, np.inf)
    kappa = np.full(k, np.nan)
    K = min(BATCH, k)
    if K == 0:
        return residual, kappa
    dt = guess.dtype
    (P, G, e, fr, S), (aug, ok, f), (v, tail) = work_arrays(N, b, K, guess[:1])
    r, lc = np.zeros((N, b, K), dt), np.zeros((N, b, K), dt)
    x, ax = np.empty((N, b, K), dt), np.empty((N, b, K), dt)
    lam, overlap = np.zeros(K, dt), np.zeros(K, dt)
    norm, res, size = np.zeros(K), np.zeros(K), np.zeros(K)
    last = np.full(K, np.inf)  # each slot's previous residual
    pair = np.full(K, -1)
    failed = np.zeros(K, np.bool_)
    steps = np.zeros(K, np.int64)
    upcoming = 0
    for s in range(K):
        pair[s] = upcoming
        upcoming += 1
    for s in range(K):
        p = pair[s]
        for t in range(n):
            r[t // b, t % b, s] = right[rows[t], source[p]]
            lc[t // b, t % b, s] = left[source[p], rows[t]]
        lam[s] = guess[p]
    while True:
        active = 0
        for s in range(K):
            if pair[s] >= 0:
                active += 1
        if active == 0:
            break
        factor_shifted(diag, lower, upper, lam, P, G, e, fr, S, aug, ok, f)
        solve_shifted(lower, upper, r, False, x, P, G, e, fr, S, v, tail)
        r[:] = x
        solve_shifted(lower, upper, lc, True, x, P, G, e, fr, S, v, tail)
        lc[:] = x
        _sums(r, lc, norm, overlap)
        for s in range(K):
            norm[s] = np.sqrt(norm[s])
            good = pair[s] >= 0 and ok[s] and np.isfinite(norm[s]) and norm[s] > 0.0
            if good:
                overlap[s] /= norm[s]
                good = np.isfinite(abs(overlap[s])) and overlap[s] != 0.0
            if pair[s] >= 0:
                steps[s] += 1
                failed[s] = not good  # its residual stays inf, its vectors zero
            if not good:  # unchanged below
                norm[s], overlap[s] = 1.0, 1.0
        _scale(r, norm, lc, overlap)
        matvec_blocks(diag, lower, upper, r, ax)
        _rayleigh(r, lc, ax, lam, res, size)
        for s in range(K):
            p = pair[s]
            if p == -1:
                continue
            done = failed[s]
            if done:
                for c in (target[p], mirror[p]):
                    if c >= 0:
                        right_out[:, c] = 0.0
                        left_out[c, :] = 0.0
            else:
                q = lam[s]
                res[s] = np.sqrt(res[s])
                stalled = res[s] > STALLED * last[s]
                last[s] = res[s]
                if res[s] <= tol or steps[s] >= iterations or stalled:
                    residual[p], kappa[p] = res[s], np.sqrt(size[s])
                    c, m = target[p], mirror[p]
                    values_out[c] = q
                    for t in range(n):
                        right_out[rows[t], c] = r[t // b, t % b, s]
                        left_out[c, rows[t]] = lc[t // b, t % b, s]
                    if m >= 0:
                        values_out[m] = np.conj(q)
                        for t in range(n):
                            right_out[rows[t], m] = np.conj(r[t // b, t % b, s])
                            left_out[m, rows[t]] = np.conj(lc[t // b, t % b, s])
                    done = True
            if done:  # the next pair into this slot
                steps[s] = 0
                failed[s] = False
                last[s] = np.inf
                if upcoming < k:
                    p = upcoming
                    upcoming += 1
                    pair[s] = p
                    for t in range(n):
                        r[t // b, t % b, s] = right[rows[t], source[p]]
                        lc[t // b, t % b, s] = left[source[p], rows[t]]
                    lam[s] = guess[p]
                else:
                    pair[s] = -1
                    r[:, :, s] = 0.0
                    lc[:, :, s] = 0.0
    return residual, kappa


def refine_cluster(blocks: PeriodicBlocks, values: Array, right: Array, left: Array,
                    iterations: int, tol: float) -> Array:
    """Block two-sided Rayleigh quotient iteration of the cluster (values (k,), right (n, k)
    columns, left (k, n) rows, block order, complex) in place (module docstring): the k right
    and k left vectors solved with one shift, the cluster's mean, and the k x k projected
    problem's eigenpairs taken; then each member not yet within tol polished by two steps with
    its own shift (the cluster's shift converges linearly, a member's own cubically), with the
    pivoted LU (the blocks' LU stalls near 1e-12 R for such shifts). Returns
    the members' residuals (inf, the cluster left as it was, where a factorization failed)."""
    X, Y, theta = right.T.copy(), left.copy(), values.copy()  # rows: r_j, conj(l_j)
    res = np.full(values.size, np.inf)
    for _ in range(iterations):
        sigma = complex(theta.mean())
        shifted = Shifted(blocks, sigma)
        if not shifted.ok:
            shifted = Shifted(blocks, nudged(sigma))
            if not shifted.ok:
                return np.full(values.size, np.inf)  # not res: the cluster is left as it was
        X, Y = shifted.solve(X.T).T, shifted.solve(Y.T, transpose=True).T
        if not (np.isfinite(X).all() and np.isfinite(Y).all()):
            return np.full(values.size, np.inf)
        X, Y = np.linalg.qr(X.T)[0].T, np.linalg.qr(Y.T)[0].T
        G, H = Y @ X.T, Y @ blocks.matvec(X.T)  # l_a^H x_j, l_a^H A x_j
        theta, W = np.linalg.eig(np.linalg.solve(G, H))
        X, Y = W.T @ X, np.linalg.solve(W, np.linalg.solve(G, Y))
        norm = np.linalg.norm(X, axis=1)
        X, Y = X / norm[:, None], Y * norm[:, None]  # |r| = 1, l^H r = 1
        if not np.isfinite(theta).all():
            return np.full(values.size, np.inf)
        res = np.linalg.norm(blocks.matvec(X.T).T - theta[:, None] * X, axis=1)
        if res.max() <= tol:
            break
    values[:], right[:], left[:] = theta, X.T, Y
    rough = np.flatnonzero(res > tol)
    if rough.size:
        v, r, lft = values[rough], right[:, rough], left[rough]
        polished = pivoted_rqi(blocks, v, r, lft, 2, tol)
        better = polished < res[rough]
        values[rough[better]], right[:, rough[better]], left[rough[better]] = v[better], r[:, better], lft[better]
        res[rough[better]] = polished[better]
    return res


def nudged(sigma: complex) -> complex:
    """A shift next to sigma (relative 1e-10, off the real axis), for a shifted matrix exactly
    singular at sigma: sigma is then an eigenvalue to working precision (an exactly degenerate
    pair, a mode decoupled from its neighbours), and inverse iteration with the nudged shift
    still converges to it in one step."""
    return sigma + 1e-10 * max(abs(sigma), 1.0) * (1.0 + 1.0j)


def pivoted_rqi(blocks: PeriodicBlocks, values: Array, right: Array, left: Array,
                 iterations: int, tol: float, deflated: Optional[tuple[Array, Array]] = None) -> Array:
    """Two-sided Rayleigh quotient iteration of each pair alone, in place (complex; layout of
    rqi_many), the shifted solves by LAPACK's banded LU with partial pivoting (zgbtrf) of the
    matrix in the folded order: stable where the blocks' LU without pivoting between blocks
    grows (a shift near an eigenvalue of a leading sub-chain), at about three times its cost.
    A pair whose value and vectors are real is iterated in real arithmetic (dgbtrf: the rough
    pairs the blocks' LU leaves are mostly real ones), in complex arithmetic from where its
    shift must be nudged (a singular shifted matrix) or known pairs are deflated.
    deflated: (right vectors as columns, left vectors as rows) of known eigenpairs projected
    out of each iterate (x - R L^H x, l - L (R^T l) in the rows' conjugate layout), so that the
    iteration finds another eigenvalue. Returns the residuals (inf where a factorization
    failed)."""
    N, b = blocks.diag.shape[:2]
    n, kl = N * b, 3 * b - 1
    perm = (b * folded(N)[:, None] + np.arange(b)).ravel()  # folded position -> unknown
    A = sp.coo_array(blocks.sparse()[perm][:, perm])
    real_band = np.zeros((3 * kl + 1, n))  # LAPACK's layout: ab[2 kl + i - j, j] = M[i, j]
    real_band[2 * kl + A.row - A.col, A.col] = A.data
    band = real_band.astype(np.complex128)
    residual = np.full(values.size, np.inf)
    if deflated is not None:
        known_r, known_l = deflated[0][perm], deflated[1][:, perm]
    for p in range(values.size):
        lam, r, lc = complex(values[p]), right[perm, p].astype(np.complex128), left[p, perm].astype(np.complex128)
        real = deflated is None and lam.imag == 0.0 and not (np.any(r.imag) or np.any(lc.imag))
        if real:
            lam, r, lc = lam.real, r.real.copy(), lc.real.copy()
        res = np.inf
        for _ in range(iterations):
            for shift in (lam, nudged(lam)):
                if real and isinstance(shift, complex):  # nudged off the real axis
                    real, r, lc = False, r.astype(np.complex128), lc.astype(np.complex128)
                shifted = (real_band if real else band).copy()
                shifted[2 * kl] -= shift
                lu, piv, info = (dgbtrf if real else zgbtrf)(shifted, kl, kl)
                if info == 0:
                    break
            if info != 0:
                res = np.inf
                break
            solve = dgbtrs if real else zgbtrs
            r, info_r = solve(lu, kl, kl, r, piv)
            lc, info_l = solve(lu, kl, kl, lc, piv, trans=1)
            if deflated is not None:
                r = r - known_r @ (known_l @ r)
                lc = lc - (lc @ known_r) @ known_l
            norm = np.linalg.norm(r)
            overlap = np.sum(lc * r) / norm
            if info_r or info_l or not (np.isfinite(norm) and norm > 0.0 and np.isfinite(overlap) and overlap != 0.0):
                res = np.inf
                break
            r, lc = r / norm, lc / overlap
            ar = A @ r
            lam = (float if real else complex)(np.sum(lc * ar))
            res = float(np.linalg.norm(ar - lam * r))
            if res <= tol:
                break
        if np.isfinite(res):
            residual[p], values[p] = res, lam
            right[perm, p], left[p, perm] = r, lc
    return residual


def polish(blocks: PeriodicBlocks, pairs: Array, values: Array, right: Array, left: Array, residual: Array,
           tol: float, iterations: int = 2) -> Array:
    """pivoted_rqi on the given pairs (indices into values (k,), right (n, k) columns, left (k,
    n) rows, in the matrix's own order, complex), each replaced in place where its residual
    fell below `residual` (theirs now); returns the pairs' residuals."""
    order = np.arange(blocks.n) if blocks.order is None else np.asarray(blocks.order)
    v, r, lft = values[pairs], right[order][:, pairs], left[pairs][:, order]  # block order
    polished = pivoted_rqi(blocks, v, r, lft, iterations, tol)
    better = polished < residual
    take = pairs[better]
    values[take] = v[better]
    right[np.ix_(order, take)], left[np.ix_(take, order)] = r[:, better], lft[better]
    return np.where(better, polished, residual)
