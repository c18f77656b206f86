"""A few eigenvalues near predicted values, with their left and right vectors, without the full
spectrum: shift-invert subspace iteration with a two-sided Rayleigh-Ritz projection.

Collision detection refines an interval only for the eigenvalues whose pairs it could not
certify (a cluster K, typically 2 to 6 of them; collisions.py). Their values at a new point
cost one sparse LU of A - sigma I and a few dozen solves instead of an O(n^3) dense eigensolver:

    V <- (A - sigma I)^-1 V,   W <- (A - sigma I)^-T W,   orthonormalised,   k + extra columns,

with sigma the mean of the predicted values (real: clusters are closed under conjugation) and V,
W started from the cluster's right and left vectors at the nearest sample. The Ritz values are
the eigenvalues of the oblique projection (W^T V)^-1 W^T A V; the k nearest to the predictions
are taken once each has a relative residual |A r - theta r| / (|theta| + |A|) <= tol. Each
iteration shrinks the error of eigenvalue lambda by |lambda - sigma| / |mu - sigma|, mu the
nearest eigenvalue outside the subspace; the extra columns keep that ratio small. Fails (None)
if it has not converged in max_iter iterations; the caller then takes the full spectrum.
"""
from __future__ import annotations

from typing import Optional

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from .linalg import Matrix, SingularMatrix, factorize
from .spectra import Eigensystem

Array = np.ndarray

EXTRA = 4
"""Columns beyond the cluster's size."""


def _real_basis(vectors: Array, columns: int, rng: np.random.Generator) -> Array:
    """Orthonormal real basis of span(Re v, Im v) padded with random columns to `columns`."""
    n = vectors.shape[0]
    parts = np.column_stack([vectors.real, vectors.imag, rng.standard_normal((n, columns))])
    Q, R = np.linalg.qr(parts)
    keep = np.abs(np.diag(R)) > 1e-12 * np.abs(np.diag(R)).max()
    return Q[:, keep][:, :columns]


def cluster_eigensystem(A: Matrix, predicted: Array, right: Array, left: Array,
                        tol: float = 1e-11, max_iter: int = 30) -> Optional[Eigensystem]:
    """Eigenvalues of A nearest to `predicted` (k values, closed under conjugation), with right
    vectors (columns) and left vectors (rows, l^H r = 1), in the order of `predicted`; right
    (n x k) and left (k x n) start the iteration. None if it does not converge."""
    k = predicted.size
    n = A.shape[0]
    m = min(n, k + EXTRA)
    sigma = float(np.mean(predicted.real))
    identity = sp.identity(n, format="csr") if sp.issparse(A) else np.eye(n)
    try:
        lu = factorize(A - sigma * identity)
    except SingularMatrix:
        sigma *= 1.0 + 1e-9
        lu = factorize(A - sigma * identity)
    rng = np.random.default_rng(0)
    V = _real_basis(right, m, rng)
    W = _real_basis(left.conj().T, m, rng)
    scale = float(np.max(np.abs(predicted))) + _norm_estimate(A)
    for _ in range(max_iter):
        V = np.linalg.qr(lu.solve(V))[0]
        W = np.linalg.qr(lu.solve(W, transpose=True))[0]
        AV = A @ V
        H = np.linalg.solve(W.T @ V, W.T @ AV)
        theta, Y = np.linalg.eig(H)
        pick = _nearest(predicted, theta)
        r = V @ Y[:, pick]
        res = np.linalg.norm(AV @ Y[:, pick] - r * theta[pick], axis=0) / np.linalg.norm(r, axis=0)
        if np.all(res <= tol * (np.abs(theta[pick]) + scale)):
            return _two_sided(A, V, W, theta[pick])
    return None


def _nearest(predicted: Array, theta: Array) -> Array:
    """Indices of theta matched one-to-one to the predicted values (smallest total distance)."""
    from scipy.optimize import linear_sum_assignment

    cost = np.abs(predicted[:, None] - theta[None, :])
    return linear_sum_assignment(cost)[1]


def _two_sided(A: Matrix, V: Array, W: Array, values: Array) -> Eigensystem:
    """Right and left Ritz vectors of the converged values from the two subspaces: the pencil
    (W^T A V, W^T V) has right vectors y (r = V y) and left vectors z (l = W z)."""
    M, B = W.T @ (A @ V), W.T @ V
    theta, vl, vr = sla.eig(M, B, left=True, right=True)
    pick = _nearest(values, theta)
    right = V @ vr[:, pick]
    left = (W @ vl[:, pick]).conj().T
    left = left / np.einsum("ij,ji->i", left, right)[:, None]
    return Eigensystem(theta[pick].astype(complex), right, left)


def _norm_estimate(A: Matrix) -> float:
    """max |A_ij| (a cheap scale for the relative residual)."""
    return float(abs(A).max()) if sp.issparse(A) else float(np.max(np.abs(A)))
