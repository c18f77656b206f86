"""The Newton locator of a double eigenvalue (detection/locate.py): quadratic convergence to a
closed-form collision, and the Jordan chain at a double eigenvalue, dense or sparse, and refined
on the locator's last factorization."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation import FunctionProblem
from diskfriction.continuation.detection.locate import locate_double_eigenvalue


def test_locator_converges_quadratically_to_a_closed_form_collision():
    """u in R^2 on the curved branch u = (p^2, sin p); A = [[a, 1], [c, a]] with
    c = (u_2 - sin p0) + (u_1 - p^2): on the branch c = sin p - sin p0, a double eigenvalue a
    with a Jordan block at p0 exactly. Newton from 3e-3 away (eigenvalue guess 0.01 off, as
    the cubic model of the pair's mean gives): each correction |dp| is at most 20 times the
    square of the one before, and it lands within 1e-12 of p0."""
    a, p0 = -0.7, 0.4

    def A(u, p):
        return np.array([[a, 1.0], [(u[1] - np.sin(p0)) + (u[0] - p * p), a]])

    problem = FunctionProblem(G=lambda u, p: u - np.array([p * p, np.sin(p)]),
                              G_u=lambda u, p: np.eye(2),
                              G_p=lambda u, p: -np.array([2 * p, np.cos(p)]), A=A)
    p = p0 + 3e-3
    x0 = np.array([p * p, np.sin(p), p])
    t0 = np.array([2 * p, np.cos(p), 1.0])
    found = locate_double_eigenvalue(problem, x0, a + 0.01, np.array([1.0, 0.0]),
                                     np.array([0.0, 1.0]), t0, tol_p=1e-10, newton_tol=1e-12)
    assert abs(found.x[-1] - p0) <= 1e-12 and abs(found.lam - a) <= 1e-9
    assert len(found.history) >= 3
    for d0, d1 in zip(found.history, found.history[1:]):
        assert d1 <= 20.0 * d0 * d0  # quadratic: e_(k+1) <= C e_k^2
    assert found.overlap <= 1e-8  # a Jordan block: left and right eigenvectors orthogonal


@pytest.mark.parametrize("sparse", [True, False])
@pytest.mark.parametrize("offset", [0.0, 1e-9, 1e-7])
def test_jordan_chain_near_a_double_eigenvalue_dense_or_sparse(sparse, offset, monkeypatch):
    """jordan_chain_near at a Jordan block [[a, 1], [0, a]] inside a 400 x 400 block-diagonal
    matrix: v = e_0, w = e_1 and overlap 0 to rounding at lambda = a, and within about the
    offset (as least squares on the dense matrix gives them) with lambda off by 1e-9 or 1e-7
    (an interpolated collision). No dense matrix for a sparse one: eps = 0 at N = 3000 spent
    minutes in a dense SVD for such collisions."""
    import scipy.sparse as sps

    from diskfriction.continuation.detection.locate import jordan_chain_near

    a, n = -0.7, 400
    rng = np.random.default_rng(3)
    A = sps.diags_array(np.concatenate([[a, a], 1.0 + rng.random(n - 2)])).tolil()
    A[0, 1] = 1.0
    for i in range(2, n - 1, 2):  # 2 x 2 blocks with real eigenvalues away from a
        A[i, i + 1] = 0.3
    A = sps.csr_array(A) if sparse else A.toarray()
    if sparse:
        def no_dense(self, *args, **kwargs):
            raise AssertionError("a sparse matrix made dense")

        monkeypatch.setattr(sps.csr_array, "toarray", no_dense)
        monkeypatch.setattr(sps.csc_array, "toarray", no_dense)
    v, w, overlap = jordan_chain_near(A, a + offset)
    tol = 1.5 * offset + 1e-12
    e0, e1 = np.eye(n)[0], np.eye(n)[1]
    assert np.allclose(v, e0, atol=tol) and overlap <= 2 * tol
    assert np.allclose(w / np.linalg.norm(w), e1, atol=tol)


def test_jordan_chain_refined_on_the_locators_last_factorization(monkeypatch):
    """jordan_chain with near = the LU of B at lambda 1e-9 away (the locator's last iterate):
    the same v, w and overlap as with a factorization of its own, to 1e-12, without one."""
    import scipy.sparse as sps

    from diskfriction.continuation.linalg import solves as linalg
    from diskfriction.continuation.detection.locate import _identity, jordan_chain

    a, n = -0.7, 400
    rng = np.random.default_rng(3)
    A = sps.diags_array(np.concatenate([[a, a], 1.0 + rng.random(n - 2)])).tolil()
    A[0, 1] = 1.0
    A = sps.csr_array(A)
    b, c = 1e-6 * np.eye(n)[1], 1e-6 * np.eye(n)[0]
    own = jordan_chain(A, a, b, c)
    near = linalg.factorize(linalg.bordered(A - (a + 1e-9) * _identity(A), b, c))
    factorized, original = [], linalg.factorize
    monkeypatch.setattr(linalg, "factorize", lambda *args: factorized.append(1) or original(*args))
    refined = jordan_chain(A, a, b, c, near=near)
    assert factorized == []
    assert np.allclose(refined[0], own[0], rtol=0, atol=1e-12)
    assert np.allclose(refined[1], own[1], rtol=0, atol=1e-12)
    assert abs(refined[2] - own[2]) <= 1e-12
