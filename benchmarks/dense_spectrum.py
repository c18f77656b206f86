"""What one full spectrum costs: LAPACK's dgeev on the chain's stability matrix, the floor
under the fast detection's cost (issue 8; docs/continuation.md, Cost).

For each N: the dense J (n = 3N) of the paper's scene with N disks at F_x = 0.002 (eps = 1e-4),
and the median time of its eigenvalues alone, with right vectors, and with left and right
vectors (what a full sample computes: spectra.eigensystem), one BLAS thread. Every accepted
point and every full split sample costs one of the last. Run:
python benchmarks/dense_spectrum.py [--N 10,100,200] [--repeat 7]
"""
from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.linalg as sla

from diskfriction.disks.equilibria import DiskEquilibria, relax
from diskfriction.continuation.linalg import blas_threads, dense
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def median_ms(fn, repeat: int) -> float:
    """Median wall time of fn() over `repeat` calls after one warm-up call, in ms."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times)) * 1e3


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--N", default="10,100,200")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load average {open('/proc/loadavg').read().split()[0]}")
    print("| N | n | eigenvalues | with right vectors | with left and right vectors |")
    print("|---|---|---|---|---|")
    for N in [int(v) for v in args.N.split(",") if v]:
        system = System.from_scene(Scene(N=N, eps=1e-4))
        q, xi = relax(system, *system.rest_state(), 0.002)
        A = dense(DiskEquilibria(system, q, xi, 0.002, "J").stability_matrix(q, 0.002))
        with blas_threads():
            ms = [median_ms(lambda: sla.eigvals(A, check_finite=False), args.repeat),
                  median_ms(lambda: sla.eig(A, check_finite=False), args.repeat),
                  median_ms(lambda: sla.eig(A, left=True, check_finite=False), args.repeat)]
        print(f"| {N} | {A.shape[0]} | " + " | ".join(f"{t:.3g} ms" if t < 1e3 else f"{t / 1e3:.3g} s" for t in ms)
              + " |", flush=True)


if __name__ == "__main__":
    main()
