"""Every eigenvalue of a real sparse matrix inside a circle, with left and right vectors: a
contour-filter subspace iteration (FEAST type).

The spectral projector onto the eigenvalues inside a closed curve C is
P = (1 / 2 pi i) oint_C (z I - B)^-1 dz. On the circle z = c + r e^{i theta} (c real) the
trapezoid rule with the nodes theta_j = 2 pi (j + 1/2) / N, j = 0..N-1 (N even) gives the
rational filter

    F = (1 / N) sum_j r e^{i theta_j} (z_j I - B)^-1,    f(lambda) = 1 / (1 + w^N),
    w = (lambda - c) / r,

which has the eigenvectors of B and maps an eigenvalue lambda to f(lambda): |f| > 1/2 inside
the circle (|w| < 1), about |w|^-N far outside. The nodes come in conjugate pairs, so for a
real B and a real block Y, F Y = 2 Re sum_{j < N/2} w_j (z_j I - B)^-1 Y: N / 2 complex LU
factorizations (SuperLU) serve the whole iteration, each solving a block of right-hand sides
at once, and the transposed solves with the same factors give F^T, whose dominant subspace
holds the left vectors. Subspace iteration Q <- orth(F Q), P <- orth(F^T P) converges to the
m eigenvalues of largest |f| at the rate |f(lambda_{m+1}) / f(lambda_i)| per iteration; a
two-sided Rayleigh-Ritz projection on (Q, P) (the m x m pencil (P^T A Q, P^T Q)) gives the
eigenvalues with right and left vectors, l_i^H r_i = 1. A start block near the wanted
subspace (the previous point's basis along a branch) needs fewer iterations.

Convergence: every Ritz value in the disc |lambda - c| < within (within <= r) with both
residuals ||A r - lambda r||, ||l^H A - lambda l^H|| at most tol ||A||_1 (r, l of unit norm);
a disc smaller than the circle converges faster, its eigenvalues having
|f| >= 1 / (1 + (within / r)^N). The count: the eigenvalues found in the disc; `certified`
where the count is smaller than the subspace's size m. That is the argument of ARPACK's k
nearest, not a proof: a generic start block converges to the dominant invariant subspace of
F, and a subspace with room to spare holds every eigenvalue whose |f| exceeds that of the
eigenvalues it left out, which holds for the disc unless eigenvalues just outside the circle,
near a node (where |f| is large), crowd it.

A deflation (nearest.Deflated: a matrix B with the same eigenvalues as A off its null space,
B T = 0, U^T B = 0, and maps from B's vectors to A's) is factorized in place of A, the
iterates projected off the null space (x - T (U^T T)^-1 U^T x, and its transpose on the left),
and the Rayleigh-Ritz projection taken on A with the mapped subspaces.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from diskfriction.continuation.linalg.solves import blas_threads

Array = np.ndarray

ORDERING = dict(permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.01, options=dict(SymmetricMode=True))
"""SuperLU's ordering for z I - B: as the shift-invert's (nearest.SHIFT_INVERT_ORDERING),
computed once per call and kept for every node (the nodes share B's pattern)."""


@dataclass(frozen=True)
class Circle:
    """The circle |z - center| = radius (center real) with `nodes` trapezoid nodes (even: the
    conjugate pairs)."""

    center: float
    radius: float
    nodes: int = 8

    def __post_init__(self):
        if self.radius <= 0 or self.nodes < 2 or self.nodes % 2:
            raise ValueError(f"a circle needs radius > 0 and an even number of nodes >= 2, got "
                             f"{self.radius}, {self.nodes}")

    def upper(self) -> tuple[Array, Array]:
        """(z_j, weights w_j) of the nodes in the upper half-plane: F Y = 2 Re sum_j w_j
        (z_j I - B)^-1 Y for real Y."""
        theta = 2 * np.pi * (np.arange(self.nodes // 2) + 0.5) / self.nodes
        e = np.exp(1j * theta)
        return self.center + self.radius * e, self.radius * e / self.nodes

    def filter(self, values: Array) -> Array:
        """f(lambda) = 1 / (1 + w^N), w = (lambda - center) / radius: the filter's value."""
        w = (np.asarray(values, dtype=complex) - self.center) / self.radius
        return 1.0 / (1.0 + w ** self.nodes)

    def inside(self, values: Array) -> Array:
        return np.abs(np.asarray(values) - self.center) < self.radius


@dataclass(frozen=True)
class ContourEigensystem:
    """What contour_eigensystem found: the eigenvalues inside its disc (values, converged)
    with right vectors (columns of `right`) and left vectors (rows of `left`, l^H A = lambda
    l^H), l_i^H r_i = 1, in A's coordinates; the real orthonormal bases (n x m, in the
    factorized matrix's coordinates) of the last filtered subspaces, right and left, to start
    a nearby problem from; count: the eigenvalues found in the disc; certified: count < m,
    the subspace's size (module docstring); residual: the largest of both residuals over
    `values`, relative to ||A||_1; iterations, factorizations, solves (columns solved, both
    sides)."""

    values: Array
    right: Array
    left: Array
    basis: Array
    left_basis: Array
    count: int
    certified: bool
    residual: float
    iterations: int
    factorizations: int
    solves: int


class ContourFailed(RuntimeError):
    """The iteration did not converge within its iterations, or a node's matrix is singular."""


def contour_eigensystem(A, circle: Circle, size: int, start: Optional[Array] = None,
                        left_start: Optional[Array] = None, tol: float = 1e-10, max_iterations: int = 20,
                        deflated=None, within: Optional[float] = None, seed: int = 0) -> ContourEigensystem:
    """The eigenvalues of the real sparse A (n x n) with |lambda - circle.center| < within
    (default: the circle's radius; at most it) with left and right vectors, by subspace
    iteration with the circle's filter on `size` columns (module docstring): a disc inside the
    circle converges faster (its eigenvalues have |f| >= 1 / (1 + (within / radius)^N)).
    start, left_start: n x j real blocks to start from (j <= size; padded with random columns
    from `seed`; left_start None: start); deflated: a nearest.Deflated to factorize in place of
    A. BLAS runs on one thread (solves.blas_threads). Raises ContourFailed."""
    with blas_threads():
        return _iterated(A, circle, size, start, left_start, tol, max_iterations, deflated, within, seed)


def _iterated(A, circle, size, start, left_start, tol, max_iterations, deflated, within, seed):
    n = A.shape[0]
    B = A if deflated is None else deflated.matrix
    within = circle.radius if within is None else within
    if not 0 < size < n or not 0 < within <= circle.radius:
        raise ValueError(f"need size in 1..{n - 1} and 0 < within <= the radius, got {size}, {within}")
    norm = float(abs(A).sum(axis=0).max())
    projections = _projections(deflated)
    nodes, weights = circle.upper()
    solvers = _factorized(sp.csc_array(B), nodes)
    rng = np.random.default_rng(seed)
    Q = _block(start, size, n, rng)
    P = _block(left_start if left_start is not None else start, size, n, rng)
    right_map = None if deflated is None else deflated.right_map
    left_map = None if deflated is None else deflated.left_map
    solves = 0
    for iteration in range(1, max_iterations + 1):
        Q = _orth(projections[0](_filtered(solvers, weights, Q, "N")))
        P = _orth(projections[1](_filtered(solvers, weights, P, "T")))
        solves += (Q.shape[1] + P.shape[1]) * len(solvers)
        V = Q if right_map is None else right_map @ Q
        W = P if left_map is None else left_map @ P
        values, right, left = _two_sided(A, V, W)
        inside = np.abs(values - circle.center) < within
        residual = _residuals(A, values[inside], right[:, inside], left[inside], norm)
        if residual <= tol:
            count = int(inside.sum())
            return ContourEigensystem(values[inside], right[:, inside], left[inside], Q, P, count,
                                      count < min(Q.shape[1], P.shape[1]), residual, iteration, len(solvers),
                                      solves)
    raise ContourFailed(f"no convergence to {tol:g} in {max_iterations} iterations "
                        f"(residual {residual:.2e}, {int(inside.sum())} Ritz values inside)")


def _projections(deflated):
    """(right, left) projections off the deflation's null space, identities without one."""
    if deflated is None:
        return (lambda X: X), (lambda X: X)
    T, U = np.asarray(deflated.right_null), np.asarray(deflated.left_null)
    C = np.linalg.inv(U.T @ T)
    return (lambda X: X - T @ (C @ (U.T @ X))), (lambda X: X - U @ (C.T @ (T.T @ X)))


def _factorized(B: sp.csc_array, nodes: Array) -> list:
    """SuperLU factors of z_j I - B for each node, ordered once (ORDERING) for all of them."""
    n = B.shape[0]
    identity = sp.identity(n, format="csc")
    first = spla.splu(sp.csc_array(nodes[0] * identity - B), **ORDERING)
    q = first.perm_c
    inverse = np.argsort(q)
    out = [(first, None)]
    for z in nodes[1:]:
        M = sp.csc_array(z * identity - B)
        permuted = sp.csc_array(M[inverse][:, inverse])
        try:
            out.append((spla.splu(permuted, **{**ORDERING, "permc_spec": "NATURAL"}), inverse))
        except RuntimeError as err:
            raise ContourFailed(f"z I - B singular at z = {z:.6g}: {err}") from None
    return out


def _filtered(solvers: list, weights: Array, Y: Array, trans: str) -> Array:
    """F Y (trans "N") or F^T Y ("T") for real Y: 2 Re sum_j w_j (z_j I - B)^-1 Y."""
    out = np.zeros(Y.shape)
    Yc = Y.astype(complex)
    for (lu, order), w in zip(solvers, weights):
        if order is None:
            X = lu.solve(Yc, trans=trans)
        else:  # factors of M[o][:, o]: M x = y is M' x[o] = y[o], and M^T likewise
            X = np.empty_like(Yc)
            X[order] = lu.solve(np.ascontiguousarray(Yc[order]), trans=trans)
        out += 2.0 * (w * X).real
    return out


def _block(start: Optional[Array], size: int, n: int, rng) -> Array:
    """`size` columns: start's (at most size of them) padded with random ones."""
    columns = [] if start is None else [np.asarray(start, dtype=float)[:, :size]]
    have = 0 if start is None else columns[0].shape[1]
    if have < size:
        columns.append(rng.standard_normal((n, size - have)))
    return np.hstack(columns)


def _orth(X: Array) -> Array:
    """An orthonormal basis of X's columns (those with a relative singular value above 1e-12)."""
    U, s, _ = sla.svd(X, full_matrices=False, check_finite=False)
    return U[:, s > 1e-12 * s[0]]


def _two_sided(A, V: Array, W: Array) -> tuple[Array, Array, Array]:
    """Two-sided Rayleigh-Ritz on the real subspaces V (right) and W (left): the pencil
    (W^T A V, W^T V); returns (values, right n x m, left m x n as rows l^H), l_i^H r_i = 1."""
    m = min(V.shape[1], W.shape[1])
    V, W = V[:, :m], W[:, :m]
    K, G = W.T @ (A @ V), W.T @ V
    values, vl, vr = sla.eig(K, G, left=True, right=True)
    right = V @ vr
    left = (W @ vl).conj().T
    left = left / np.einsum("ij,ji->i", left, right)[:, None]
    return values, right, left


def _residuals(A, values: Array, right: Array, left: Array, norm: float) -> float:
    """The largest ||A r - lambda r|| / ||r|| and ||l^H A - lambda l^H|| / ||l|| over the pairs,
    relative to norm; 0 for none."""
    if values.size == 0:
        return 0.0
    r = right / np.linalg.norm(right, axis=0)
    lh = left / np.linalg.norm(left, axis=1)[:, None]
    rr = np.linalg.norm(A @ r - r * values, axis=0)
    lr = np.linalg.norm((A.T @ lh.T).T - lh * values[:, None], axis=1)
    return float(max(rr.max(), lr.max()) / norm)
