"""The Brusselator as a reaction-diffusion chain: many modes that cross without interacting.

    u_t = D_u u_xx + A - (B + 1) u + u^2 v,   v_t = D_v v_xx + B u - u^2 v   on (0, 1),

u = A, v = B / A at both ends, central differences on N interior points (n = 2N unknowns, a
sparse dG/du). The homogeneous state u = A, v = B / A is an equilibrium for every B, and the
Jacobian decouples into one 2 x 2 block per Fourier mode k = 1..N,

    [[B - 1 - D_u q_k, A^2], [-B, -A^2 - D_v q_k]],   q_k = 4 (N + 1)^2 sin^2(k pi / (2 (N + 1))),

so real eigenvalues of different modes pass through each other as B moves (they do not
interact), while each mode's pair collides where its block's discriminant vanishes
(collision_points) and may cross the imaginary axis. The certifier sees those crossings as
decoupled pairs (certify.decoupled) and spends no spectrum on them (docs/api.md, Limits).
A = 2, D_u = 1.6e-3, D_v = 8e-3, B from 1 to 5.5, N = 50: three collisions, two Hopf points.

    diskfriction bifurcate --problem examples/brusselator_chain.py
"""
import numpy as np
import scipy.sparse as sp
from scipy.optimize import brentq

from diskfriction.continuation import BifurcationProblem, problem_from_functions

A, D_U, D_V = 2.0, 1.6e-3, 8e-3
SPAN = (1.0, 5.5)


def wavenumbers(N: int) -> np.ndarray:
    """q_k = 4 (N + 1)^2 sin^2(k pi / (2 (N + 1))), the eigenvalues of -d^2/dx^2 on the mesh."""
    return 4.0 * (N + 1) ** 2 * np.sin(np.arange(1, N + 1) * np.pi / (2 * (N + 1))) ** 2


def collision_points(N: int, span=SPAN) -> np.ndarray:
    """The B in span where some mode's block has a double eigenvalue: its discriminant
    (B - 1 - A^2 - (D_u + D_v) q)^2 - 4 ((B - 1 - D_u q)(-A^2 - D_v q) + A^2 B) changes sign
    (roots by brentq to 1e-15 on a grid of 20001), sorted."""
    roots = []
    for q in wavenumbers(N):
        def disc(B):
            a, d = B - 1.0 - D_U * q, -A * A - D_V * q
            return (a + d) ** 2 - 4.0 * (a * d + A * A * B)
        grid = np.linspace(*span, 20001)
        values = disc(grid)
        for m in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:])):
            roots.append(brentq(disc, grid[m], grid[m + 1], xtol=1e-15))
    return np.sort(roots)


def brusselator_chain(N: int = 50) -> BifurcationProblem:
    """The problem on N interior points, B over SPAN from the homogeneous state."""
    h2 = (N + 1) ** 2
    L = sp.diags([np.ones(N - 1), -2.0 * np.ones(N), np.ones(N - 1)], [-1, 0, 1], format="csr") * h2
    ends = np.zeros(N)
    ends[[0, -1]] = h2

    def G(w, B):
        u, v = w[:N], w[N:]
        return np.concatenate([D_U * (L @ u + A * ends) + A - (B + 1) * u + u * u * v,
                               D_V * (L @ v + B / A * ends) + B * u - u * u * v])

    def dG_dw(w, B):
        u, v = w[:N], w[N:]
        return sp.bmat([[D_U * L + sp.diags(2 * u * v - (B + 1)), sp.diags(u * u)],
                        [sp.diags(B - 2 * u * v), D_V * L - sp.diags(u * u)]], format="csr")

    def dG_dB(w, B):
        return np.concatenate([-w[:N], D_V * ends / A + w[:N]])

    return BifurcationProblem(problem_from_functions(G, dG_du=dG_dw, dG_dp=dG_dB),
                              u0=lambda B: np.concatenate([np.full(N, A), np.full(N, B / A)]),
                              p_span=SPAN, parameter="B", matrix="dG/du")


problem = brusselator_chain()
