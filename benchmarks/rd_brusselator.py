"""Spectra per point on a problem with many close real eigenvalues: the
Brusselator reaction-diffusion chain of examples/brusselator_chain.py, its homogeneous
equilibrium followed in B (n = 2N unknowns, sparse dG/du; one 2 x 2 block per Fourier mode,
so real eigenvalues of different modes cross each other without interacting while each mode's
pair collides and may cross the imaginary axis). Printed per N and theta: accepted points,
collisions, Hopf points, the dense spectra the run computed (linalg's ledger) and their number
per point, the corrector solves, the seconds, and the largest distance of a collision from
its closed form (collision_points). Measured in this run, scans inline.

Run: python benchmarks/rd_brusselator.py [N ...]   (default: 50 100)
"""
from __future__ import annotations

import importlib.util
import sys
import time
from pathlib import Path

import numpy as np

from diskfriction.continuation import Options, solve_branch
from diskfriction.continuation.linalg.solves import measured

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "brusselator_chain.py"


def load_example():
    """examples/brusselator_chain.py as a module (examples/ is not a package)."""
    spec = importlib.util.spec_from_file_location("brusselator_chain", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run(chain, N: int, theta) -> str:
    problem = chain.brusselator_chain(N)
    start = time.perf_counter()
    with measured() as spent:
        result = solve_branch(problem.problem, problem.u0(chain.SPAN[0]), chain.SPAN,
                              Options(theta=theta, workers=0))
    seconds = time.perf_counter() - start
    exact = chain.collision_points(N)
    got = np.sort([c.p for c in result.collisions])
    error = f"{np.abs(got - exact).max():.1e}" if got.size == exact.size else "count differs"
    return (f"{N:>5} {2 * N:>5} {str(theta):>6} {len(result.p):>7} {len(result.collisions):>10} "
            f"{len(result.hopf):>5} {spent.spectra:>8} {spent.spectra / len(result.p):>9.1f} "
            f"{spent.solves:>7} {seconds:>7.1f} {error:>13}")


def main(sizes) -> None:
    chain = load_example()
    print(f"Brusselator reaction-diffusion, A = {chain.A:g}, D_u = {chain.D_U:g}, "
          f"D_v = {chain.D_V:g}, B {chain.SPAN[0]:g} -> {chain.SPAN[1]:g}")
    print(f"{'N':>5} {'n':>5} {'theta':>6} {'points':>7} {'collisions':>10} {'hopf':>5} "
          f"{'spectra':>8} {'per point':>9} {'solves':>7} {'s':>7} {'|B - exact|':>13}")
    for N in sizes:
        for theta in (1.0, None):
            print(run(chain, N, theta), flush=True)


if __name__ == "__main__":
    main([int(a) for a in sys.argv[1:]] or [50, 100])
