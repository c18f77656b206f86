"""How spectra and linear systems are solved, as a user chooses it: Options.eigensolver and
Options.linear_solver (continuation/spectra/eigensolvers.py, linalg/solves.py), and the
structure a Problem subclass declares of its stability matrix (spectra/structure.py)."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla
import scipy.sparse as sp

from diskfriction.continuation import (DenseSpectra, LinearSolver, Options, Problem, StructuredMatrix,
                                       problem_from_functions, solve_branch)


def pair(p: float, at: float) -> np.ndarray:
    """[[q, 1], [-1, -q]], q = p - at: eigenvalues +-sqrt(q^2 - 1), a complex pair for |q| < 1,
    which dies at p = at + 1 (going up)."""
    q = p - at
    return np.array([[q, 1.0], [-1.0, -q]])


class TwoPairs(Problem):
    """G(u, p) = u (the branch u = 0), A(p) = diag(pair(p, 0), pair(p, 0.5)): two deaths, at
    p = 1 and 1.5; with `decoupled`, the second pair declared a decoupled block of A."""

    def __init__(self, decoupled: bool):
        self.decoupled = decoupled

    def residual(self, u, p):
        return u.copy()

    def jacobian(self, u, p):
        return np.eye(u.size)

    def dG_dp(self, u, p):
        return np.zeros(u.size)

    def stability_matrix(self, u, p):
        return sla.block_diag(pair(p, 0.0), pair(p, 0.5))

    def stability_structure(self, u, p):
        if not self.decoupled:
            return super().stability_structure(u, p)
        return StructuredMatrix(self.stability_matrix(u, p), decoupled=np.array([[2, 3]]))


@pytest.mark.parametrize("eigensolver", [DenseSpectra(), Options().eigensolver])
def test_a_declared_decoupled_block_is_tracked_but_takes_part_in_no_collision(eigensolver):
    """The block's eigenvalues are in every stored spectrum, its death at p = 1.5 is not located:
    its modes are excluded; the coupled pair's death at p = 1 is, as without the structure."""
    options = Options(special_points=(), eigensolver=eigensolver, workers=0)
    plain = solve_branch(TwoPairs(False), np.zeros(4), (0.0, 2.0), options)
    blocked = solve_branch(TwoPairs(True), np.zeros(4), (0.0, 2.0), options)
    assert [c.kind for c in plain.collisions] == ["death", "death"]
    assert [c.p for c in plain.collisions] == pytest.approx([1.0, 1.5], abs=1e-9)
    assert [(c.kind, c.p) for c in blocked.collisions] == [("death", pytest.approx(1.0, abs=1e-9))]
    assert blocked.eigenvalues.shape == plain.eigenvalues.shape == (len(blocked.p), 4)
    at_start = np.sort_complex(blocked.eigenvalues[0])
    assert np.allclose(at_start, np.sort_complex(np.linalg.eigvals(TwoPairs(False).stability_matrix(None, 0.0))))


def sparse_chain(n: int = 60):
    """G(u, p) = (L - 2 I) u + sin(u) / 10 - p, L the periodic second difference: a sparse
    Jacobian, diagonally dominant (a branch without folds), that SuperLU factorizes."""
    L = sp.diags_array([np.full(n, -2.0), np.ones(n - 1), np.ones(n - 1)], offsets=[0, 1, -1]).tolil()
    L[0, n - 1] = L[n - 1, 0] = 1.0
    K = sp.csr_array(L) - 2.0 * sp.eye_array(n)

    def G(u, p):
        return K @ u + 0.1 * np.sin(u) - p

    def G_u(u, p):
        return sp.csr_array(K + sp.diags_array(0.1 * np.cos(u)))

    def G_p(u, p):
        return -np.ones(n)

    return problem_from_functions(G, dG_du=G_u, dG_dp=G_p), np.zeros(n)


def test_a_linear_solvers_ordering_follows_the_same_branch(monkeypatch):
    """SuperLU's minimum degree ordering on A + A^T against its default: every factorization of
    the run takes it, and the same points and spectra come out to rounding; an unknown ordering
    is refused at the door."""
    from diskfriction.continuation.linalg import solves

    problem, u0 = sparse_chain()
    options = Options(special_points=(), workers=0, ds_max=0.05)
    default = solve_branch(problem, u0, (0.0, 1.0), options)
    taken, factorize = [], solves.factorize
    monkeypatch.setattr(solves, "factorize", lambda M, ordering=None: taken.append(ordering) or factorize(M, ordering))
    solver = LinearSolver("MMD_AT_PLUS_A")
    ordered = solve_branch(problem, u0, (0.0, 1.0), Options(special_points=(), workers=0, ds_max=0.05,
                                                             linear_solver=solver))
    assert taken and all(ordering == {"permc_spec": "MMD_AT_PLUS_A"} for ordering in taken)
    assert default.success and ordered.success and len(default.p) == len(ordered.p)
    assert np.abs(default.u - ordered.u).max() <= 1e-10
    assert np.abs(default.eigenvalues - ordered.eigenvalues).max() <= 1e-9 * np.abs(default.eigenvalues).max()
    with pytest.raises(ValueError, match="ordering must be one of"):
        LinearSolver("AMD")
