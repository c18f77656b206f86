"""Periodic block-tridiagonal matrices: shifted solves in O(N b^3) and eigenpair refinement
(issue 26 item 1, the eigenpair continuation's kernel).

A matrix of N x N blocks of size b with blocks only on the diagonal, the first off-diagonals
and the two periodic corners (the disk chain's stability matrix: each disk couples to its two
neighbours, disk N to disk 1):

    row k:   lower[k] x[k-1] + diag[k] x[k] + upper[k] x[k+1] = rhs[k],   indices mod N.

Shifted solves. M = A - sigma I (sigma complex) is factorized with the last block row and
column as a border: T (the first N - 1 block rows and columns) is block tridiagonal without
corners, factorized by block LU without pivoting between blocks (partial pivoting inside each
b x b block), and the border by its Schur complement S = M_ll - F T^-1 E (E: the last block
column, nonzero in block rows 0 and N - 2; F: the last block row). Solves with M and with M^T
each cost O(N b^2) after the factorization. No pivoting between blocks: where a leading
block of T is singular for the shift (a pivot block exactly singular) the factorization gives
non-finite values and the caller falls back to a dense solve (refine_eigenpairs marks the
pair unconverged).

Eigenpair refinement. Two-sided Rayleigh quotient iteration (Ostrowski; Parlett 1974) from a
guess (lambda, r, l) with l^H r = 1:

    M = A - lambda I,   r <- M^-1 r,   l <- M^-H l,   scale so |r| = 1 and l^H r = 1,
    lambda <- l^H A r,

cubically convergent for a simple eigenvalue. Each iteration is one factorization and two
solves, O(N b^3) per eigenpair; all eigenpairs are refined in one compiled loop. The residual
|A r - lambda r| (|r| = 1) and kappa = |l| |r| / |l^H r| bound the eigenvalue's error to first
order by kappa |A r - lambda r| (Wilkinson).
"""
from __future__ import annotations

from dataclasses import dataclass

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

    @property
    def n(self) -> int:
        return self.diag.shape[0] * self.diag.shape[1]

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
        return cls(blocks[1], blocks[0], blocks[2])

    def dense(self) -> Array:
        """The n x n matrix (tests)."""
        N, b = self.diag.shape[:2]
        A = np.zeros((self.n, self.n))
        for k in range(N):
            rows = slice(k * b, (k + 1) * b)
            A[rows, k * b:(k + 1) * b] += self.diag[k]
            prev, nxt = (k - 1) % N, (k + 1) % N
            A[rows, prev * b:(prev + 1) * b] += self.lower[k]
            A[rows, nxt * b:(nxt + 1) * b] += self.upper[k]
        return A

    def solve(self, sigma: complex, rhs: Array, transpose: bool = False) -> Array:
        """x with (A - sigma I) x = rhs (or its transpose), rhs (n,): one factorization."""
        N, b = self.diag.shape[:2]
        factors, scratch, columns = _work(N, b, np.zeros(1, np.complex128))
        ok = _factor(self.diag, self.lower, self.upper, complex(sigma), *factors, *scratch)
        x = np.empty((N, b), np.complex128)
        _solve(self.lower, self.upper, np.asarray(rhs, np.complex128).reshape(N, b), transpose, x,
               *factors, *columns)
        return x.ravel() if ok else np.full(self.n, np.nan + 0j)

    def matvec(self, x: Array) -> Array:
        """A x for x (n,), complex."""
        N, b = self.diag.shape[:2]
        y = np.empty((N, b), np.complex128)
        _matvec(self.diag, self.lower, self.upper, np.asarray(x, np.complex128).reshape(N, b), y)
        return y.ravel()


def disk_major(N: int, b: int) -> Array:
    """The order that takes field-major unknowns (index f N + k for field f of disk k) to
    disk-major ones (k b + f): PeriodicBlocks.from_matrix's `order` for the disk chain."""
    return np.arange(N * b).reshape(b, N).T.ravel()


@numba.njit(cache=True)
def _work(N, b, proto):
    """A factorization's arrays, of proto's dtype (real for a real shift): the pivot blocks'
    inverses P^-1, the multipliers G, T^-1 E and T^-T F^T (m, b, b), S^-1 (b, b), m = N - 1;
    then _factor's scratch (e, ft, w, block) and _solve's (head, y, w1, tail)."""
    m = N - 1
    dtype = proto.dtype
    factors = (np.empty((m, b, b), dtype), np.empty((m, b, b), dtype), np.empty((m, b, b), dtype),
               np.empty((m, b, b), dtype), np.empty((b, b), dtype))
    scratch = (np.empty((m, b, b), dtype), np.empty((m, b, b), dtype), np.empty((m, b, b), dtype),
               np.empty((b, b), dtype))
    columns = (np.empty((m, b, 1), dtype), np.empty((m, b, 1), dtype), np.empty((m, b, 1), dtype),
               np.empty(b, dtype))
    return factors, scratch, columns


@numba.njit(cache=True)
def _invert(a, out):
    """out = a^-1 (b x b complex) by Gauss-Jordan with partial pivoting; False if singular."""
    b = a.shape[0]
    aug = np.empty((b, 2 * b), out.dtype)
    for i in range(b):
        for j in range(b):
            aug[i, j] = a[i, j]
            aug[i, b + j] = 1.0 if i == j else 0.0
    for c in range(b):
        p, best = c, abs(aug[c, c])
        for r in range(c + 1, b):
            if abs(aug[r, c]) > best:
                p, best = r, abs(aug[r, c])
        if best == 0.0:
            return False
        if p != c:
            for j in range(2 * b):
                aug[c, j], aug[p, j] = aug[p, j], aug[c, j]
        piv = 1.0 / aug[c, c]
        for j in range(2 * b):
            aug[c, j] *= piv
        for r in range(b):
            if r != c and aug[r, c] != 0.0:
                f = aug[r, c]
                for j in range(2 * b):
                    aug[r, j] -= f * aug[c, j]
    for i in range(b):
        for j in range(b):
            out[i, j] = aug[i, b + j]
    return True


@numba.njit(cache=True)
def _mul_sub(c, a, bmat, transpose_b):
    """c -= a @ bmat (or a @ bmat^T), b x b."""
    b = c.shape[0]
    for i in range(b):
        for j in range(b):
            s = 0.0
            for k in range(b):
                s += a[i, k] * (bmat[j, k] if transpose_b else bmat[k, j])
            c[i, j] -= s


@numba.njit(cache=True)
def _tsolve(pinv, mult, upper, rhs, transpose, out, w):
    """out = T^-1 rhs (or T^-T rhs), rhs, out and the scratch w (m, b, c): c right-hand sides
    at once."""
    m, b, ncol = rhs.shape
    if not transpose:
        for k in range(m):  # L w = rhs, L unit lower block bidiagonal (mult)
            for i in range(b):
                for c in range(ncol):
                    s = rhs[k, i, c]
                    if k > 0:
                        for j in range(b):
                            s -= mult[k, i, j] * w[k - 1, j, c]
                    w[k, i, c] = s
        for k in range(m - 1, -1, -1):  # U x = w: U has pivots P_k and upper[k]
            for i in range(b):
                for c in range(ncol):
                    s = w[k, i, c]
                    if k < m - 1:
                        for j in range(b):
                            s -= upper[k, i, j] * out[k + 1, j, c]
                    w[k, i, c] = s
            for i in range(b):
                for c in range(ncol):
                    s = 0.0
                    for j in range(b):
                        s += pinv[k, i, j] * w[k, j, c]
                    out[k, i, c] = s
    else:
        for k in range(m):  # U^T w = rhs
            for i in range(b):
                for c in range(ncol):
                    s = rhs[k, i, c]
                    if k > 0:
                        for j in range(b):
                            s -= upper[k - 1, j, i] * w[k - 1, j, c]
                    out[k, i, c] = s
            for i in range(b):
                for c in range(ncol):
                    s = 0.0
                    for j in range(b):
                        s += pinv[k, j, i] * out[k, j, c]
                    w[k, i, c] = s
        for k in range(m - 1, -1, -1):  # L^T x = w
            for i in range(b):
                for c in range(ncol):
                    s = w[k, i, c]
                    if k < m - 1:
                        for j in range(b):
                            s -= mult[k + 1, j, i] * out[k + 1, j, c]
                    out[k, i, c] = s


@numba.njit(cache=True)
def _factor(diag, lower, upper, sigma, pinv, mult, z, zt, sinv, e, ft, w, block):
    """Factorize M = A - sigma I (module docstring) into the work arrays (e, ft, w: (m, b, b)
    scratch; block: (b, b) scratch); False if a pivot block or the Schur complement is
    singular."""
    N, b = diag.shape[0], diag.shape[1]
    m = N - 1
    for k in range(m):
        for i in range(b):
            for j in range(b):
                block[i, j] = diag[k, i, j]
            block[i, i] -= sigma
        if k > 0:
            for i in range(b):  # G_k = lower[k] P_{k-1}^-1
                for j in range(b):
                    s = 0.0
                    for t in range(b):
                        s += lower[k, i, t] * pinv[k - 1, t, j]
                    mult[k, i, j] = s
            _mul_sub(block, mult[k], upper[k - 1], False)
        if not _invert(block, pinv[k]):
            return False
    # E: block rows 0 (lower[0], the corner) and m - 1 (upper[m - 1]) of the last block column;
    # F^T: the transposed last block row, block columns 0 (upper[N - 1], the corner), m - 1 (lower[N - 1])
    e[0] = 0.0
    e[m - 1] = 0.0
    ft[0] = 0.0
    ft[m - 1] = 0.0
    for k in range(1, m - 1):
        e[k] = 0.0
        ft[k] = 0.0
    for i in range(b):
        for j in range(b):
            e[0, i, j] += lower[0, i, j]
            e[m - 1, i, j] += upper[m - 1, i, j]
            ft[0, i, j] += upper[N - 1, j, i]
            ft[m - 1, i, j] += lower[N - 1, j, i]
    _tsolve(pinv, mult, upper, e, False, z, w)
    _tsolve(pinv, mult, upper, ft, True, zt, w)
    for i in range(b):  # S = M_ll - F T^-1 E
        for j in range(b):
            s = diag[N - 1, i, j] - (sigma if i == j else 0.0)
            for t in range(b):
                s -= upper[N - 1, i, t] * z[0, t, j] + lower[N - 1, i, t] * z[m - 1, t, j]
            block[i, j] = s
    return _invert(block, sinv)


@numba.njit(cache=True)
def _solve(lower, upper, rhs, transpose, out, pinv, mult, z, zt, sinv, head, y, w1, tail):
    """out = M^-1 rhs (or M^-T rhs), rhs and out (N, b), with _factor's arrays (head, y, w1:
    (m, b, 1) scratch; tail: (b,) scratch)."""
    N, b = rhs.shape
    m = N - 1
    for k in range(m):
        for i in range(b):
            head[k, i, 0] = rhs[k, i]
    _tsolve(pinv, mult, upper, head, transpose, y, w1)
    for i in range(b):  # rhs_l - F y, or rhs_l - E^T y
        s = rhs[N - 1, i]
        for t in range(b):
            if transpose:
                s -= lower[0, t, i] * y[0, t, 0] + upper[m - 1, t, i] * y[m - 1, t, 0]
            else:
                s -= upper[N - 1, i, t] * y[0, t, 0] + lower[N - 1, i, t] * y[m - 1, t, 0]
        tail[i] = s
    for i in range(b):
        s = 0.0
        for t in range(b):
            s += (sinv[t, i] if transpose else sinv[i, t]) * tail[t]
        out[N - 1, i] = s
    zz = zt if transpose else z
    for k in range(m):
        for i in range(b):
            s = y[k, i, 0]
            for t in range(b):
                s -= zz[k, i, t] * out[N - 1, t]
            out[k, i] = s


@numba.njit(cache=True)
def _matvec(diag, lower, upper, x, y):
    """y = A x, x and y (N, b)."""
    N, b = x.shape
    for k in range(N):
        prev, nxt = (k - 1) % N, (k + 1) % N
        for i in range(b):
            s = 0.0
            for j in range(b):
                s += diag[k, i, j] * x[k, j] + lower[k, i, j] * x[prev, j] + upper[k, i, j] * x[nxt, j]
            y[k, i] = s


@numba.njit(cache=True)
def _orthonormal(V):
    """The rows of V (k, n) replaced by an orthonormal basis of their span (QR)."""
    q, _ = np.linalg.qr(np.ascontiguousarray(V.T))
    return np.ascontiguousarray(q.T)


@numba.njit(cache=True)
def _refine(diag, lower, upper, values, right, left, starts, members, iterations, tol, largest):
    """Block two-sided Rayleigh quotient iteration of every cluster of eigenpairs (module
    docstring), in place: values (n,), right (n, n) columns, left (n, n) rows (l^H as
    spectra.Eigensystem stores them); cluster c holds members[starts[c]:starts[c + 1]]; at most
    `iterations` steps, fewer once every member's residual is <= tol. Returns each pair's
    residual |A r - lambda r| with |r| = 1 (inf where a factorization failed, or for the
    members of a cluster larger than `largest`, which is left as it was)."""
    N, b = diag.shape[0], diag.shape[1]
    n = N * b
    residual = np.full(n, np.inf)
    for c in range(starts.size - 1):
        idx = members[starts[c]:starts[c + 1]]
        k = idx.size
        if k > largest:
            continue
        factors, scratch, columns = _work(N, b, np.zeros(1, np.complex128))
        X = np.empty((k, n), np.complex128)  # right vectors, one per row
        Y = np.empty((k, n), np.complex128)  # conj(left vectors): l^H x = sum(Y[j] * x)
        for j in range(k):
            X[j] = right[:, idx[j]]
            Y[j] = left[idx[j]]
        theta = values[idx].copy()
        x = np.empty((N, b), np.complex128)
        ax = np.empty((N, b), np.complex128)
        res = np.full(k, np.inf)
        failed = False
        for _ in range(iterations):
            sigma = np.mean(theta)
            if not _factor(diag, lower, upper, sigma, *factors, *scratch):
                failed = True
                break
            for j in range(k):
                _solve(lower, upper, X[j].reshape(N, b), False, x, *factors, *columns)
                X[j] = x.ravel()
                _solve(lower, upper, Y[j].reshape(N, b), True, x, *factors, *columns)
                Y[j] = x.ravel()
            if not (np.all(np.isfinite(X)) and np.all(np.isfinite(Y))):
                failed = True
                break
            X, Y = _orthonormal(X), _orthonormal(Y)
            G = np.empty((k, k), np.complex128)  # Y^H X in l^H r terms: G[a, b] = l_a^H x_b
            H = np.empty((k, k), np.complex128)  # l_a^H A x_b
            for j in range(k):
                _matvec(diag, lower, upper, X[j].reshape(N, b), ax)
                axr = ax.ravel()
                for a in range(k):
                    G[a, j] = np.sum(Y[a] * X[j])
                    H[a, j] = np.sum(Y[a] * axr)
            Ginv = np.linalg.inv(G)
            theta, W = np.linalg.eig(Ginv @ H)
            Winv_Ginv = np.linalg.inv(W) @ Ginv
            Xn = np.zeros((k, n), np.complex128)
            Yn = np.zeros((k, n), np.complex128)
            for j in range(k):
                for a in range(k):
                    Xn[j] += W[a, j] * X[a]
                    Yn[j] += Winv_Ginv[j, a] * Y[a]
            for j in range(k):  # |r| = 1, l^H r = 1
                scale = np.sqrt(np.sum(np.abs(Xn[j]) ** 2))
                Xn[j] /= scale
                Yn[j] *= scale
            X, Y = Xn, Yn
            if not np.all(np.isfinite(theta)):
                failed = True
                break
            for j in range(k):
                _matvec(diag, lower, upper, X[j].reshape(N, b), ax)
                res[j] = np.sqrt(np.sum(np.abs(ax.ravel() - theta[j] * X[j]) ** 2))
            if res.max() <= tol:
                break
        if failed:
            continue
        if k > 1 and res.max() > tol:
            # the cluster's one shift converges linearly; each member's own shift cubically
            for j in range(k):
                for _ in range(2):
                    if res[j] <= tol or not _factor(diag, lower, upper, theta[j], *factors, *scratch):
                        break
                    _solve(lower, upper, X[j].reshape(N, b), False, x, *factors, *columns)
                    xr = x.ravel().copy()
                    _solve(lower, upper, Y[j].reshape(N, b), True, x, *factors, *columns)
                    yr = x.ravel().copy()
                    norm = np.sqrt(np.sum(np.abs(xr) ** 2))
                    overlap = np.sum(yr * xr) / norm
                    if not (np.isfinite(norm) and norm > 0.0 and np.isfinite(abs(overlap)) and overlap != 0.0):
                        break
                    X[j] = xr / norm
                    Y[j] = yr / overlap
                    _matvec(diag, lower, upper, X[j].reshape(N, b), ax)
                    theta[j] = np.sum(Y[j] * ax.ravel())
                    res[j] = np.sqrt(np.sum(np.abs(ax.ravel() - theta[j] * X[j]) ** 2))
        for j in range(k):
            residual[idx[j]] = res[j]
            values[idx[j]] = theta[j]
            right[:, idx[j]] = X[j]
            left[idx[j]] = Y[j]
    return residual


@numba.njit(cache=True)
def _rqi_many(diag, lower, upper, values, right, left, iterations, tol):
    """Two-sided Rayleigh quotient iteration of each pair alone, in place, in the dtype of
    `right` (real pairs in real arithmetic, four times cheaper): values (k,), right (n, k)
    columns, left (k, n) rows (conj(l) entries: l^H x = sum(left[j] * x)). Returns the
    residuals (inf where a factorization failed)."""
    N, b = diag.shape[0], diag.shape[1]
    n, k = right.shape
    factors, scratch, columns = _work(N, b, right[:1, 0])
    r = np.empty((N, b), right.dtype)
    lc = np.empty((N, b), right.dtype)
    x = np.empty((N, b), right.dtype)
    ax = np.empty((N, b), right.dtype)
    residual = np.full(k, np.inf)
    for p in range(k):
        for t in range(n):
            r[t // b, t % b] = right[t, p]
            lc[t // b, t % b] = left[p, t]
        lam = values[p]
        res = np.inf
        for _ in range(iterations):
            if not _factor(diag, lower, upper, lam, *factors, *scratch):
                res = np.inf
                break
            _solve(lower, upper, r, False, x, *factors, *columns)
            r[:] = x
            _solve(lower, upper, lc, True, x, *factors, *columns)
            lc[:] = x
            norm = np.sqrt(np.sum(np.abs(r) ** 2))
            overlap = np.sum(lc * r) / norm
            if not (np.isfinite(norm) and norm > 0.0 and np.isfinite(abs(overlap)) and overlap != 0.0):
                res = np.inf
                break
            r /= norm
            lc /= overlap
            _matvec(diag, lower, upper, r, ax)
            lam = np.sum(lc * ax)
            res = np.sqrt(np.sum(np.abs(ax - lam * r) ** 2))
            if res <= tol:
                break
        if not np.isfinite(res):
            continue
        residual[p] = res
        values[p] = lam
        for t in range(n):
            right[t, p] = r[t // b, t % b]
            left[p, t] = lc[t // b, t % b]
    return residual


def clusters(guess: Array, reach: Array) -> tuple[Array, Array]:
    """The eigenpairs to refine together: i and j are linked when their predicted eigenvalues
    are closer than reach_i + reach_j (reach: how far each may be from its prediction), and a
    cluster is a connected set of links. Returns (starts, members) as _refine takes them."""
    return _clusters(np.asarray(guess, np.complex128), np.asarray(reach, float))


@numba.njit(cache=True)
def _clusters(values, reach):
    n = values.size
    parent = np.arange(n)
    order = np.argsort(values.real)
    widest = 2.0 * reach.max()
    for a in range(n):
        i = order[a]
        for c in range(a + 1, n):
            j = order[c]
            if values[j].real - values[i].real > widest:
                break
            if abs(values[i] - values[j]) <= reach[i] + reach[j]:
                ri, rj = i, j
                while parent[ri] != ri:
                    ri = parent[ri]
                while parent[rj] != rj:
                    rj = parent[rj]
                if ri != rj:
                    parent[max(ri, rj)] = min(ri, rj)
    root = np.empty(n, np.int64)
    for i in range(n):
        r = i
        while parent[r] != r:
            r = parent[r]
        root[i] = r
    members = np.argsort(root, kind="mergesort")
    starts = [0]
    for a in range(1, n):
        if root[members[a]] != root[members[a - 1]]:
            starts.append(a)
    starts.append(n)
    return np.array(starts, np.int64), members.astype(np.int64)


LARGEST_CLUSTER = 16
"""Clusters of more eigenpairs are not refined (refine_eigenpairs: residual inf): one shift
serves a cluster, and the farther its members lie from it, the slower they converge."""


def refine_eigenpairs(blocks: PeriodicBlocks, values: Array, right: Array, left: Array,
                      reach: Array, iterations: int = 6, tol: float = 0.0
                      ) -> tuple[Array, Array, Array, Array]:
    """Every eigenpair of `blocks`' matrix refined from the guesses (values (n,), right vectors
    as columns, left vectors as rows l_i^H with l_i^H r_i = 1: spectra.Eigensystem's layout) by
    at most `iterations` block two-sided Rayleigh quotient steps (fewer once each residual is
    <= tol) on the clusters of pairs whose guesses are within reach of each other (clusters;
    module docstring). Returns new (values, right, left, residual): |r_i| = 1, l_i^H r_i = 1,
    residual_i = |A r_i - lambda_i r_i| (inf where a factorization failed or a cluster has
    more than LARGEST_CLUSTER pairs)."""
    values = np.array(values, np.complex128)
    right = np.array(right, np.complex128)
    left = np.array(left, np.complex128)
    starts, members = clusters(values, reach)
    sizes = np.diff(starts)
    alone = members[starts[:-1][sizes == 1]]
    real = alone[(values[alone].imag == 0.0) & ~np.any(right[:, alone].imag, axis=0)
                 & ~np.any(left[alone].imag, axis=1)]
    residual = np.full(values.size, np.inf)
    A = (blocks.diag, blocks.lower, blocks.upper)
    for picked, dtype in ((real, float), (np.setdiff1d(alone, real), complex)):
        part = (values[picked], right[:, picked], left[picked])
        v, r, lft = (a.real.copy() if dtype is float else a for a in part)
        residual[picked] = _rqi_many(*A, v, r, lft, iterations, tol)
        values[picked], right[:, picked], left[picked] = v, r, lft
    grouped = np.flatnonzero(sizes > 1)
    if grouped.size:
        spans = [members[starts[c]:starts[c + 1]] for c in grouped]
        group_starts = np.concatenate([[0], np.cumsum([span.size for span in spans])])
        residual_grouped = _refine(*A, values, right, left, group_starts, np.concatenate(spans),
                                   iterations, tol, LARGEST_CLUSTER)
        together = np.concatenate(spans)
        residual[together] = residual_grouped[together]
    return values, right, left, residual


def separated(values: Array, bounds: Array) -> bool:
    """Whether the discs |z - values_i| <= bounds_i are pairwise disjoint: then each holds a
    different eigenvalue, and n of them hold the whole spectrum of an n x n matrix."""
    return bool(_separated(np.asarray(values, np.complex128), np.asarray(bounds, float)))


@numba.njit(cache=True)
def _separated(values, bounds):
    order = np.argsort(values.real)
    n = values.size
    for a in range(n):
        i = order[a]
        for c in range(a + 1, n):
            j = order[c]
            if values[j].real - values[i].real > bounds[i] + bounds[j]:
                break  # sorted by real part: no later disc can reach disc i
            if abs(values[i] - values[j]) <= bounds[i] + bounds[j]:
                return False
    return True
