"""Linear algebra of the core: dense or sparse, chosen by the matrix a problem returns.

Every solve of the core is with a bordered matrix

    [[K, c], [b^T, d]]      K (n x n) dense ndarray or scipy.sparse, c, b (n,), d scalar,

(K = G_u with c = G_p for the corrector and the tangent, K = A - lambda I for the collision
locator). A dense K is factorized by LAPACK (getrf, O(n^3)); a sparse K by SuperLU on the
bordered matrix in CSC form (the border adds 2n + 1 entries; for the disk chain, a
block-tridiagonal K with periodic corners, fill-in stays O(n)). Both factorizations solve with
the matrix and with its transpose (left null vectors of the locator).

BLAS threads. OpenBLAS starts a thread per core even for 30 x 30 matrices, and on a machine
where anything else runs, threads that wait for each other cost far more than they give (a
dense eigendecomposition several times slower on two threads than on one). `blas_threads()`
therefore runs the core on one BLAS
thread (threadpoolctl) whatever the size; the other core stays free for another job (a dask
worker, a second sweep).

Memory. A continuation runs inside `heap_kept()`: glibc keeps the memory the process frees
and hands it out again, instead of unmapping every large block and having the kernel zero
fresh pages for the next one.
"""
from __future__ import annotations

import contextlib
import ctypes
import functools
from dataclasses import astuple, dataclass, fields
from typing import Callable, Optional, Union

import numba
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from diskfriction.continuation.linalg import orderings
from diskfriction.continuation.linalg.triangular import TriangularFactors

Array = np.ndarray
Matrix = Union[Array, sp.spmatrix, sp.sparray]

@dataclass
class Work:
    """What the core spent: full eigendecompositions (dense, O(n^3)), partial ones (a few
    eigenvalues near a shift: nearest.py), LU factorizations and triangular solves; full
    spectra refined from a nearby sample's instead of decomposed, those of them certified only
    after a repair by shift-invert, and refinements declined by their certificate
    (refinement.py; a dense spectrum was taken instead). Printed by benchmarks/scaling.py."""

    spectra: int = 0
    spectra_partial: int = 0
    factorizations: int = 0
    solves: int = 0
    spectra_refined: int = 0
    refinements_declined: int = 0
    refinements_repaired: int = 0

    def counts(self) -> tuple[int, ...]:
        return astuple(self)

    def add(self, counts: tuple[int, ...]) -> None:
        for f, n in zip(fields(self), counts):
            setattr(self, f.name, getattr(self, f.name) + n)


_LEDGER = Work()
"""Everything this process's core has spent, scan workers' results included (book). Only
ever added to: what a piece of work cost is read with measured(), never by resetting it."""


def book(kind: str, n: int = 1) -> None:
    """Add n of `kind` (a Work field: "spectra", "solves", ...) to the ledger."""
    setattr(_LEDGER, kind, getattr(_LEDGER, kind) + n)


def book_counts(counts: tuple[int, ...]) -> None:
    """Add the counts of work done elsewhere (a scan worker's, ScanOutcome.spent)."""
    _LEDGER.add(counts)


@contextlib.contextmanager
def measured():
    """The work the core spends inside the block, scan workers' booked results included: a
    Work that holds it once the block ends (`with measured() as spent: ...; spent.spectra`)."""
    before, spent = _LEDGER.counts(), Work()
    try:
        yield spent
    finally:
        spent.add(tuple(a - b for a, b in zip(_LEDGER.counts(), before)))


class SingularMatrix(np.linalg.LinAlgError):
    """A factorization met an exactly singular (or non-finite) matrix."""


def dense(K: Matrix) -> Array:
    """K as a dense ndarray (no copy if it is one)."""
    return K.toarray() if sp.issparse(K) else np.asarray(K)


def same_matrix(A: Matrix, B: Matrix) -> bool:
    """Whether A and B hold the same values (dense or sparse, whatever the sparse pattern
    stores)."""
    if A.shape != B.shape or sp.issparse(A) != sp.issparse(B):
        return False
    if sp.issparse(A):
        return (A != B).nnz == 0
    return bool(np.array_equal(A, B))


def bordered(K: Matrix, c: Array, b: Array, d: float = 0.0) -> Matrix:
    """[[K, c], [b^T, d]], dense if K is dense, CSC if K is sparse."""
    n = K.shape[0]
    if not sp.issparse(K):
        M = np.empty((n + 1, n + 1))
        M[:n, :n] = K
        M[:n, n] = c
        M[n, :n] = b
        M[n, n] = d
        return M
    # CSC built directly by one compiled pass over K's CSR arrays: every column of K gains the
    # border entry b_j in row n, then the column [c; d] (a COO round trip, or scipy's CSC
    # conversion with its sum of duplicates and inserts, costs a good part of a factorization)
    K = K if K.format == "csr" else sp.csr_array(K)
    data, indices, indptr = _bordered_csc(K.indptr, K.indices, K.data, np.asarray(c, dtype=float),
                                          np.asarray(b, dtype=float), float(d), n)
    return sp.csc_array((data, indices, indptr), shape=(n + 1, n + 1))


@numba.njit(cache=True)
def _bordered_csc(indptr, indices, data, c, b, d, n):
    """CSC arrays (data, indices, indptr) of [[K, c], [b^T, d]] from K's CSR arrays (n x n):
    row indices sorted within each column, duplicates summed, explicit zeros kept (as scipy's
    CSC conversion and sum_duplicates give them)."""
    count = np.zeros(n + 1, np.int64)
    for k in range(indptr[n]):
        count[indices[k] + 1] += 1
    for j in range(n):
        count[j + 1] += count[j]
    rows = np.empty(indptr[n], np.int64)
    values = np.empty(indptr[n])
    fill = count[:n].copy()
    for i in range(n):  # rows in order: each column's rows come out sorted
        for k in range(indptr[i], indptr[i + 1]):
            j = indices[k]
            rows[fill[j]] = i
            values[fill[j]] = data[k]
            fill[j] += 1
    out_indptr = np.zeros(n + 2, np.int32)
    out_rows = np.empty(indptr[n] + 2 * n + 1, np.int32)
    out_data = np.empty(indptr[n] + 2 * n + 1)
    m = 0
    for j in range(n):
        for k in range(count[j], count[j + 1]):
            if k > count[j] and rows[k] == rows[k - 1]:
                out_data[m - 1] += values[k]
            else:
                out_rows[m] = rows[k]
                out_data[m] = values[k]
                m += 1
        out_rows[m] = n
        out_data[m] = b[j]
        m += 1
        out_indptr[j + 1] = m
    for i in range(n):
        out_rows[m] = i
        out_data[m] = c[i]
        m += 1
    out_rows[m] = n
    out_data[m] = d
    m += 1
    out_indptr[n + 1] = m
    return out_data[:m], out_rows[:m], out_indptr


_getrs = sla.get_lapack_funcs("getrs", dtype=float)


COPY_FACTORS_AT = 4
"""The solve from which a sparse factorization solves with its copied triangular factors
(triangular.py: the copy costs four to seven of SuperLU's solves and saves 36-70% of each
later one)."""


@dataclass
class Factorization:
    """An LU factorization of a square matrix; solve(r) = M^-1 r, solve(r, transpose=True) =
    M^-T r. Counts its solves in `solves`. A sparse one solves with SuperLU, and from its
    COPY_FACTORS_AT-th solve on by compiled substitution over SuperLU's factors (triangular.py,
    the same factors: the results agree to rounding)."""

    lu: object
    sparse: bool
    solves: int = 0
    triangular: Optional[TriangularFactors] = None

    def solve(self, rhs: Array, transpose: bool = False) -> Array:
        self.solves += 1
        book("solves")
        if self.sparse and self.triangular is None and self.solves >= COPY_FACTORS_AT:
            self.triangular = TriangularFactors.of(self.lu)
        if self.triangular is not None:
            x = self.triangular.solve(rhs, transpose)
        elif self.sparse:
            x = self.lu.solve(np.ascontiguousarray(rhs, dtype=float), trans="T" if transpose else "N")
        else:
            # LAPACK's getrs directly: scipy's lu_solve wrapper costs several times the solve
            # itself at n = 30 (benchmarks/continuation_speed.py)
            x, _ = _getrs(*self.lu, rhs, trans=1 if transpose else 0)
        if not np.all(np.isfinite(x)):
            raise SingularMatrix("solve produced non-finite values")
        return x


def factorize(M: Matrix, ordering: Optional[dict] = None) -> Factorization:
    """LU of M (dense getrf or sparse SuperLU, with `ordering` its keyword arguments, None:
    SuperLU's defaults, COLAMD and partial pivoting; a pattern factorized before keeps its
    column order: orderings.py); raises SingularMatrix if M is singular."""
    book("factorizations")
    if sp.issparse(M):
        M = M if M.format == "csc" else sp.csc_array(M)
        empty = _empty_line(M)
        if empty is not None:  # SuperLU would print BLAS errors (DGEMV) before failing
            raise SingularMatrix(f"matrix has an empty {empty}")
        try:
            return Factorization(orderings.splu(M, ordering), True)
        except RuntimeError as err:  # SuperLU: "Factor is exactly singular"
            raise SingularMatrix(str(err)) from None
    M = np.asarray(M, dtype=float)
    if not np.all(np.isfinite(M)):
        raise SingularMatrix("matrix has non-finite entries")
    lu, piv, info = sla.lapack.dgetrf(M)
    if info > 0:
        raise SingularMatrix(f"matrix is exactly singular (pivot {info})")
    return Factorization((lu, piv), False)


@dataclass(frozen=True)
class LinearSolver:
    """How the core solves its linear systems (the corrector's and the tangent's bordered
    matrices, the collision locator's; a choice of the run: Options.linear_solver,
    ContinuationParams.linear_solver), as BifurcationKit's linsolver: a dense matrix by LAPACK's
    LU (getrf), a sparse one by SuperLU with partial pivoting and the column ordering
    `ordering`, scipy's splu permc_spec (None: SuperLU's default, COLAMD; "MMD_AT_PLUS_A":
    minimum degree on the pattern of A + A^T, for a structurally symmetric matrix; "MMD_ATA",
    "NATURAL"). Which of the two a system takes is the matrix's: what the problem's jacobian
    returns."""

    ordering: Optional[str] = None

    ORDERINGS = ("COLAMD", "MMD_AT_PLUS_A", "MMD_ATA", "NATURAL")

    def __post_init__(self):
        if self.ordering is not None and self.ordering not in self.ORDERINGS:
            raise ValueError(f"ordering must be one of {self.ORDERINGS} or None, got {self.ordering!r}")

    @property
    def options(self) -> Optional[dict]:
        """SuperLU's keyword arguments (factorize's `ordering`), None: its defaults."""
        return None if self.ordering is None else dict(permc_spec=self.ordering)

    def factorize(self, M: Matrix) -> Factorization:
        """The LU of M (factorize)."""
        return factorize(M, self.options)


DIRECT = LinearSolver()
"""The linear solver of a run that names none: LAPACK, or SuperLU with its default ordering."""


REFINE_TOL = 1e-14
"""solve_near accepts a solution once a correction is at most this fraction of it (max norms)."""
REFINE_STEPS = 6
"""The most corrections solve_near makes."""
REFINE_RATE = 1e-3
"""solve_near gives up at once where its first correction is above this fraction of the first
solution: the factorized matrix is too far from M for a few corrections to converge."""
REFINE_FLOOR = 1e-9
"""Where the corrections stop shrinking (by 10 times each) before REFINE_TOL, they have reached
the rounding of the residual times M's condition (on the locator's bordered matrices near a
Jordan block, 1e-13 to 2e-12 of the solution), which bounds a fresh factorization's solve as
well: solve_near accepts the solution there if the corrections are below this fraction."""


def solve_near(lu, apply, rhs: Array, transpose: bool = False) -> Optional[Array]:
    """M^-1 rhs (M^-T rhs with transpose) by iterative refinement on `lu`, the factorization
    (anything with Factorization's solve) of a matrix M_0 near M:

        x_0 = M_0^-1 rhs,    x_(k+1) = x_k + M_0^-1 (rhs - M x_k),

    which converges at the rate |M_0^-1 (M - M_0)| down to the rounding of the residual.
    apply(y) = M y (M^T y with transpose). Converged where a correction is within REFINE_TOL
    of the solution, or where the corrections stop shrinking within REFINE_FLOOR of it (the
    rounding floor). Returns None where the first correction is above REFINE_RATE |x_0|, where
    REFINE_STEPS do not converge or a solve is not finite (the caller then factorizes M). No
    factorization: a solve and a product per correction against SuperLU's LU."""
    try:
        x = lu.solve(rhs, transpose)
    except SingularMatrix:
        return None
    size, last = float(np.max(np.abs(x), initial=0.0)), np.inf
    for k in range(REFINE_STEPS):
        try:
            dx = lu.solve(rhs - apply(x), transpose)
        except SingularMatrix:
            return None
        x = x + dx
        change = float(np.max(np.abs(dx), initial=0.0))
        if not np.isfinite(change) or (k == 0 and change > REFINE_RATE * size):
            return None
        if change <= REFINE_TOL * size:
            return x
        if change > 0.1 * last:  # no longer shrinking: the rounding floor
            return x if change <= REFINE_FLOOR * size else None
        size, last = float(np.max(np.abs(x))), change
    return None


@dataclass
class RefinedSolve:
    """Solves with a matrix M known by its products (apply(y) = M y, apply_t(y) = M^T y) on
    `near`, the factorization of a matrix nearby (solve_near, anything with Factorization's
    solve; None: none); where that does not converge, M is built (matrix()) and factorized
    once, and every later solve uses that factorization. Worth it where M is solved a few
    times at most: every solve on `near` is refined on its own. apply_t may be None where M^T
    is never solved."""

    matrix: object
    apply: object
    apply_t: object
    near: Optional[object] = None
    options: Optional[dict] = None
    fresh: Optional[Factorization] = None

    def solve(self, rhs: Array, transpose: bool = False) -> Array:
        if self.fresh is None and self.near is not None:
            x = solve_near(self.near, self.apply_t if transpose else self.apply, rhs, transpose)
            if x is not None:
                return x
        if self.fresh is None:
            self.fresh = factorize(self.matrix(), self.options)
        return self.fresh.solve(rhs, transpose)


def _empty_line(M: sp.csc_array) -> Optional[str]:
    """"row" or "column" if the sparse M has one without a nonzero value (exactly singular),
    else None. O(nnz), one compiled pass, no sparse copies."""
    return (None, "column", "row")[_empty_kind(M.indptr, M.indices, M.data, M.shape[0])]


@numba.njit(cache=True)
def _empty_kind(indptr, indices, data, rows: int) -> int:
    """0: every row and column of the CSC arrays holds a nonzero; 1: a column does not; 2: a
    row does not (columns first)."""
    seen = np.zeros(rows, np.bool_)
    for j in range(indptr.size - 1):
        empty = True
        for k in range(indptr[j], indptr[j + 1]):
            if data[k] != 0.0:
                empty = False
                seen[indices[k]] = True
        if empty:
            return 1
    for i in range(rows):
        if not seen[i]:
            return 2
    return 0


def log_determinant(M: Matrix) -> tuple[float, float]:
    """(sign, log|det M|) of a dense or sparse square M by LU (sign 0 and -inf if singular)."""
    if not sp.issparse(M):
        sign, logabs = np.linalg.slogdet(np.asarray(M, dtype=float))
        return float(sign), float(logabs)
    try:
        lu = spla.splu(sp.csc_array(M))
    except RuntimeError:  # exactly singular
        return 0.0, -np.inf
    diagonal = lu.U.diagonal()
    sign = np.prod(np.sign(diagonal)) * _parity(lu.perm_r) * _parity(lu.perm_c)
    return float(sign), float(np.sum(np.log(np.abs(diagonal))))


def _parity(permutation: Array) -> int:
    """+1 for an even permutation, -1 for an odd one (from its cycles)."""
    seen, sign = np.zeros(permutation.size, bool), 1
    for start in range(permutation.size):
        length, k = 0, start
        while not seen[k]:
            seen[k], k, length = True, permutation[k], length + 1
        if length % 2 == 0 and length > 0:
            sign = -sign
    return sign


def solve(M: Matrix, rhs: Array) -> Array:
    """M^-1 rhs by one factorization."""
    return factorize(M).solve(rhs)


@functools.lru_cache(maxsize=1)
def _controller():
    """threadpoolctl's view of the loaded BLAS libraries, made once (about 1 ms each time)."""
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


def blas_threads():
    """Context running BLAS on one thread (module docstring)."""
    return _controller().limit(limits=1, user_api="blas")


M_TRIM_THRESHOLD, M_MMAP_MAX = -1, -4
"""glibc's mallopt parameters (malloc.h)."""
KEPT_HEAP = 2 ** 31 - 1
"""Free memory at the top of the heap that glibc keeps while heap_kept is active (mallopt's
int limit, 2 GiB)."""
_kept = [0]  # heap_kept's nesting depth


@functools.lru_cache(maxsize=1)
def _glibc():
    """The process's C library where it is glibc (mallopt, malloc_trim), else None."""
    try:
        libc = ctypes.CDLL(None)
    except OSError:
        return None
    return libc if all(hasattr(libc, f) for f in ("gnu_get_libc_version", "mallopt", "malloc_trim")) else None


@contextlib.contextmanager
def heap_kept():
    """Context in which glibc keeps freed memory for the process to reuse: every allocation
    from the heap (mallopt M_MMAP_MAX 0) and up to KEPT_HEAP of free memory at its top kept
    (M_TRIM_THRESHOLD); on leaving, glibc's defaults (65536 mappings, 128 KiB) and the free
    memory returned (malloc_trim). By default glibc maps each allocation above 32 MiB on its
    own and unmaps it when freed, so the next one comes as fresh pages that the kernel zeroes:
    a full sample of 1000 disks allocates 288 MB of eigenvectors, and a sweep would spend a
    fifth of its time in the kernel zeroing pages. The resident memory then stays at its peak
    until the context ends. Elsewhere than glibc: nothing changes. Forked scan workers inherit
    the setting."""
    libc = _glibc()
    if libc is None:
        yield
        return

    def keep() -> None:
        libc.mallopt(M_MMAP_MAX, 0)
        libc.mallopt(M_TRIM_THRESHOLD, KEPT_HEAP)

    def release() -> None:
        libc.mallopt(M_MMAP_MAX, 65536)
        libc.mallopt(M_TRIM_THRESHOLD, 128 * 1024)
        libc.malloc_trim(0)

    with outermost(_kept, keep, release):
        yield


@contextlib.contextmanager
def outermost(depth: list, enter: Callable[[], None], leave: Callable[[], None]):
    """A context that nests: enter() on the outermost entry, leave() on the outermost exit;
    depth[0] counts the contexts open (heap_kept, spill.files_kept)."""
    if depth[0] == 0:
        enter()
    depth[0] += 1
    try:
        yield
    finally:
        depth[0] -= 1
        if depth[0] == 0:
            leave()


def row_norms(a: Array) -> Array:
    """|a_i| of each row of the 2-d array a, real or complex, without the temporary copy of a
    complex a that np.linalg.norm(a, axis=1) makes (its conjugate, most of its cost). Column
    norms: row_norms(a.T)."""
    return np.sqrt(np.einsum("ij,ij->i", a.real, a.real) + np.einsum("ij,ij->i", a.imag, a.imag))
