"""Bratu's problem, u'' + lambda e^u = 0 on (0, 1) with u(0) = u(1) = 0: a fold, on a mesh.

Central differences on n interior points (h = 1 / (n + 1)) give G(u, lambda) = L u + lambda e^u
with L = tridiag(1, -2, 1) / h^2, dG/du = L + diag(lambda e^u) as a sparse matrix. The branch
from u = 0 at lambda = 0 rises to the fold lambda_n and comes back on the upper branch, whose
u grows without bound as lambda -> 0. lambda_n converges at second order in h to the
continuous problem's lambda* = 3.513830719125162 (Bratu 1914, Gelfand 1963); the terms
of G are of size |u| / h^2, far above its residual (docs/api.md, Step length).

    diskfriction bifurcate --problem examples/bratu.py

The branch turns back at the fold and leaves the span at its start: the command writes it and
says so (exit 1), as for any branch that does not reach the span's end.
"""
import numpy as np
import scipy.sparse as sp

from diskfriction.continuation import BifurcationProblem, Options, problem_from_functions


def bratu(n: int = 50) -> BifurcationProblem:
    """The problem on n interior points, lambda from 0.01 over the fold and back to 0.01."""
    L = sp.diags([np.ones(n - 1), -2.0 * np.ones(n), np.ones(n - 1)], [-1, 0, 1], format="csr") * (n + 1) ** 2
    return BifurcationProblem(
        problem_from_functions(lambda u, lam: L @ u + lam * np.exp(u),
                               dG_du=lambda u, lam: (L + sp.diags(lam * np.exp(u))).tocsr(),
                               dG_dp=lambda u, lam: np.exp(u)),
        u0=np.zeros(n), p_span=(0.01, 4.0), parameter="lambda", matrix="dG/du",
        options=Options(special_points=("fold",)))


problem = bratu()
