"""Periodic block-tridiagonal matrices: shifted solves in O(N b^3) and eigenpair refinement
(issue 26 item 1, the eigenpair continuation's kernel).

A matrix of N x N blocks of size b with blocks only on the diagonal, the first off-diagonals
and the two periodic corners (the disk chain's stability matrix: each disk couples to its two
neighbours, disk N to disk 1):

    row k:   lower[k] x[k-1] + diag[k] x[k] + upper[k] x[k+1] = rhs[k],   indices mod N.

Shifted solves. M = A - sigma I (sigma complex) is factorized with the last block row and
column as a border: T (the first N - 1 block rows and columns) is block tridiagonal without
corners, factorized by block LU without pivoting between blocks (partial pivoting inside each
b x b block), T = L U, and the border by its Schur complement S = M_ll - F T^-1 E (E: the last
block column, nonzero in block rows 0 and N - 2; F: the last block row), from the border's
fill-in L^-1 E and F U^-1, each one forward recurrence (the block LU of the whole matrix with
the border last: about 8 b^3 multiplications per block row, where the columns T^-1 E and
T^-T F^T, each a forward and a backward pass, took 10 b^3). Solves with M and with M^T each
cost O(N b^2) after the factorization. The compiled kernels factorize K shifts side by
side (arrays with the shift last, every loop over the shifts innermost: _work, _factor,
_solve). No pivoting between blocks: where a pivot block is singular for the shift the
factorization reports it (ok False), and where one nearly is the solves lose accuracy;
refine_eigenpairs then turns to LAPACK's pivoted banded LU in the folded order (_pivoted_rqi).

Eigenpair refinement. Two-sided Rayleigh quotient iteration (Ostrowski; Parlett 1974) from a
guess (lambda, r, l) with l^H r = 1:

    M = A - lambda I,   r <- M^-1 r,   l <- M^-H l,   scale so |r| = 1 and l^H r = 1,
    lambda <- l^H A r,

cubically convergent for a simple eigenvalue. Each iteration is one factorization and two
solves, O(N b^3) per eigenpair; BATCH eigenpairs at a time in one compiled loop. The residual
|A r - lambda r| (|r| = 1) and kappa = |l| |r| / |l^H r| bound the eigenvalue's error to first
order by kappa |A r - lambda r| (Wilkinson).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numba
import numpy as np
import scipy.sparse as sp
from scipy.linalg.lapack import dgbtrf, dgbtrs, zgbtrf, zgbtrs
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from diskfriction.continuation.linalg.solves import row_norms

Array = np.ndarray


@dataclass(frozen=True)
class PeriodicBlocks:
    """A periodic block-tridiagonal matrix: diag, lower, upper (N, b, b) real arrays (module
    docstring); lower[0] is the corner coupling block row 0 to block column N - 1, upper[N - 1]
    the corner coupling block row N - 1 to block column 0."""

    diag: Array
    lower: Array
    upper: Array
    order: Optional[Array] = None
    """order[i]: the index in the original matrix of block row and column i's unknown (None:
    the same order); from_matrix."""

    @property
    def n(self) -> int:
        return self.diag.shape[0] * self.diag.shape[1]

    def traces(self) -> tuple[float, float]:
        """(tr A, tr A^2): sum_k tr D_k and sum_k tr D_k^2 + 2 tr(L_k U_{k-1}) (L_k couples
        block row k to column k - 1, U_{k-1} row k - 1 to column k; N >= 3), O(N b^2)."""
        below = np.roll(self.upper, 1, axis=0)  # U_{k-1}
        return (float(np.einsum("kii->", self.diag)),
                float(np.einsum("kij,kji->", self.diag, self.diag) + 2.0 * np.einsum("kij,kji->", self.lower, below)))

    @classmethod
    def from_matrix(cls, A, b: int, order=None) -> "PeriodicBlocks":
        """The blocks of the n x n matrix A (dense or sparse), n = N b, N >= 3, with its rows and
        columns taken in `order` (order[i]: A's index of row and column i; None: as they are;
        the disk chain's unknowns are field-major, x_1..x_N, y_1..y_N, ..., so its block order
        is disk_major(N, b)). ValueError if the result has an entry outside the periodic
        block-tridiagonal pattern."""
        A = sp.csr_array(A)
        if order is not None:
            A = A[order][:, order]
        A = sp.coo_array(A)
        n = A.shape[0]
        if A.shape != (n, n) or n % b or n // b < 3:
            raise ValueError(f"a periodic block-tridiagonal matrix has N >= 3 blocks of size {b} "
                             f"(got shape {A.shape})")
        N = n // b
        rows, cols, values = A.row, A.col, A.data
        blocks = np.zeros((3, N, b, b))  # lower, diag, upper
        offset = (cols // b - rows // b + 1) % N  # 0: lower, 1: diag, 2: upper
        if np.any(offset > 2) and np.any(values[offset > 2] != 0.0):
            raise ValueError("the matrix has entries outside the periodic block-tridiagonal pattern")
        keep = offset <= 2
        np.add.at(blocks, (offset[keep], rows[keep] // b, rows[keep] % b, cols[keep] % b), values[keep])
        return cls(blocks[1], blocks[0], blocks[2], None if order is None else np.asarray(order))

    def sparse(self) -> sp.csr_array:
        """The n x n matrix in block order, sparse."""
        N, b = self.diag.shape[:2]
        k = np.repeat(np.arange(N), b * b)
        i, j = np.tile(np.repeat(np.arange(b), b), N), np.tile(np.arange(b), N * b)
        rows = np.concatenate([k * b + i] * 3)
        cols = np.concatenate([((k + shift) % N) * b + j for shift in (0, -1, 1)])
        values = np.concatenate([self.diag.ravel(), self.lower.ravel(), self.upper.ravel()])
        return sp.csr_array((values, (rows, cols)), shape=(self.n, self.n))

    def original(self) -> sp.csr_array:
        """The n x n matrix in its original order (from_matrix's A: row and column order[i]
        is block order's i), sparse."""
        A = self.sparse()
        if self.order is None:
            return A
        back = np.empty(self.n, np.int64)
        back[np.asarray(self.order)] = np.arange(self.n)
        return A[back][:, back]

    def dense(self) -> Array:
        """The n x n matrix (tests)."""
        return self.sparse().toarray()

    def solve(self, sigma: complex, rhs: Array, transpose: bool = False) -> Array:
        """x with (A - sigma I) x = rhs (or its transpose), rhs (n,): one factorization (nan
        where a pivot block is singular)."""
        shifted = Shifted(self, sigma)
        return shifted.solve(rhs, transpose) if shifted.ok else np.full(self.n, np.nan + 0j)

    def matvec(self, X: Array) -> Array:
        """A X for X (n,) or (n, K), complex."""
        N, b = self.diag.shape[:2]
        X = np.asarray(X, np.complex128)
        x = np.ascontiguousarray(X.reshape(self.n, -1)).reshape(N, b, -1)
        y = np.empty_like(x)
        _matvec(self.diag, self.lower, self.upper, x, y)
        return y.reshape(X.shape)


def disk_major(N: int, b: int) -> Array:
    """The order that takes field-major unknowns (index f N + k for field f of disk k) to
    disk-major ones (k b + f): PeriodicBlocks.from_matrix's `order` for the disk chain."""
    return np.arange(N * b).reshape(b, N).T.ravel()


@numba.njit(cache=True)
def _work(N, b, K, proto):
    """The arrays of K shifted factorizations side by side, of proto's dtype (real for real
    shifts): the pivot blocks' inverses P, the multipliers G, the border's fill-in e and f
    (m, b, b, K), m = N - 1, and S^-1 (b, b, K) (_factor); _factor's scratch aug (b, 2 b, K),
    ok (K,), f (K,); _solve's scratch v and tail (b, K)."""
    m = N - 1
    dt = proto.dtype
    factors = (np.empty((m, b, b, K), dt), np.empty((m, b, b, K), dt), np.empty((m, b, b, K), dt),
               np.empty((m, b, b, K), dt), np.empty((b, b, K), dt))
    scratch = (np.empty((b, 2 * b, K), dt), np.ones(K, np.bool_), np.empty(K, dt))
    columns = (np.empty((b, K), dt), np.empty((b, K), dt))
    return factors, scratch, columns


class Shifted:
    """A - sigma I factorized (_factor with one shift), solved for any number of right-hand
    sides (_solve, one at a time). ok: False where a pivot block or the Schur complement is
    singular (the solutions are then not finite)."""

    def __init__(self, blocks: "PeriodicBlocks", sigma: complex):
        N, b = blocks.diag.shape[:2]
        shift = np.array([sigma], np.complex128)
        self.blocks, self.shape = blocks, (N, b, 1)
        self.factors, self.scratch, self.columns = _work(N, b, 1, shift)
        _factor(blocks.diag, blocks.lower, blocks.upper, shift, *self.factors, *self.scratch)
        self.ok = bool(self.scratch[1][0])

    def solve(self, rhs: Array, transpose: bool = False) -> Array:
        """(A - sigma I)^-1 rhs (or with the transpose): rhs and the result (n,) or (n, k)."""
        rhs = np.asarray(rhs, np.complex128)
        out = np.empty(rhs.shape, np.complex128)
        x = np.empty(self.shape, np.complex128)
        for j, column in enumerate(rhs.reshape(rhs.shape[0], -1).T):
            _solve(self.blocks.lower, self.blocks.upper, np.ascontiguousarray(column).reshape(self.shape),
                   transpose, x, *self.factors, *self.columns)
            out.reshape(rhs.shape[0], -1)[:, j] = x.ravel()
        return out


@numba.njit(cache=True)
def _square(z):
    """|z|^2 of a real or complex number."""
    return z.real * z.real + z.imag * z.imag


@numba.njit(cache=True)
def _invert(aug, out, ok, f):
    """For each shift s: out[:, :, s] = the inverse of aug[:, :b, s] (Gauss-Jordan with partial
    pivoting; aug (b, 2 b, K) overwritten); ok[s] = False where singular. f: (K,) scratch."""
    b, K = aug.shape[0], aug.shape[2]
    for i in range(b):
        for j in range(b):
            for s in range(K):
                aug[i, b + j, s] = 1.0 if i == j else 0.0
    for c in range(b):
        for s in range(K):
            p, best = c, _square(aug[c, c, s])  # |.|^2: no hypot for a complex entry
            for r in range(c + 1, b):
                if _square(aug[r, c, s]) > best:
                    p, best = r, _square(aug[r, c, s])
            if best == 0.0:
                ok[s] = False
                aug[c, c, s] = 1.0
            elif p != c:
                for j in range(2 * b):
                    aug[c, j, s], aug[p, j, s] = aug[p, j, s], aug[c, j, s]
            f[s] = 1.0 / aug[c, c, s]
        for j in range(2 * b):
            for s in range(K):
                aug[c, j, s] *= f[s]
        for r in range(b):
            if r != c:
                for s in range(K):
                    f[s] = aug[r, c, s]
                for j in range(2 * b):
                    for s in range(K):
                        aug[r, j, s] -= f[s] * aug[c, j, s]
    for i in range(b):
        for j in range(b):
            for s in range(K):
                out[i, j, s] = aug[i, b + j, s]


@numba.njit(cache=True)
def _factor(diag, lower, upper, sigma, P, G, e, fr, S, aug, ok, f):
    """Factorize M_s = A - sigma_s I (module docstring) for the shifts sigma (K,) side by side,
    every loop over them innermost, as

        M = [[L, 0], [fr, I]] [[U, e], [0, S^-1]],

    L unit lower block-bidiagonal (G[k] below the diagonal, block row k), U upper
    block-bidiagonal (pivot blocks P[k]^-1, upper[k] above); e = L^-1 E by the forward
    recurrence e_k = E_k - G_k e_{k-1}, fr = F U^-1 by fr_k = (F_k - fr_{k-1} upper_{k-1}) P_k,
    and S^-1 = M_ll - sum_k fr_k e_k (E_k, F_k nonzero at k = 0 and m - 1 only: the corners).
    P, G, e, fr (m, b, b, K), S (b, b, K); aug (b, 2 b, K) and f (K,) scratch (_work); ok[s]
    False where shift s met a singular pivot block or Schur complement."""
    N, b, K = diag.shape[0], diag.shape[1], sigma.size
    m = N - 1
    ok[:] = True
    for k in range(m):
        for i in range(b):
            for j in range(b):
                d = diag[k, i, j]
                for s in range(K):
                    aug[i, j, s] = d
            for s in range(K):
                aug[i, i, s] -= sigma[s]
        if k > 0:
            for i in range(b):
                for j in range(b):
                    for s in range(K):
                        G[k, i, j, s] = 0.0
                    for t in range(b):
                        low = lower[k, i, t]
                        for s in range(K):
                            G[k, i, j, s] += low * P[k - 1, t, j, s]
            for i in range(b):
                for j in range(b):
                    for t in range(b):
                        u = upper[k - 1, t, j]
                        for s in range(K):
                            aug[i, j, s] -= G[k, i, t, s] * u
        _invert(aug, P[k], ok, f)
        for i in range(b):
            for j in range(b):
                corner = (lower[0, i, j] if k == 0 else 0.0) + (upper[m - 1, i, j] if k == m - 1 else 0.0)
                for s in range(K):
                    e[k, i, j, s] = corner
                if k > 0:
                    for t in range(b):
                        for s in range(K):
                            e[k, i, j, s] -= G[k, i, t, s] * e[k - 1, t, j, s]
                corner = (upper[N - 1, i, j] if k == 0 else 0.0) + (lower[N - 1, i, j] if k == m - 1 else 0.0)
                for s in range(K):
                    aug[i, j, s] = corner
                if k > 0:
                    for t in range(b):
                        u = upper[k - 1, t, j]
                        for s in range(K):
                            aug[i, j, s] -= fr[k - 1, i, t, s] * u
        for i in range(b):
            for j in range(b):
                for s in range(K):
                    fr[k, i, j, s] = 0.0
                for t in range(b):
                    for s in range(K):
                        fr[k, i, j, s] += aug[i, t, s] * P[k, t, j, s]
    for i in range(b):
        for j in range(b):
            d = diag[N - 1, i, j]
            for s in range(K):
                aug[i, j, s] = d - (sigma[s] if i == j else 0.0)
    for k in range(m):
        for i in range(b):
            for j in range(b):
                for t in range(b):
                    for s in range(K):
                        aug[i, j, s] -= fr[k, i, t, s] * e[k, t, j, s]
    _invert(aug, S, ok, f)


@numba.njit(cache=True)
def _times(M, v, out, transpose):
    """out[i, s] = sum_t M[i, t, s] v[t, s] (M[t, i, s] where transpose) for each slot s: M
    (b, b, K), v and out (b, K)."""
    b, K = v.shape
    for i in range(b):
        for s in range(K):
            out[i, s] = 0.0
        for t in range(b):
            if transpose:
                for s in range(K):
                    out[i, s] += M[t, i, s] * v[t, s]
            else:
                for s in range(K):
                    out[i, s] += M[i, t, s] * v[t, s]


@numba.njit(cache=True)
def _solve(lower, upper, rhs, transpose, out, P, G, e, fr, S, v, tail):
    """out[..., s] = M_s^-1 rhs[..., s] (or M_s^-T) for each factorization s (_factor's): rhs
    and out (N, b, K), distinct; v, tail (b, K) scratch (_work). M x = rhs: z = L^-1 rhs (head),
    x_last = S (rhs_last - fr z), x_k = P_k (z_k - e_k x_last - upper_k x_{k+1}). M^T x = rhs:
    w = U^-T rhs (head), x_last = S^T (rhs_last - e^T w), x_k = w_k - fr_k^T x_last -
    G_{k+1}^T x_{k+1}."""
    N, b, K = rhs.shape
    m = N - 1
    for i in range(b):
        for s in range(K):
            tail[i, s] = rhs[N - 1, i, s]
    for k in range(m):  # forward: z (or w) into out's head, and the border's rhs_last - fr z (- e^T w)
        if not transpose:
            for i in range(b):
                for s in range(K):
                    out[k, i, s] = rhs[k, i, s]
                if k > 0:
                    for j in range(b):
                        for s in range(K):
                            out[k, i, s] -= G[k, i, j, s] * out[k - 1, j, s]
        else:
            for i in range(b):
                for s in range(K):
                    v[i, s] = rhs[k, i, s]
                if k > 0:
                    for j in range(b):
                        u = upper[k - 1, j, i]
                        for s in range(K):
                            v[i, s] -= u * out[k - 1, j, s]
            _times(P[k], v, out[k], True)
        for i in range(b):
            for t in range(b):
                for s in range(K):
                    tail[i, s] -= (e[k, t, i, s] if transpose else fr[k, i, t, s]) * out[k, t, s]
    _times(S, tail, out[N - 1], transpose)
    for k in range(m - 1, -1, -1):  # backward
        if not transpose:
            for i in range(b):
                for s in range(K):
                    v[i, s] = out[k, i, s]
                for t in range(b):
                    for s in range(K):
                        v[i, s] -= e[k, i, t, s] * out[N - 1, t, s]
                if k < m - 1:
                    for j in range(b):
                        u = upper[k, i, j]
                        for s in range(K):
                            v[i, s] -= u * out[k + 1, j, s]
            _times(P[k], v, out[k], False)
        else:
            for i in range(b):
                for t in range(b):
                    for s in range(K):
                        out[k, i, s] -= fr[k, t, i, s] * out[N - 1, t, s]
                if k < m - 1:
                    for j in range(b):
                        for s in range(K):
                            out[k, i, s] -= G[k + 1, j, i, s] * out[k + 1, j, s]


@numba.njit(cache=True)
def _matvec(diag, lower, upper, x, y):
    """y = A x for K vectors at once, x and y (N, b, K)."""
    N, b, K = x.shape
    for k in range(N):
        prev, nxt = (k - 1) % N, (k + 1) % N
        for i in range(b):
            for s in range(K):
                y[k, i, s] = 0.0
            for j in range(b):
                d, low, u = diag[k, i, j], lower[k, i, j], upper[k, i, j]
                for s in range(K):
                    y[k, i, s] += d * x[k, j, s] + low * x[prev, j, s] + u * x[nxt, j, s]


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
                square[s] += _square(r[k, i, s])
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
                res[s] += _square(ax[k, i, s] - lam[s] * r[k, i, s])
                size[s] += _square(lc[k, i, s])


STALLED = 0.1
"""_rqi_many stops a pair whose residual fell by less than this factor in a step (cubic
convergence falls by orders of magnitude): the blocks' LU has reached its accuracy (pivot
growth, module docstring), and the pivoted LU takes the pair over. The chain of 1000 disks:
of 2118 real pairs 60 were above 1e-12 of the spectral radius after 2 steps and 52 after 6,
and steps 3 to 6 made the refinement a quarter slower (2.58 against 2.07 s)."""

BATCH = 16
"""Pairs refined side by side by _rqi_many (each with its own shift, every per-block loop over
them innermost; 16 was the fastest of 8, 16, 32, 64 at N = 1000)."""


@numba.njit(cache=True)
def _rqi_many(diag, lower, upper, guess, right, left, rows, source, target, mirror, values_out, right_out,
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
    (P, G, e, fr, S), (aug, ok, f), (v, tail) = _work(N, b, K, guess[:1])
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
        _factor(diag, lower, upper, lam, P, G, e, fr, S, aug, ok, f)
        _solve(lower, upper, r, False, x, P, G, e, fr, S, v, tail)
        r[:] = x
        _solve(lower, upper, lc, True, x, P, G, e, fr, S, v, tail)
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
        _matvec(diag, lower, upper, r, ax)
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


def close_pairs(points: Array, radius: float) -> tuple[Array, Array]:
    """Index pairs (i < j) of the complex points within `radius` of each other (a k-d tree)."""
    if points.size < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    pairs = cKDTree(np.column_stack([points.real, points.imag])).query_pairs(radius, output_type="ndarray")
    return pairs[:, 0], pairs[:, 1]


NEAR_REAL = 1e-9
"""A guess without a conjugate partner whose imaginary part is within this many times the
spectral radius (the complex status threshold, spectra.py) is refined in real arithmetic, from
its vectors made real (Guesses.made_real): complex arithmetic leaves a real eigenvalue's vectors
with a complex phase and its value with an imaginary part of rounding size, and without this
the pair would stay in complex arithmetic, four times dearer, at every later refinement (on the
chain of 400 disks, 251 of 1200 pairs after 150 s of a sweep)."""

LARGEST_CLUSTER = 16
"""Largest group of pairs refined again together (refine_eigenpairs, refinement_groups); a
larger one is left as it is, to the certificate."""

PARTNERS = 2
"""Pairs whose guesses are nearest a pair still above the tolerance, refined again with it
(refinement_groups). With one, the two real guesses of a pair born inside the step (a complex
pair now) were each grouped with a third eigenvalue nearer it than its partner, and neither
group spans the pair: 20 of the 36 refinements declined on the chain of 400 disks from rest to
0.12 (2026-11-28)."""

PARTNER_REACH = 4.0
"""A partner beyond the nearest joins only within this many times the nearest one's distance
(a far one would only slow the group's shifted iteration): the two members of the pairs above
were 1.5 to 2.9 times farther apart than the nearest third guess."""


def refine_eigenpairs(blocks: PeriodicBlocks, values: Array, right: Array, left: Array,
                      iterations: int = 6, tol: float = 0.0, columns: Optional[Array] = None
                      ) -> tuple[Array, Array, Array, Array]:
    """Every eigenpair of `blocks`' matrix refined from the guesses: values (n,), right vectors
    as columns and left vectors as rows l_i^H (l_i^H r_i = 1: spectra.Eigensystem's layout) in
    the matrix's own order (PeriodicBlocks.order takes block unknowns to it), pair i's in column
    (and row) columns[i] (None: i). Each pair alone by at most `iterations` two-sided Rayleigh
    quotient steps (fewer once its residual is <= tol): in real arithmetic where guess and
    vectors are real, the lower member of a complex-conjugate pair as the conjugate of the upper
    one. Any pair still above tol gets `iterations` more steps alone with a pivoted banded LU
    (_pivoted_rqi; again a lower member as its upper one's conjugate). Pairs whose error discs
    kappa_i rho_i then meet (a degenerate or nearly degenerate eigenvalue: alone, two pairs may
    land on one eigenpair, or on vectors of one eigenspace that are not biorthogonal), and each
    pair still above tol with the pair whose guess is nearest (refinement_groups), are refined
    again together from their guesses, in groups of at most LARGEST_CLUSTER (_refine_cluster:
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
    out = Refined.empty(guess.rows)
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
        out.put(rough, v, r, lft, _pivoted_rqi(blocks, v, r, lft, iterations, tol), better=True)
        mirrored = np.isin(upper, rough)
        v, r, lft = out.take(upper[mirrored])
        out.put(lower[mirrored], v.conj(), r.conj(), lft.conj(), out.residual[upper[mirrored]])
    for group in refinement_groups(guess.values, out.values, out.residual, out.kappa, tol):
        if group.size <= LARGEST_CLUSTER:
            v, r, lft = guess.take(group)
            res = _refine_cluster(blocks, v, r, lft, iterations, tol)
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
            out.put(np.array([p]), v, r, lft, _pivoted_rqi(blocks, v, r, lft, 2 * iterations, tol, (known_r, known_l)))
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
class Refined:
    """refine_eigenpairs' result as it is built: values (n,), right (n, n), left (n, n) in the
    matrix's order (pair i in column and row i), residual and kappa = |l_i| (nan where none)."""

    values: Array
    right: Array
    left: Array
    residual: Array
    kappa: Array
    rows: Array

    @classmethod
    def empty(cls, rows: Array) -> "Refined":
        n = rows.size
        # the right vectors column by column, the left ones row by row, as LAPACK leaves them:
        # each pair's reads and writes are contiguous. Not zeroed: _rqi_many writes every
        # column and row (refine_eigenpairs gives it every pair), and zeroing 288 MB at
        # N = 1000 cost as much as writing them
        return cls(np.zeros(n, np.complex128), np.empty((n, n), np.complex128, order="F"),
                   np.empty((n, n), np.complex128), np.full(n, np.inf), np.full(n, np.nan), rows)

    def rqi(self, blocks: PeriodicBlocks, guess: Guesses, pairs: Array, mirror: Array, iterations: int,
            tol: float, real: bool = False) -> None:
        """_rqi_many on `pairs` from their guesses, written here (with each conjugate into its
        mirror's column and row, mirror -1: none); real: in real arithmetic."""
        values, right, left = guess.values[pairs], guess.right, guess.left
        if real:
            values, right, left = values.real.copy(), right.real, left.real
        else:
            right, left = np.asarray(right, np.complex128), np.asarray(left, np.complex128)
        self.residual[pairs], self.kappa[pairs] = _rqi_many(
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


def _found_twice(guess: Array, out: Refined) -> Array:
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


def _refine_cluster(blocks: PeriodicBlocks, values: Array, right: Array, left: Array,
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
        polished = _pivoted_rqi(blocks, v, r, lft, 2, tol)
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


def folded(N: int) -> Array:
    """The block order 0, N - 1, 1, N - 2, 2, ...: in it each block's periodic neighbours are at
    most two places away, so a periodic block-tridiagonal matrix becomes banded (3 b - 1
    diagonals on each side)."""
    order = np.empty(N, np.int64)
    order[0::2], order[1::2] = np.arange((N + 1) // 2), N - 1 - np.arange(N // 2)
    return order


def _pivoted_rqi(blocks: PeriodicBlocks, values: Array, right: Array, left: Array,
                 iterations: int, tol: float, deflated: Optional[tuple[Array, Array]] = None) -> Array:
    """Two-sided Rayleigh quotient iteration of each pair alone, in place (complex; layout of
    _rqi_many), the shifted solves by LAPACK's banded LU with partial pivoting (zgbtrf) of the
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
    """_pivoted_rqi on the given pairs (indices into values (k,), right (n, k) columns, left (k,
    n) rows, in the matrix's own order, complex), each replaced in place where its residual
    fell below `residual` (theirs now); returns the pairs' residuals."""
    order = np.arange(blocks.n) if blocks.order is None else np.asarray(blocks.order)
    v, r, lft = values[pairs], right[order][:, pairs], left[pairs][:, order]  # block order
    polished = _pivoted_rqi(blocks, v, r, lft, iterations, tol)
    better = polished < residual
    take = pairs[better]
    values[take] = v[better]
    right[np.ix_(order, take)], left[np.ix_(take, order)] = r[:, better], lft[better]
    return np.where(better, polished, residual)


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
