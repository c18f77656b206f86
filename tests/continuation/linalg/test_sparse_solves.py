"""Sparse against dense linear algebra on the chain of 40 disks (continuation/linalg/): a
Newton correction, the tangent and the spectrum alike, substitution over copied factors like
SuperLU's solve, and a repeated pattern factorized in its first column order."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.continuation.stepping.newton import bordered_newton, tangent
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def test_sparse_and_dense_solves_agree_at_N40():
    """The same problem assembled dense (LAPACK) and sparse (SuperLU): residual, a Newton
    correction, the tangent and the spectrum agree."""
    system = System.from_scene(Scene(N=40, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), 0.01)
    dense, sparse = (DiskEquilibria(system, q, xi, 0.01, "J", sparse=s) for s in (False, True))
    x = np.append(q + 1e-7 * np.sin(np.arange(q.size)), 0.0101)
    e_p = np.zeros(x.size)
    e_p[-1] = 1.0
    steps = [bordered_newton(pr, x, e_p, 1e-11, 8) for pr in (dense, sparse)]
    assert all(s.converged for s in steps)
    assert np.max(np.abs(steps[0].x - steps[1].x)) <= 1e-12
    t = [tangent(pr, steps[0].x, e_p) for pr in (dense, sparse)]
    assert np.max(np.abs(t[0] - t[1])) <= 1e-10
    ev = [np.sort_complex(DenseSpectra().eigensystem(pr, steps[0].x[:-1], 0.0101).values) for pr in (dense, sparse)]
    assert np.max(np.abs(ev[0] - ev[1])) <= 1e-9 * np.abs(ev[0]).max()


def test_compiled_substitution_solves_like_superlu():
    """A factorization solved with repeatedly switches from SuperLU's solve to substitution over
    its copied factors (triangular.py): on the bordered A - sigma I of the N = 40 chain (near an
    eigenvalue, so ill-conditioned) both give the same x and A^-T x to rounding, for vectors
    and for the columns of a matrix."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from diskfriction.continuation.linalg.solves import COPY_FACTORS_AT, bordered, factorize

    system = System.from_scene(Scene(N=40, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), 0.01)
    A = DiskEquilibria(system, q, xi, 0.01, "J", sparse=True).stability_matrix(q, 0.01)
    n = A.shape[0]
    sigma = np.sort(np.linalg.eigvals(A.toarray()).real)[n // 2] * (1 + 1e-6)
    rng = np.random.default_rng(3)
    M = bordered(A - sigma * sp.identity(n, format="csr"), rng.standard_normal(n), rng.standard_normal(n))
    reference = spla.splu(sp.csc_array(M))
    lu = factorize(M)
    rhs = rng.standard_normal((n + 1, 3))
    for k in range(COPY_FACTORS_AT + 2):
        transpose = k % 2 == 1
        x = lu.solve(rhs[:, k % 3], transpose)
        expected = reference.solve(rhs[:, k % 3], trans="T" if transpose else "N")
        assert np.max(np.abs(x - expected)) <= 1e-10 * np.max(np.abs(expected))
    assert lu.triangular is not None
    X = lu.solve(rhs)
    assert np.max(np.abs(M @ X - rhs)) <= 1e-9 * np.max(np.abs(X))
    assert np.max(np.abs(M.T @ lu.solve(rhs, transpose=True) - rhs)) <= 1e-9 * np.max(np.abs(X))


@pytest.mark.parametrize("symmetric", [False, True], ids=["partial-pivoting", "symmetric-mode"])
def test_a_repeated_pattern_reuses_its_ordering_and_solves_alike(symmetric):
    """A second matrix of the same pattern (the bordered A - sigma I of the N = 40 chain at
    another sigma, near an eigenvalue) is factorized in the column order of the first
    (orderings.py) and solves like SuperLU's own factorization of it, with SuperLU's solve and
    after the factors are copied (triangular.py), with and without transpose: bit for bit with
    partial pivoting, to rounding with SymmetricMode; the log-determinant from its factors
    (sign and value) is that of the matrix; another pattern is ordered afresh, and solves bit
    for bit as it does once its pattern is known (with SymmetricMode its first factors are
    those of the reordered matrix: a result must not depend on what the process factorized
    before)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from diskfriction.continuation.linalg import orderings
    from diskfriction.continuation.linalg.solves import COPY_FACTORS_AT, bordered, factorize
    from diskfriction.continuation.spectra.nearest import SHIFT_INVERT_ORDERING

    options = SHIFT_INVERT_ORDERING if symmetric else None
    system = System.from_scene(Scene(N=40, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), 0.01)
    A = DiskEquilibria(system, q, xi, 0.01, "J", sparse=True).stability_matrix(q, 0.01)
    n = A.shape[0]
    eigenvalues = np.sort(np.linalg.eigvals(A.toarray()).real)
    rng = np.random.default_rng(5)
    c, b = rng.standard_normal(n), rng.standard_normal(n)
    matrix = lambda sigma: sp.csc_array(bordered(A - sigma * sp.identity(n, format="csr"), c, b))  # noqa: E731
    first, second = matrix(eigenvalues[n // 3]), matrix(eigenvalues[n // 2] * (1 + 1e-6))
    factorize(first, options)
    lu = factorize(second, options)
    assert isinstance(lu.lu, orderings.Reordered)
    reference = spla.splu(second, **(options or {}))
    rhs = rng.standard_normal((n + 1, 2))
    for k in range(COPY_FACTORS_AT + 4):
        transpose = k % 2 == 1
        x = lu.solve(rhs[:, (k // 2) % 2], transpose)
        expected = reference.solve(rhs[:, (k // 2) % 2], trans="T" if transpose else "N")
        if symmetric:
            assert np.max(np.abs(x - expected)) <= 1e-10 * np.max(np.abs(expected))
        elif lu.triangular is None:
            assert np.array_equal(x, expected)
        residual = (second.T if transpose else second) @ x - rhs[:, (k // 2) % 2]
        assert np.max(np.abs(residual)) <= 1e-9 * np.max(np.abs(x))
    assert lu.triangular is not None
    diagonal = lu.lu.U.diagonal()
    sign = np.prod(np.sign(diagonal)) * linalg_parity(lu.lu.perm_r) * linalg_parity(lu.lu.perm_c)
    assert (sign, np.sum(np.log(np.abs(diagonal)))) == pytest.approx(np.linalg.slogdet(second.toarray()), rel=1e-9)
    coupled = sp.lil_array(A)
    coupled[0, n - 5] = 1e-3  # one more nonzero
    other = sp.csc_array(bordered(sp.csr_array(coupled) - 0.5 * sp.identity(n, format="csr"), c, b))
    fresh = factorize(other, options)
    assert isinstance(fresh.lu, orderings.Reordered) == symmetric
    again = factorize(other, options)
    assert isinstance(again.lu, orderings.Reordered)
    assert np.array_equal(fresh.solve(rhs[:, 0]), again.solve(rhs[:, 0]))


def linalg_parity(permutation):
    from diskfriction.continuation.linalg.solves import _parity

    return _parity(permutation)
