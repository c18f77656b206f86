"""Periodic block-tridiagonal matrices and their shifted solves in O(N b^3).

A matrix of N x N blocks of size b with blocks only on the diagonal, the first off-diagonals
and the two periodic corners (a ring of N identical cells, each coupled to its two neighbours,
cell N to cell 1):

    row k:   lower[k] x[k-1] + diag[k] x[k] + upper[k] x[k+1] = rhs[k],   indices mod N.

Shifted solves. M = A - sigma I (sigma complex) is factorized with the last block row and
column as a border: T (the first N - 1 block rows and columns) is block tridiagonal without
corners, factorized by block LU without pivoting between blocks (partial pivoting inside each
b x b block), T = L U, and the border by its Schur complement S = M_ll - F T^-1 E (E: the last
block column, nonzero in block rows 0 and N - 2; F: the last block row), from the border's
fill-in L^-1 E and F U^-1, each one forward recurrence (about 8 b^3 multiplications per block
row). Solves with M and with M^T each cost O(N b^2) after the factorization. The compiled
kernels factorize K shifts side by side (arrays with the shift last, every loop over the
shifts innermost: work_arrays, factor_shifted, solve_shifted). No pivoting between blocks:
where a pivot block is singular for the shift the factorization reports it (ok False), and
where one nearly is the solves lose accuracy; the eigenpair refinement then turns to LAPACK's
pivoted banded LU in the folded order (spectra/rayleigh.py).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numba
import numpy as np
import scipy.sparse as sp

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
        field-major unknowns, x_1..x_N, y_1..y_N, ..., take the order block_major(N, b)).
        ValueError if the result has an entry outside the periodic
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
        matvec_blocks(self.diag, self.lower, self.upper, x, y)
        return y.reshape(X.shape)


def block_major(N: int, b: int) -> Array:
    """The order that takes field-major unknowns (index f N + k for field f of cell k) to
    cell-major ones (k b + f): PeriodicBlocks.from_matrix's `order` for them."""
    return np.arange(N * b).reshape(b, N).T.ravel()


@numba.njit(cache=True)
def work_arrays(N, b, K, proto):
    """The arrays of K shifted factorizations side by side, of proto's dtype (real for real
    shifts): the pivot blocks' inverses P, the multipliers G, the border's fill-in e and f
    (m, b, b, K), m = N - 1, and S^-1 (b, b, K) (factor_shifted); factor_shifted's scratch aug (b, 2 b, K),
    ok (K,), f (K,); solve_shifted's scratch v and tail (b, K)."""
    m = N - 1
    dt = proto.dtype
    factors = (np.empty((m, b, b, K), dt), np.empty((m, b, b, K), dt), np.empty((m, b, b, K), dt),
               np.empty((m, b, b, K), dt), np.empty((b, b, K), dt))
    scratch = (np.empty((b, 2 * b, K), dt), np.ones(K, np.bool_), np.empty(K, dt))
    columns = (np.empty((b, K), dt), np.empty((b, K), dt))
    return factors, scratch, columns


class Shifted:
    """A - sigma I factorized (factor_shifted with one shift), solved for any number of right-hand
    sides (solve_shifted, one at a time). ok: False where a pivot block or the Schur complement is
    singular (the solutions are then not finite)."""

    def __init__(self, blocks: "PeriodicBlocks", sigma: complex):
        N, b = blocks.diag.shape[:2]
        shift = np.array([sigma], np.complex128)
        self.blocks, self.shape = blocks, (N, b, 1)
        self.factors, self.scratch, self.columns = work_arrays(N, b, 1, shift)
        factor_shifted(blocks.diag, blocks.lower, blocks.upper, shift, *self.factors, *self.scratch)
        self.ok = bool(self.scratch[1][0])

    def solve(self, rhs: Array, transpose: bool = False) -> Array:
        """(A - sigma I)^-1 rhs (or with the transpose): rhs and the result (n,) or (n, k)."""
        rhs = np.asarray(rhs, np.complex128)
        out = np.empty(rhs.shape, np.complex128)
        x = np.empty(self.shape, np.complex128)
        for j, column in enumerate(rhs.reshape(rhs.shape[0], -1).T):
            solve_shifted(self.blocks.lower, self.blocks.upper, np.ascontiguousarray(column).reshape(self.shape),
                   transpose, x, *self.factors, *self.columns)
            out.reshape(rhs.shape[0], -1)[:, j] = x.ravel()
        return out


@numba.njit(cache=True)
def modulus_squared(z):
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
            p, best = c, modulus_squared(aug[c, c, s])  # |.|^2: no hypot for a complex entry
            for r in range(c + 1, b):
                if modulus_squared(aug[r, c, s]) > best:
                    p, best = r, modulus_squared(aug[r, c, s])
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
def factor_shifted(diag, lower, upper, sigma, P, G, e, fr, S, aug, ok, f):
    """Factorize M_s = A - sigma_s I (module docstring) for the shifts sigma (K,) side by side,
    every loop over them innermost, as

        M = [[L, 0], [fr, I]] [[U, e], [0, S^-1]],

    L unit lower block-bidiagonal (G[k] below the diagonal, block row k), U upper
    block-bidiagonal (pivot blocks P[k]^-1, upper[k] above); e = L^-1 E by the forward
    recurrence e_k = E_k - G_k e_{k-1}, fr = F U^-1 by fr_k = (F_k - fr_{k-1} upper_{k-1}) P_k,
    and S^-1 = M_ll - sum_k fr_k e_k (E_k, F_k nonzero at k = 0 and m - 1 only: the corners).
    P, G, e, fr (m, b, b, K), S (b, b, K); aug (b, 2 b, K) and f (K,) scratch (work_arrays); ok[s]
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
def solve_shifted(lower, upper, rhs, transpose, out, P, G, e, fr, S, v, tail):
    """out[..., s] = M_s^-1 rhs[..., s] (or M_s^-T) for each factorization s (factor_shifted's): rhs
    and out (N, b, K), distinct; v, tail (b, K) scratch (work_arrays). M x = rhs: z = L^-1 rhs (head),
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
def matvec_blocks(diag, lower, upper, x, y):
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


def folded(N: int) -> Array:
    """The block order 0, N - 1, 1, N - 2, 2, ...: in it each block's periodic neighbours are at
    most two places away, so a periodic block-tridiagonal matrix becomes banded (3 b - 1
    diagonals on each side)."""
    order = np.empty(N, np.int64)
    order[0::2], order[1::2] = np.arange((N + 1) // 2), N - 1 - np.arange(N // 2)
    return order
