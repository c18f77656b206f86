"""Continuation benchmark on the paper's scene: cost per accepted point and its parts, the whole
diagram with the fast and the exhaustive detection. Cost against N: benchmarks/scaling.py.

Run: python benchmarks/continuation_speed.py [--repeat 5]. Medians over repeats, warm (kernels
compiled), one BLAS thread as the sweeps use.
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from diskfriction.continuation.detection.collisions import DetectionParams
from diskfriction.continuation.linalg.solves import blas_threads, measured
from diskfriction.continuation.spectra.tracking import eigensystem
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def timed(fn, repeat: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def per_call(fn, calls: int = 2000) -> float:
    fn()
    t0 = time.perf_counter()
    for _ in range(calls):
        fn()
    return (time.perf_counter() - t0) / calls


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    print(f"load average {open('/proc/loadavg').read().split()[0]} at the start")
    system = System.from_scene(Scene())
    sweep(system, 0.0, 0.12)  # warm up
    off = SweepParams(detection=DetectionParams(enabled=False))
    t, branch = timed(lambda: sweep(system, 0.0, 0.12, "J", off), args.repeat)
    print(f"N = 10, detection off: {len(branch)} points in {t * 1e3:.0f} ms = "
          f"{t / len(branch) * 1e3:.2f} ms per accepted point (Newton + eigenvalues + history)")
    fast = SweepParams(detection=DetectionParams(mode="fast"))
    t, branch = timed(lambda: sweep(system, 0.0, 0.12, "J", fast), args.repeat)
    print(f"N = 10, fast detection: {t / len(branch) * 1e3:.2f} ms per accepted point "
          f"(with eigenvectors, slopes, certification and location)  (target <= 0.1 ms)")
    q, xi = branch.q[len(branch) // 2], branch.xi[len(branch) // 2]
    F, J = system.forces_and_jacobian(q, xi, 0.06)
    with blas_threads():
        parts = {"F + dense J": per_call(lambda: system.forces_and_jacobian(q, xi, 0.06)),
                 "trial history": per_call(lambda: system.history_step(q, q, xi)),
                 "linear solve (31 x 31 bordered)": per_call(lambda: np.linalg.solve(J, F)),
                 "eigenvalues (30 x 30, LAPACK dgeev)": per_call(lambda: np.linalg.eigvals(J)),
                 "eigenvalues and both vectors (dgeev)": per_call(lambda: eigensystem(J, True))}
    for what, tp in parts.items():
        print(f"    {what:<40}{tp * 1e6:8.1f} us")
    for matrix in ("J", "M^-1 J"):
        for mode in ("fast", "exhaustive"):
            params = SweepParams(detection=DetectionParams(mode=mode))
            with measured() as work:
                t, branch = timed(lambda: sweep(system, 0.0, 0.12, matrix, params), args.repeat)
            print(f"paper diagram 0..0.12, {matrix:<6} {mode:<10}: {t:.2f} s warm, {len(branch)} "
                  f"points, {len(branch.collisions)} collisions, "
                  f"{work.spectra / args.repeat / len(branch):.1f} spectra per point  (target <= 0.3 s)")


if __name__ == "__main__":
    main()
