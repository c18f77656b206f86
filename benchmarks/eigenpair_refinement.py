"""Eigenpair refinement against a dense spectrum: what continuing every
eigenpair of the chain's J from one point to the next costs, and how accurate it is.

For each N: the paper's scene with N disks and eps = 1e-4 relaxed from rest to F_x = 0.002,
its eigensystem by LAPACK (tracking.eigensystem, one BLAS thread; the time is the median of
--repeat); then one quasistatic step to 0.002 + dF and every eigenpair of the new J refined
from the old ones (eigenvalues predicted to first order, lambda + l^H dA r, as the slopes do;
vectors the old ones) by two-sided Rayleigh quotient iteration on the periodic block-tridiagonal
matrix (continuation/spectra/eigenpairs.py; one core, the median of --repeat). Printed: the times,
the largest eigenvalue error against LAPACK's at the new point over the spectral radius, the
largest residual |A r - lambda r| over it, and whether the result passes the refinement's
certificate (continuation/spectra/refinement.py: residuals, error discs, trace identities). Run:
python benchmarks/eigenpair_refinement.py [--N 100,300,1000] [--dF 1e-4,5e-4] [--iterations 2]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from diskfriction.continuation.linalg.block_tridiagonal import PeriodicBlocks, block_major as disk_major
from diskfriction.continuation.spectra.eigenpairs import refine_eigenpairs
from diskfriction.continuation.spectra.refinement import TOLERANCE, certified
from diskfriction.continuation.linalg.solves import blas_threads, dense
from diskfriction.continuation.spectra.tracking import eigensystem, eigenvalue_slopes, spectra_on, track
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
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
    args = ap.parse_args()
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load average {open('/proc/loadavg').read().split()[0]}")
    print("| N | n | dF | LAPACK, both vectors | refined | LAPACK / refined | "
          "max eigenvalue error / radius | max residual / radius | certified |")
    print("|---|---|---|---|---|---|---|---|---|")
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
            # first order in the matrix's change: lambda + l^H (A1 - A0) r (what the slopes predict)
            step = eigenvalue_slopes(old, A - stability(system, q0, xi0, 0.002))
            guess = old.values + step
            scale = np.abs(old.values).max()
            tol = TOLERANCE * scale
            refined_s, (values, right, left, residual) = seconds(
                lambda: refine_eigenpairs(blocks, guess, old.right, old.left, args.iterations, tol),
                args.repeat)
            with blas_threads(), spectra_on("cpu"):
                exact = eigensystem(dense(A), False).values
            radius = np.abs(exact).max()
            error = np.abs(track(exact, values) - exact).max() / radius
            passed = certified(blocks, values, right, left, residual, scale) is not None
            print(f"| {N} | {A.shape[0]} | {dF:g} | {lapack_s:.3g} s | {refined_s:.3g} s | "
                  f"{lapack_s / refined_s:.3g} | {error:.1e} | {residual.max() / radius:.1e} | {passed} |",
                  flush=True)


if __name__ == "__main__":
    main()
