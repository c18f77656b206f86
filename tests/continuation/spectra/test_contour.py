"""The contour-filter subspace iteration (continuation/spectra/contour.py) on sparse
nonsymmetric matrices whose spectra are known by construction: a permuted block upper
triangular matrix with 1x1 blocks (real eigenvalues) and 2x2 blocks [[a, b], [-b, a]] (pairs
a +- ib), strictly upper coupling."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from diskfriction.continuation.spectra.contour import Circle, ContourFailed, contour_eigensystem
from diskfriction.continuation.spectra.nearest import Deflated

TOL = 1e-12


def known_matrix(n: int, seed: int, pairs: int = 10) -> tuple[sp.csr_array, np.ndarray]:
    """(A, its eigenvalues): real eigenvalues spread over [0, 10] and `pairs` complex pairs with
    real parts in [0, 10] (the first three in [3.5, 4.5]) and imaginary parts in [0.05, 0.5],
    block upper triangular under a random permutation (a similarity)."""
    rng = np.random.default_rng(seed)
    D = sp.lil_array((n, n))
    values = []
    i = 0
    for m in range(pairs):
        a, b = rng.uniform(3.5, 4.5) if m < 3 else rng.uniform(0, 10), rng.uniform(0.05, 0.5)
        D[i, i], D[i, i + 1], D[i + 1, i], D[i + 1, i + 1] = a, b, -b, a
        values += [a + 1j * b, a - 1j * b]
        i += 2
    for j in range(i, n):
        D[j, j] = rng.uniform(0, 10)
        values.append(D[j, j] + 0j)
    upper = sp.triu(sp.random(n, n, density=4.0 / n, random_state=seed), k=2)  # above the 2x2 blocks
    T = sp.csr_array(D) + upper
    p = rng.permutation(n)
    return sp.csr_array(T[p][:, p]), np.array(values)


def relative_residuals(A, found) -> tuple[float, float]:
    norm = abs(A).sum(axis=0).max()
    r = found.right / np.linalg.norm(found.right, axis=0)
    lh = found.left / np.linalg.norm(found.left, axis=1)[:, None]
    right = np.linalg.norm(A @ r - r * found.values, axis=0).max() / norm
    left = np.linalg.norm((A.T @ lh.T).T - lh * found.values[:, None], axis=1).max() / norm
    return right, left


def matched(reference: np.ndarray, found: np.ndarray) -> float:
    """Largest distance from a reference eigenvalue to the nearest found one, and back."""
    d = np.abs(reference[:, None] - found[None, :])
    return float(max(d.min(axis=1).max(), d.min(axis=0).max()))


def test_the_filter_is_the_trapezoid_sum():
    circle = Circle(1.0, 2.0, 8)
    nodes, weights = circle.upper()
    lam = np.array([0.3 + 0.2j, 2.9, -1.5 + 1.7j, 6.0])
    explicit = sum(w / (z - lam) + np.conj(w) / (np.conj(z) - lam) for z, w in zip(nodes, weights))
    assert np.allclose(explicit, circle.filter(lam), rtol=1e-13, atol=0)
    assert np.all(np.abs(circle.filter(lam[circle.inside(lam)])) > 0.5)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_every_eigenvalue_inside_with_both_vectors(seed):
    A, values = known_matrix(200, seed)
    circle = Circle(4.0, 0.8, 8)
    inside = values[circle.inside(values)]
    dense = np.linalg.eigvals(A.toarray())
    found = contour_eigensystem(A, circle, size=int(1.5 * inside.size) + 8, tol=TOL)
    assert found.count == inside.size == int(circle.inside(dense).sum())
    assert found.certified
    assert found.values.size == inside.size and matched(inside, found.values) < 1e-9
    right, left = relative_residuals(A, found)
    assert right <= TOL and left <= TOL
    assert np.allclose(np.einsum("ij,ji->i", found.left, found.right), 1.0, atol=1e-10)
    assert np.any(np.abs(found.values.imag) > 0.01)  # complex pairs among them, both members
    assert matched(found.values, found.values.conj()) < 1e-9


def test_a_subspace_too_small_does_not_pass_for_complete():
    """Fewer columns than eigenvalues inside: no convergence, or an uncertified count short of
    the true one."""
    A, values = known_matrix(200, 4)
    circle = Circle(4.0, 0.8, 8)
    count = int(circle.inside(values).sum())
    try:
        found = contour_eigensystem(A, circle, size=count - 2, tol=TOL, max_iterations=30)
    except ContourFailed:
        return
    assert not found.certified and found.count < count


def test_a_warm_start_from_a_nearby_matrix_needs_fewer_iterations():
    A, values = known_matrix(200, 5)
    circle = Circle(4.0, 0.8, 8)
    size = int(1.5 * circle.inside(values).sum()) + 8
    first = contour_eigensystem(A, circle, size, tol=TOL)
    nudge = sp.random(200, 200, density=3.0 / 200, random_state=6)
    B = sp.csr_array(A + 1e-4 * nudge)
    cold = contour_eigensystem(B, circle, size, tol=TOL)
    warm = contour_eigensystem(B, circle, size, start=first.basis, left_start=first.left_basis, tol=TOL)
    assert warm.iterations < cold.iterations
    assert warm.count == cold.count == int(circle.inside(np.linalg.eigvals(B.toarray())).sum())
    assert matched(cold.values, warm.values) < 1e-9


def test_a_deflation_keeps_its_null_space_out():
    """B = Pi A0 Pi with Pi = I - e0 e0^T has the eigenvalue 0 (vector e0) besides A0's others
    off coordinate 0; shift-inverting B with the projection leaves 0 out."""
    A0, _ = known_matrix(200, 7)
    n = 200
    keep = sp.diags_array(np.r_[0.0, np.ones(n - 1)])
    B = sp.csr_array(keep @ A0 @ keep)
    e0 = np.zeros((n, 1))
    e0[0] = 1.0
    circle, within = Circle(0.5, 0.77, 8), 0.68  # B's eigenvalues nearest: 0.632, 0.729, 0.816 off 0.5
    dense = np.linalg.eigvals(B.toarray())
    expected = dense[(np.abs(dense - 0.5) < within) & (np.abs(dense) > 1e-12)]
    plain = contour_eigensystem(B, circle, size=expected.size + 12, tol=TOL, within=within)
    deflation = Deflated(B, e0, e0, sp.identity(n, format="csr"), sp.identity(n, format="csr"))
    deflated = contour_eigensystem(B, circle, size=expected.size + 12, tol=TOL, deflated=deflation, within=within)
    assert plain.count == expected.size + 1 and np.abs(plain.values).min() < 1e-10
    assert deflated.count == expected.size and matched(expected, deflated.values) < 1e-9
