"""The k eigenvalues of A nearest a real shift sigma, with left and right vectors: shift-invert.

One LU factorization of A - sigma I (solves.factorize: SuperLU for a sparse A, LAPACK for a
dense one) serves both sides: ARPACK (scipy.sparse.linalg.eigs) iterates with (A - sigma I)^-1
for the k right vectors V and with (A - sigma I)^-T for the k left vectors W; the eigenvalues
of (A - sigma I)^-1 of largest modulus are those of A nearest sigma. A two-sided Rayleigh-Ritz
projection on the two subspaces (the k x k pencil (W^H A V, W^H V)) pairs left with right
vectors and normalises l_i^H r_i = 1. Completeness: the k eigenvalues returned are the k
nearest sigma, so every eigenvalue with |lambda - sigma| < radius = max_i |lambda_i - sigma|
is among them. Cost at n = 300 (the chain of 100 disks), k = 8: about 1/5 of a full dense
eigendecomposition with both vectors (docs/notes/core-detection.md, "Partial split samples").
ARPACK's Krylov space is at most KRYLOV_EXTRA vectors larger than k (krylov_size; measured in
docs/notes/core-spectra.md, "ARPACK's Krylov size and compiled substitution").
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numba
import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from diskfriction.continuation.linalg.solves import Matrix, factorize
from diskfriction.continuation.spectra.tracking import Eigensystem

Array = np.ndarray


ARPACK_TOL = 1e-10
"""ARPACK's stopping tolerance (Ritz estimates relative to the eigenvalues of the shift-inverted
operator; scipy's default 0 asks for the machine precision). The two-sided Rayleigh-Ritz
projection on A that follows (_two_sided) gives the eigenvalues to second order in the
vectors' error, so that the vectors' residuals after it stay near 1e-10 and the located
collisions are those of the machine precision's to rounding, for fewer operator
applications."""
KRYLOV_EXTRA = 60
"""Most Arnoldi vectors ARPACK keeps beyond the k wanted (module docstring)."""


def krylov_size(k: int, n: int) -> int:
    """ARPACK's ncv for k eigenvalues of an n x n matrix: scipy's default max(2k + 1, 20), but at
    most k + KRYLOV_EXTRA. Each Arnoldi step orthogonalises against all ncv vectors and each
    restart costs O(n ncv^2), so for large k (a long chain's spectral window) a Krylov space
    nearer 1.4 k is cheaper although it restarts more; for small k scipy's default is."""
    return min(n, max(20, min(2 * k + 1, k + KRYLOV_EXTRA)))  # ARPACK: k + 1 < ncv <= n


SHIFT_INVERT_ORDERING = dict(permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.01,
                             options=dict(SymmetricMode=True))
"""SuperLU's ordering and pivoting for A - sigma I: minimum degree on the pattern of A + A^T,
the diagonal pivot kept where it is at least 0.01 of its column's largest entry, as for a
structurally symmetric matrix (the chain's and the contact networks' Jacobians): about half
the fill of SuperLU's default (COLAMD, partial pivoting; benchmarks/solve_speed.py). Its
backward errors, about 1e-14 against 1e-15, are harmless here, where the Rayleigh-Ritz
projection takes A itself (eigenvalue errors second order in the vectors'), but not for the
tangents of the other bordered solves (a LinearSolver's ordering keeps partial pivoting). A
threshold of 0.1 (or partial pivoting) lets off-diagonal pivots undo the minimum degree
order."""


def start_vector(n: int) -> Array:
    """ARPACK's start vector for an n x n matrix, the same in every call: ARPACK's own is drawn
    from a generator whose state carries over from one call to the next in a process, so a
    result would depend on what the process computed before (a packing's shear resumed after
    its finished segments differed from the uninterrupted run at the rounding level)."""
    return np.random.default_rng(n).standard_normal(n)


@dataclass(frozen=True)
class Deflated:
    """A matrix B to shift-invert in place of A (same coordinates) where its LU fills less:
    B's nonzero spectrum off its null space is A's, B T = 0 and U^T B = 0 (T, U: n x r, U^T T
    invertible), and the maps take B's eigenvectors to A's: right vectors r_A = right_map r_B,
    left vectors l_A = left_map l_B (sparse n x n). The shift-invert iterates with the
    projected (B - sigma I)^-1, v -> x - T (U^T T)^-1 U^T x (and its transpose for the left
    side), on which B's null space has eigenvalue 0, never among the largest, so that the
    eigenvalues found nearest sigma are A's (models/packing/equilibria.py: the
    network's M^-1 J, whose translations T and total forces U are its null spaces, against
    A_g, whose coordinates relative to a reference disk couple every row to that disk's and
    fill its LU more)."""

    matrix: object
    right_null: Array
    left_null: Array
    right_map: object
    left_map: object

    def operators(self, lu, n: int) -> tuple:
        """The projected solves with B - sigma I's factorization `lu` (direct, transposed)."""
        T, U = np.ascontiguousarray(self.right_null), np.ascontiguousarray(self.left_null)
        C = np.linalg.inv(U.T @ T)
        Ct = np.ascontiguousarray(C.T)
        return (spla.LinearOperator((n, n), matvec=lambda r: _project(lu.solve(r), T, C, U), dtype=float),
                spla.LinearOperator((n, n), matvec=lambda r: _project(lu.solve(r, transpose=True), U, Ct, T),
                                    dtype=float))


@numba.njit(cache=True)
def _project(x: Array, T: Array, C: Array, U: Array) -> Array:
    """x - T C U^T x in place (T, U: n x r, C: r x r); returns x. Compiled: four numpy calls
    cost a good part of a solve."""
    n, r = T.shape
    u = np.zeros(r)
    for i in range(n):
        for a in range(r):
            u[a] += U[i, a] * x[i]
    c = C @ u
    for i in range(n):
        for a in range(r):
            x[i] -= T[i, a] * c[a]
    return x


def _shift_inverted(B: Matrix, sigma: float):
    """The factorization of B - sigma I (SHIFT_INVERT_ORDERING) and the LinearOperator that
    solves with it."""
    n = B.shape[0]
    shift = sp.identity(n, format="csr") * sigma if sp.issparse(B) else sigma * np.eye(n)
    lu = factorize(B - shift, SHIFT_INVERT_ORDERING)
    return lu, spla.LinearOperator((n, n), matvec=lu.solve, dtype=float)


def nearest_values(A: Matrix, sigma: float, k: int) -> Array:
    """The k eigenvalues of A nearest sigma, without vectors: ARPACK on the shift-invert with
    A - sigma I factorized as nearest_eigensystem factorizes it (SHIFT_INVERT_ORDERING; scipy's
    own eigs takes COLAMD, about twice the fill)."""
    return spla.eigs(A, k=k, sigma=sigma, OPinv=_shift_inverted(A, sigma)[1], v0=start_vector(A.shape[0]),
                     return_eigenvectors=False)


class ShiftInvertFailed(RuntimeError):
    """A - sigma I is singular or ARPACK did not converge."""


def nearest_eigensystem(A: Matrix, sigma: float, k: int,
                        deflated: Optional[Deflated] = None) -> tuple[Eigensystem, float]:
    """(the eigensystem of the k eigenvalues of A nearest sigma with normalised left and right
    vectors, radius: the largest |lambda - sigma| among them); every eigenvalue of A strictly
    closer to sigma than radius is among the k. With `deflated`, its matrix is shift-inverted
    and its vectors mapped to A's (Deflated). Raises ShiftInvertFailed. The caller books it
    (solves.book)."""
    n = A.shape[0]
    if not 0 < k < n - 1:
        raise ShiftInvertFailed(f"k = {k} must lie in 1..{n - 2} for an {n} x {n} matrix")
    B = A if deflated is None else deflated.matrix
    try:
        lu, inverse = _shift_inverted(B, sigma)
        if deflated is None:
            inverse_t = spla.LinearOperator((n, n), matvec=lambda r: lu.solve(r, transpose=True), dtype=float)
        else:
            inverse, inverse_t = deflated.operators(lu, n)
        v0 = start_vector(n)
        ncv = krylov_size(k, n)
        _, V = spla.eigs(B, k=k, sigma=sigma, OPinv=inverse, v0=v0, ncv=ncv, tol=ARPACK_TOL)
        _, W = spla.eigs(B.T, k=k, sigma=sigma, OPinv=inverse_t, v0=v0, ncv=ncv, tol=ARPACK_TOL)
    except (np.linalg.LinAlgError, spla.ArpackError, spla.ArpackNoConvergence) as err:
        raise ShiftInvertFailed(f"shift-invert at sigma = {sigma:.6g}: {err}") from None
    if deflated is not None:
        V, W = deflated.right_map @ V, deflated.left_map @ W
    # A^T w = lambda w makes w^T (not w^H) a left row for lambda, and conj(w) the left
    # vector l (l^H A = lambda l^H); with w^H the projection pairs a complex eigenvalue's right
    # vector with its conjugate's left one, which is wrong when the k nearest hold one member
    # of a conjugate pair (a tie in distance at the edge of the disc)
    system = _two_sided(A, V, W.conj())
    return system, float(np.max(np.abs(system.values - sigma)))


def _two_sided(A: Matrix, V: Array, W: Array) -> Eigensystem:
    """Two-sided Rayleigh-Ritz on the right subspace V and the left subspace W (columns: left
    vectors l, l^H A = lambda l^H; module docstring): eigenvalues with right and left vectors,
    l_i^H r_i = 1. The k x k pencil (M, B) = (W^H A V, W^H V) is taken as the standard problem
    B^-1 M, whose right vectors are the pencil's and whose left vectors z give the pencil's as
    B^-H z: half the time of the QZ algorithm, the same eigenvalues to 1e-14 relative.
    ARPACK's two subspaces hold the same eigenvalues, so B is well conditioned; where it is not
    (its reciprocal condition below B_RCOND), the pencil goes to QZ."""
    M, B = W.conj().T @ (A @ V), W.conj().T @ V
    lu, piv, info = _getrf(B)
    rcond = _gecon(lu, np.linalg.norm(B, 1))[0] if info == 0 else 0.0
    if rcond >= B_RCOND:
        values, z, vr = sla.eig(_getrs(lu, piv, M)[0], left=True, right=True)
        vl = _getrs(lu, piv, z, trans=2)[0]
    else:
        values, vl, vr = sla.eig(M, B, left=True, right=True)
    right = V @ vr
    left = (W @ vl).conj().T
    left = left / np.einsum("ij,ji->i", left, right)[:, None]
    return Eigensystem(values.astype(complex), right, left)


B_RCOND = 1e-3
"""The least reciprocal condition number (1-norm) of W^H V for which _two_sided solves with it
(a loss of at most 1e3 times the rounding; QZ below)."""
_getrf, _getrs, _gecon = sla.get_lapack_funcs(("getrf", "getrs", "gecon"), dtype=complex)
