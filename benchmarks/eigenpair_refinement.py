"""Eigenpair refinement against a dense spectrum (issue 26 item 1): what continuing every
eigenpair of the chain's J from one point to the next costs, and how accurate it is.

For each N: the paper's scene with N disks and eps = 1e-4 relaxed from rest to F_x = 0.002,
its eigensystem by LAPACK (spectra.eigensystem, one BLAS thread; the time is the median of
--repeat); then one quasistatic step to 0.002 + dF and every eigenpair of the new J refined
from the old ones (eigenvalues predicted to first order, lambda + l^H dA r, as the slopes do;
vectors the old ones) by two-sided Rayleigh quotient iteration on the periodic block-tridiagonal
matrix (continuation/block_tridiagonal.py) with 1 and 2 compiled threads. Printed: the times,
the largest eigenvalue error against LAPACK's at the new point over the spectral radius, the
largest residual |A r - lambda r| over it, and whether the error discs kappa_i * residual_i
are disjoint (then the refined set is the whole spectrum). Run:
python benchmarks/eigenpair_refinement.py [--N 100,300,1000] [--dF 1e-4,5e-4] [--iterations 2]
"""
from __future__ import annotations

import argparse
import time

import numba
import numpy as np

from diskfriction.continuation.block_tridiagonal import PeriodicBlocks, disk_major, refine_eigenpairs, separated
from diskfriction.continuation.linalg import blas_threads, dense
from diskfriction.continuation.spectra import eigensystem, eigenvalue_slopes, spectra_on, track
from diskfriction.disks.equilibria import DiskEquilibria, relax
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def stability(system, q, xi, F_x):
    return DiskEquilibria(system, q, xi, F_x, "J").stability_matrix(q, F_x)


def seconds(fn, repeat: int) -> tuple[float, object]:
    """Median wall time of fn() over `repeat` calls (after a warm-up call) and its last result."""
    out = fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--N", default="100,300,1000")
    ap.add_argument("--dF", default="1e-4,5e-4")
    ap.add_argument("--iterations", type=int, default=6)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--reach", type=float, default=4.0, help="clusters: pairs within REACH times their predicted moves")
    args = ap.parse_args()
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load average {open('/proc/loadavg').read().split()[0]}, "
          f"{numba.config.NUMBA_NUM_THREADS} compiled threads available")
    print("| N | n | dF | LAPACK, both vectors | refined, 1 thread | 2 threads | LAPACK / refined (2) | "
          "max eigenvalue error / radius | max residual / radius | discs disjoint |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for N in [int(v) for v in args.N.split(",") if v]:
        system = System.from_scene(Scene(N=N, eps=1e-4))
        q0, xi0 = relax(system, *system.rest_state(), 0.002)
        with blas_threads(), spectra_on("cpu"):
            lapack_s, old = seconds(lambda: eigensystem(dense(stability(system, q0, xi0, 0.002)), True),
                                    1 if N >= 500 else args.repeat)
        for dF in [float(v) for v in args.dF.split(",") if v]:
            q1, xi1 = relax(system, q0, xi0, 0.002 + dF)
            A = stability(system, q1, xi1, 0.002 + dF)
            b = system.ndof // N
            order = disk_major(N, b)
            blocks = PeriodicBlocks.from_matrix(A, b, order)
            guess_right, guess_left = old.right[order], old.left[:, order]
            # first order in the matrix's change: lambda + l^H (A1 - A0) r (what the slopes predict)
            step = eigenvalue_slopes(old, A - stability(system, q0, xi0, 0.002))
            guess = old.values + step
            scale = np.abs(old.values).max()
            reach, tol = args.reach * np.abs(step) + 1e-9 * scale, 1e-13 * scale
            times = []
            for threads in (1, 2):
                numba.set_num_threads(min(threads, numba.config.NUMBA_NUM_THREADS))
                t, (values, right, left, residual) = seconds(
                    lambda: refine_eigenpairs(blocks, guess, guess_right, guess_left, reach, args.iterations, tol),
                    args.repeat)
                times.append(t)
            with blas_threads(), spectra_on("cpu"):
                exact = eigensystem(dense(A), False).values
            radius = np.abs(exact).max()
            error = np.abs(track(exact, values) - exact).max() / radius
            kappa = np.linalg.norm(left, axis=1)  # |r| = 1 and l^H r = 1
            disjoint = separated(values, kappa * residual)
            print(f"| {N} | {A.shape[0]} | {dF:g} | {lapack_s:.3g} s | {times[0]:.3g} s | {times[1]:.3g} s | "
                  f"{lapack_s / times[1]:.3g} | {error:.1e} | {residual.max() / radius:.1e} | {disjoint} |",
                  flush=True)


if __name__ == "__main__":
    main()
