"""What one full spectrum costs: LAPACK's dgeev on the chain's stability matrix, the floor
under the fast detection's cost (docs/notes/chain-performance.md, "N = 100 in 10 s: where the
time goes"), and cuSOLVER's geev on a GPU (--spectra cpu,gpu; docs/notes/core-spectra.md, "Dense
spectra on a GPU").

For each N: the dense J (n = 3N) of the paper's scene with N disks at F_x = 0.002 (eps = 1e-4),
and the median time of its eigenvalues alone, with right vectors, and with left and right
vectors (what a full sample computes: tracking.eigensystem), one BLAS thread. Every accepted
point and every full split sample costs one of the last. With gpu among --spectra, also
tracking.eigensystem's eigenvalues alone and with both vectors on the GPU (copies to and from the
device included), the CPU's time over the GPU's, and the largest distance of the GPU's
eigenvalues from LAPACK's over the spectral radius. Run:
python benchmarks/dense_spectrum.py [--N 10,100,200] [--repeat 7] [--spectra cpu,gpu]
"""
from __future__ import annotations

import argparse
import time

import numpy as np
import scipy.linalg as sla

from diskfriction.continuation.linalg.solves import blas_threads, dense
from diskfriction.continuation.spectra.tracking import eigensystem, spectra_on, track
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
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


def shown(ms: float) -> str:
    return f"{ms:.3g} ms" if ms < 1e3 else f"{ms / 1e3:.3g} s"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--N", default="10,100,200")
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--spectra", default="cpu", help="cpu, or cpu,gpu")
    args = ap.parse_args()
    gpu = "gpu" in args.spectra.split(",")
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load average {open('/proc/loadavg').read().split()[0]}")
    head = "| N | n | eigenvalues | with right vectors | with left and right vectors |"
    if gpu:
        head += " GPU eigenvalues | GPU with both vectors | CPU / GPU (both vectors) | GPU - LAPACK |"
    print(head)
    print("|---" * (head.count("|") - 1) + "|")
    for N in [int(v) for v in args.N.split(",") if v]:
        system = System.from_scene(Scene(N=N, eps=1e-4))
        q, xi = relax(system, *system.rest_state(), 0.002)
        A = dense(DiskEquilibria(system, q, xi, 0.002, "J").stability_matrix(q, 0.002))
        with blas_threads(), spectra_on("cpu"):
            ms = [median_ms(lambda: sla.eigvals(A, check_finite=False), args.repeat),
                  median_ms(lambda: sla.eig(A, check_finite=False), args.repeat),
                  median_ms(lambda: eigensystem(A, True), args.repeat)]
            lapack = eigensystem(A, False).values
        row = f"| {N} | {A.shape[0]} | " + " | ".join(shown(t) for t in ms) + " |"
        if gpu:
            with spectra_on("gpu"):
                on_gpu = [median_ms(lambda: eigensystem(A, False), args.repeat),
                          median_ms(lambda: eigensystem(A, True), args.repeat)]
                values = eigensystem(A, True).values
            error = np.abs(track(lapack, values) - lapack).max()
            row += (" " + " | ".join(shown(t) for t in on_gpu)
                    + f" | {ms[2] / on_gpu[1]:.3g} | {error / np.abs(lapack).max():.1e} |")
        print(row, flush=True)


if __name__ == "__main__":
    main()
