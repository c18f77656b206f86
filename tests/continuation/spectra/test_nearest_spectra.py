"""Shift-invert spectra nearest a shift (spectra/nearest.py): the k eigenvalues nearest sigma
with their left and right vectors, exact to rounding after ARPACK's tolerance, and the two-sided
projection that solves the projected pencil or hands it to QZ."""
from __future__ import annotations

import numpy as np
import pytest



def test_arpacks_tolerance_leaves_the_projected_eigenvalues_exact():
    """ARPACK stops at ARPACK_TOL, not at the machine precision; the two-sided Rayleigh-Ritz
    projection that follows still gives the 30 eigenvalues nearest sigma to 1e-13 of the
    largest (a dense decomposition's), and both vectors' residuals within 1e-10 of it."""
    import scipy.sparse as sp

    from diskfriction.continuation.spectra.nearest import ARPACK_TOL, nearest_eigensystem

    assert ARPACK_TOL > 0.0
    rng = np.random.default_rng(7)
    n, sigma, k = 240, 20.3, 30
    A = sp.csr_array(sp.random(n, n, density=0.05, random_state=rng) * 4.0 + sp.diags(np.arange(n, dtype=float)))
    exact = np.linalg.eigvals(A.toarray())
    scale = np.abs(exact).max()
    system, _ = nearest_eigensystem(A, sigma, k)
    nearest = exact[np.argsort(np.abs(exact - sigma))[:k]]
    assert np.abs(nearest[:, None] - system.values[None, :]).min(axis=1).max() <= 1e-13 * scale
    R, L = system.right, system.left
    assert np.abs(A @ R - R * system.values).max() <= 1e-10 * scale * np.abs(R).max()
    assert np.abs(L @ A - system.values[:, None] * L).max() <= 1e-10 * scale * np.abs(L).max()


@pytest.mark.parametrize("sparse, k", [(True, 7), (False, 7), (True, 90)])
def test_nearest_eigensystem_gives_the_k_nearest_with_normalised_vectors(sparse, k):
    """Shift-invert against a dense eigendecomposition: the k eigenvalues nearest sigma (real
    and complex ones), the radius they cover, residuals of both vectors, l^H r = 1. For k = 7
    the edge of the disc splits a conjugate pair (either member may be returned), for k = 90
    the Krylov space is cut to k + KRYLOV_EXTRA (krylov_size)."""
    import scipy.sparse as sp

    from diskfriction.continuation.spectra.nearest import KRYLOV_EXTRA, krylov_size, nearest_eigensystem

    rng = np.random.default_rng(7)
    n, sigma = 240, 20.3
    assert (krylov_size(k, n) < 2 * k + 1) == (k > KRYLOV_EXTRA + 1)
    A = sp.random(n, n, density=0.05, random_state=rng) * 4.0 + sp.diags(np.arange(n, dtype=float))
    A = sp.csr_array(A)
    exact = np.linalg.eigvals(A.toarray())
    nearest = exact[np.argsort(np.abs(exact - sigma))[:k]]
    system, radius = nearest_eigensystem(A if sparse else A.toarray(), sigma, k)
    assert np.any(np.abs(exact.imag) > 1e-3)  # the matrix has complex pairs too
    split = np.count_nonzero(nearest.imag > 1e-9) != np.count_nonzero(nearest.imag < -1e-9)
    assert split == (k == 7)
    found = np.minimum(np.abs(nearest[:, None] - system.values[None, :]),
                       np.abs(nearest.conj()[:, None] - system.values[None, :]))
    assert np.max(np.min(found, axis=1)) <= 1e-9 * n
    assert radius == pytest.approx(np.max(np.abs(nearest - sigma)), rel=1e-9)
    R, L = system.right, system.left
    assert np.max(np.abs(A @ R - R * system.values)) <= 1e-8 * n * np.max(np.abs(R))
    assert np.max(np.abs(L @ A - system.values[:, None] * L)) <= 1e-8 * n * np.max(np.abs(L))
    assert np.allclose(np.einsum("ij,ji->i", L, R), 1.0, atol=1e-10)


def test_the_two_sided_projection_solves_the_pencil_or_hands_it_to_qz():
    """nearest._two_sided on subspaces of a dense matrix with known eigenvectors: right and
    left subspaces of the same 8 eigenvalues (perturbed within the subspace) give them to
    1e-13 with residuals at rounding and l^H r = 1, as the QZ algorithm on the pencil does;
    a left vector that is mostly another eigenvalue's (orthogonal to V) makes W^H V ill
    conditioned, and the pencil then goes to QZ (the values of scipy's eig of the pencil)."""
    import scipy.linalg as sla

    from diskfriction.continuation.spectra.nearest import B_RCOND, _two_sided

    rng = np.random.default_rng(11)
    n, k = 60, 8
    A = rng.standard_normal((n, n))
    values, vl, vr = sla.eig(A, left=True, right=True)
    near = np.argsort(np.abs(values - 0.3))
    V = vr[:, near[:k]] @ (np.eye(k) + 0.05 * rng.standard_normal((k, k)))
    W = vl[:, near[:k]] @ (np.eye(k) + 0.05 * rng.standard_normal((k, k)))
    system = _two_sided(A, V, W)
    qz = sla.eigvals(W.conj().T @ A @ V, W.conj().T @ V)
    def apart(got, expected):  # each expected value's distance to the nearest one got, and back
        d = np.abs(got[:, None] - expected[None, :])
        return max(d.min(axis=0).max(), d.min(axis=1).max())

    for expected in (values[near[:k]], qz):
        assert apart(system.values, expected) <= 1e-13 * n
    assert np.max(np.abs(A @ system.right - system.right * system.values)) <= 1e-12 * n
    assert np.max(np.abs(system.left @ A - system.values[:, None] * system.left)) <= 1e-12 * n
    assert np.allclose(np.einsum("ij,ji->i", system.left, system.right), 1.0, atol=1e-12)
    W[:, 0] = 1e-7 * W[:, 0] + vl[:, near[k + 5]]  # l_(k+5) is orthogonal to every right vector of V
    B = W.conj().T @ V
    assert 1.0 / np.linalg.cond(B, 1) < B_RCOND
    system = _two_sided(A, V, W)
    qz = sla.eig(W.conj().T @ (A @ V), B, left=True, right=True)[0]
    assert np.array_equal(system.values, qz.astype(complex))
    assert apart(system.values, values[near[:k]]) <= 1e-7
