"""The Brusselator as a reaction-diffusion chain: many modes that cross without interacting.

    u_t = D_u u_xx + A - (B + 1) u + u^2 v,   v_t = D_v v_xx + B u - u^2 v   on (0, 1),

u = A, v = B / A at both ends, central differences on N interior points (n = 2N unknowns, a
sparse dG/du). The homogeneous state u = A, v = B / A is an equilibrium for every B, and the
Jacobian decouples into one 2 x 2 block per Fourier mode k = 1..N,

    [[B - 1 - D_u q_k, A^2], [-B, -A^2 - D_v q_k]],   q_k = 4 (N + 1)^2 sin^2(k pi / (2 (N + 1))),

so real eigenvalues of different modes pass through each other as B moves (they do not
interact), while each mode's pair collides where its block's discriminant vanishes
(collision_points), crosses the imaginary axis where its trace vanishes with a positive
determinant (hopf_points), and a real eigenvalue crosses zero where the determinant vanishes
(turing_points: simple branch points, where patterned branches leave the homogeneous one;
two modes' points 0.014 apart at N = 50). The certifier sees the crossings of different modes
as decoupled pairs (certify.decoupled) and spends no spectrum on them (docs/api.md, Limits).
A = 2, D_u = 1.6e-3, D_v = 8e-3, B from 1 to 5.5, N = 50: three collisions, two Hopf points,
twelve branch points.

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
    trace^2 - 4 det changes sign
    (roots by brentq to 1e-15 on a grid of 20001), sorted."""
    roots = []
    for q in wavenumbers(N):
        def disc(B):
            trace, det = _block(B, q)
            return trace * trace - 4.0 * det
        grid = np.linspace(*span, 20001)
        values = disc(grid)
        for m in np.flatnonzero(np.sign(values[:-1]) != np.sign(values[1:])):
            roots.append(brentq(disc, grid[m], grid[m + 1], xtol=1e-15))
    return np.sort(roots)


def _block(B: float, q):
    """Trace and determinant of mode q's block."""
    a, d = B - 1.0 - D_U * q, -A * A - D_V * q
    return a + d, a * d + A * A * B


def hopf_points(N: int, span=SPAN) -> np.ndarray:
    """The B in span where a mode's trace vanishes, B = 1 + A^2 + (D_u + D_v) q, with a positive
    determinant (a pair on the imaginary axis), sorted."""
    q = wavenumbers(N)
    B = 1.0 + A * A + (D_U + D_V) * q
    inside = (B > span[0]) & (B < span[1]) & (_block(B, q)[1] > 0.0)
    return np.sort(B[inside])


def turing_points(N: int, span=SPAN) -> np.ndarray:
    """The B in span where a mode's determinant vanishes, B = (1 + D_u q)(A^2 + D_v q) / (D_v q)
    (a real eigenvalue through zero), sorted."""
    q = wavenumbers(N)
    B = (1.0 + D_U * q) * (A * A + D_V * q) / (D_V * q)
    return np.sort(B[(B > span[0]) & (B < span[1])])


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
