"""Spectra per point on a problem with many close real eigenvalues (issue 27 item 5): the
Brusselator reaction-diffusion chain, its homogeneous equilibrium followed in B.

    u_t = D_u u_xx + A - (B + 1) u + u^2 v,   v_t = D_v v_xx + B u - u^2 v   on (0, 1),

u = A, v = B / A at both ends, central differences on N interior points (n = 2N unknowns, a
sparse dG/du). The equilibrium is u = A, v = B / A for every B; the Jacobian decouples into one
2 x 2 block per Fourier mode k, [[B - 1 - D_u q_k, A^2], [-B, -A^2 - D_v q_k]], q_k =
4 (N + 1)^2 sin^2(k pi / (2 (N + 1))), so real eigenvalues of different modes cross each other
as B moves (they do not interact) while each mode's pair collides and may cross the imaginary
axis (Turing and Hopf). Printed per N and theta: accepted points, collisions, Hopf points, the
dense spectra the run computed (linalg's ledger) and their number per point, the corrector
solves, the seconds. Measured in this run, scans inline.

Run: python benchmarks/rd_brusselator.py [N ...]   (default: 50 100)
"""
from __future__ import annotations

import sys
import time

import numpy as np
import scipy.sparse as sp

from diskfriction.continuation import Options, problem_from_functions, solve_branch
from diskfriction.continuation.linalg import measured

A, D_U, D_V = 2.0, 1.6e-3, 8e-3
SPAN = (1.0, 5.5)


def reaction_diffusion(N: int):
    """The problem and its homogeneous equilibrium's state (u = A, v = 1 / A at B = 1)."""
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
        u = w[:N]
        return np.concatenate([-u, D_V * ends / A + u])

    state = np.concatenate([np.full(N, A), np.full(N, SPAN[0] / A)])
    return problem_from_functions(G, dG_du=dG_dw, dG_dp=dG_dB), state


def run(N: int, theta) -> str:
    problem, state = reaction_diffusion(N)
    start = time.perf_counter()
    with measured() as spent:
        result = solve_branch(problem, state, SPAN, Options(theta=theta, workers=0))
    seconds = time.perf_counter() - start
    return (f"{N:>5} {2 * N:>5} {str(theta):>6} {len(result.p):>7} {len(result.collisions):>10} "
            f"{len(result.hopf):>5} {spent.spectra:>8} {spent.spectra / len(result.p):>9.1f} "
            f"{spent.solves:>7} {seconds:>7.1f}")


def main(sizes) -> None:
    print(f"Brusselator reaction-diffusion, A = {A:g}, D_u = {D_U:g}, D_v = {D_V:g}, B {SPAN[0]:g} -> {SPAN[1]:g}")
    print(f"{'N':>5} {'n':>5} {'theta':>6} {'points':>7} {'collisions':>10} {'hopf':>5} "
          f"{'spectra':>8} {'per point':>9} {'solves':>7} {'s':>7}")
    for N in sizes:
        for theta in (1.0, None):
            print(run(N, theta), flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [50, 100])
