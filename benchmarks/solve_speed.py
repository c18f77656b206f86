"""Sparse solves of the chain: SuperLU's own solve against compiled substitution over its
factors (continuation/linalg/triangular.py), what copying the factors costs, and the factorization
with the collision locator's borders as unit vectors and as it scales them
(locate.BORDER_SCALE: fill and time); then SuperLU's ordering as the shift-invert takes it
(nearest.SHIFT_INVERT_ORDERING) against its default (COLAMD, partial pivoting), each also with
its ordering kept for a repeated pattern (continuation/linalg/orderings.py), on the chain's matrix and
on a sheared packing's A - sigma I (the spectral window's shift-invert, --packing N
disks, window [-3, 8]; 0: none); last, the packing's bordered corrector matrix with its
linear solver (equilibria.LINEAR_SOLVER: minimum degree on A + A^T, partial pivoting) against
SuperLU's default.

The chain's matrix is the bordered A - sigma I of the locator and of a shift-invert (A the
stability matrix J of the chain at F_x = 0.002, sigma in the middle of its spectrum). Run:
python benchmarks/solve_speed.py [--N 100,1000] [--packing 256] [--repeat 7]. Medians over
repeats of many calls, one BLAS thread.
"""
from __future__ import annotations

import argparse

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.continuation.linalg import orderings as reuse
from diskfriction.continuation.linalg.solves import bordered, blas_threads
from diskfriction.continuation.spectra.nearest import SHIFT_INVERT_ORDERING
from diskfriction.continuation.detection.locate import BORDER_SCALE
from diskfriction.continuation.stepping.newton import bordered_matrix, tangent
from diskfriction.models.packing.equilibria import LINEAR_SOLVER, PackingEquilibria
from diskfriction.continuation.linalg.triangular import TriangularFactors
from diskfriction.scenes import Scene
from diskfriction.symbolic import System
from kernels import per_call  # benchmarks/kernels.py: this script's folder is on sys.path


def median_us(fn, calls: int, repeat: int) -> float:
    fn()
    return per_call(fn, calls, repeat) * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--N", default="100,1000")
    ap.add_argument("--packing", type=int, default=256)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    try:
        chains = [int(v) for v in args.N.split(",")]
    except ValueError:
        ap.error(f"--N: expected disk counts separated by commas, e.g. 100,1000 (got {args.N!r})")
    if min(chains) < 2 or args.packing == 1 or args.packing < 0 or args.repeat < 1:
        ap.error(f"need every --N >= 2, --packing 0 (none) or >= 2 and --repeat >= 1 "
                 f"(got {args.N}, {args.packing}, {args.repeat})")
    print(f"load average {open('/proc/loadavg').read().split()[0]} at the start")
    for N in chains:
        system = System.from_scene(Scene(N=N, eps=1e-4))
        q, xi = relax(system, *system.rest_state(), 0.002)
        A = DiskEquilibria(system, q, xi, 0.002, "J", sparse=True).stability_matrix(q, 0.002)
        n = A.shape[0]
        rng = np.random.default_rng(0)
        sigma = float(np.median(A.diagonal()))
        K = A - sigma * sp.identity(n, format="csr")
        M = sp.csc_array(bordered(K, rng.standard_normal(n), rng.standard_normal(n)))
        r = rng.standard_normal(n + 1)
        calls = max(20, 60000 // n)
        with blas_threads():
            lu = spla.splu(M)
            tri = TriangularFactors.of(lu)
            factor = median_us(lambda: spla.splu(M), calls // 10, args.repeat)
            rows = {"SuperLU factorization": factor,
                    "copy of the factors": median_us(lambda: TriangularFactors.of(spla.splu(M)),
                                                     calls // 10, args.repeat) - factor,
                    "SuperLU solve": median_us(lambda: lu.solve(r), calls, args.repeat),
                    "SuperLU solve, transposed": median_us(lambda: lu.solve(r, trans="T"), calls, args.repeat),
                    "substitution": median_us(lambda: tri.solve(r), calls, args.repeat),
                    "substitution, transposed": median_us(lambda: tri.solve(r, True), calls, args.repeat)}
        print(f"N = {N} (bordered n = {n + 1}, nnz(L + U) = {lu.L.nnz + lu.U.nnz}):")
        for what, us in rows.items():
            print(f"    {what:<28}{us:9.1f} us")
        unit = [v / np.linalg.norm(v) for v in (rng.standard_normal(n), rng.standard_normal(n))]
        for label, scale in (("unit borders", 1.0), ("locator's borders", BORDER_SCALE * np.abs(A.data).max())):
            B = sp.csc_array(bordered(K, scale * unit[0], scale * unit[1]))
            with blas_threads():
                fill = spla.splu(B)
                us = median_us(lambda: spla.splu(B), calls // 10, args.repeat)
            print(f"    factorization, {label:<17}{us:9.1f} us   nnz(L + U) = {fill.L.nnz + fill.U.nnz}")
        compare_orderings(f"N = {N}, A - sigma I", sp.csc_array(K), r[:n], calls, args.repeat)
    if args.packing:
        A, M = packing_matrices(args.packing)
        rng = np.random.default_rng(0)
        calls = max(20, 60000 // A.shape[0])
        compare_orderings(f"{args.packing} sheared disks, A - sigma I", A, rng.standard_normal(A.shape[0]), calls,
                          args.repeat)
        compare_orderings(f"{args.packing} sheared disks, the corrector's bordered matrix", M,
                          rng.standard_normal(M.shape[0]), calls,
                          args.repeat, (("the packing's (MMD, A + A^T, partial pivoting)",
                                         LINEAR_SOLVER.options), DEFAULT))


DEFAULT = ("SuperLU's default (COLAMD)", {})


def compare_orderings(label: str, M, r, calls: int, repeat: int,
                      orderings=(("shift-invert's (MMD, A + A^T)", SHIFT_INVERT_ORDERING), DEFAULT)) -> None:
    """Factorization, nnz(L + U), substitution and backward error with each of `orderings`
    (name, splu's keywords; default: the shift-invert's and SuperLU's default); the
    factorization again with the ordering kept for the pattern (continuation/linalg/orderings.py: what
    the core does from the second matrix of a pattern on)."""
    print(f"{label} (n = {M.shape[0]}):")
    for name, options in orderings:
        with blas_threads():
            lu = spla.splu(M, **options)
            tri = TriangularFactors.of(lu)
            factor = median_us(lambda: spla.splu(M, **options), calls // 10, repeat)
            kept = median_us(lambda: reuse.splu(M, options), calls // 10, repeat)
            solve = median_us(lambda: tri.solve(r), calls, repeat)
            x = tri.solve(r)
            residual = np.abs(M @ x - r).max() / (abs(M).max() * np.abs(x).max())
        print(f"    {name:<30} factorization {factor:8.1f} us ({kept:.1f} us with the ordering kept), "
              f"substitution {solve:7.1f} us, nnz(L + U) = {lu.L.nnz + lu.U.nnz}, "
              f"backward error {residual:.1e}")


def packing_matrices(N: int):
    """(A_red - sigma I, the corrector's bordered matrix [[G_u, G_p], [t^T]]) (CSC) of N disks
    (seed 1) at the start of their shear, sigma the centre of the window [-3, 8], t the branch's
    tangent there."""
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.models.packing.shear import mass_diagonal, network_of, start
    from diskfriction.scenes.packing import PackingScene
    scene = PackingScene(N=N, seed=1)
    packing = prepare_scene(scene)
    network = network_of(scene, packing)
    q, xi, rows = start(network, packing.positions)
    problem = PackingEquilibria(network, q, xi, rows, 0.0, mass_diagonal(network, scene.m, scene.inertia),
                                scene.matrix)
    A = problem.reduced(q, 0.0)
    x = np.append(q, 0.0)
    e_p = np.zeros(x.size)
    e_p[-1] = 1.0
    M = sp.csc_array(bordered_matrix(problem, x, tangent(problem, x, e_p)))
    return sp.csc_array(A - 2.5 * sp.identity(A.shape[0], format="csr")), M


if __name__ == "__main__":
    main()
