"""Kernel benchmark: cold derive + codegen + compile, cached start, F + J cost.

Run: python benchmarks/kernels.py [--repeat 7]. Prints medians over repeats, measured in this run.
Cold and cached starts run in fresh processes against a fresh cache directory.
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

STARTUP = """
import time; t0 = time.perf_counter()
from diskfriction.scenes import Scene
from diskfriction.symbolic import System
s = System.from_scene(Scene())
q, xi = s.rest_state()
F, J = s.forces_and_jacobian(q, xi, 0.01)
print(time.perf_counter() - t0)
"""


def start_times(repeat: int) -> tuple[list[float], list[float], list[float]]:
    """(cold in-process, cached in-process, cached whole process) seconds per fresh cache."""
    cold, cached, process = [], [], []
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "DISKFRICTION_CACHE": cache}
            run = lambda: subprocess.run([sys.executable, "-c", STARTUP], env=env, check=True,
                                         capture_output=True, text=True).stdout
            cold.append(float(run()))
            t0 = time.perf_counter()
            cached.append(float(run()))
            process.append(time.perf_counter() - t0)
    return cold, cached, process


def per_call(fn, calls: int, repeat: int) -> float:
    """Median over `repeat` batches of the mean time of one call [s]."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(calls):
            fn()
        times.append((time.perf_counter() - t0) / calls)
    return statistics.median(times)


def evaluation_times(N: int, repeat: int) -> dict[str, float]:
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    s = System.from_scene(Scene(N=N))
    k, p = s.kernels, s.params
    q, xi = s.rest_state()
    rng = np.random.default_rng(0)
    q[:N] += rng.normal(0, 1e-4, N)  # pairs and substrate active, histories nonzero
    xi[:] = rng.uniform(-1e-4, 1e-4, 2 * N)
    n = s.ndof
    F, vals = np.empty(n), np.empty(s.rows.size)
    calls = max(10, 200_000 // N)
    out = {"F + J values (sparse)": per_call(lambda: k.evaluate(q, xi, 0.01, p, F, vals), calls, repeat),
           "F only": per_call(lambda: k.forces(q, xi, 0.01, p, F), calls, repeat)}
    if N <= 100:
        J = np.empty((n, n))
        out["F + dense J"] = per_call(
            lambda: k.evaluate_dense(q, xi, 0.01, p, F, J, vals, s.rows, s.cols), calls, repeat)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    cold, cached, process = start_times(max(3, args.repeat // 2))
    print(f"cold derive + codegen + compile + first J (in-process): median {statistics.median(cold):.2f} s"
          f"  (target <= 15 s)")
    print(f"cached start to first J (in-process, incl. imports):    median {statistics.median(cached):.3f} s"
          f"  (target <= 1 s)")
    print(f"cached start, whole process incl. interpreter:          median {statistics.median(process):.3f} s")
    print(f"\n{'N':>6}  {'what':<24}{'per call':>12}{'per disk':>12}")
    for N in (10, 100, 1000):
        for what, t in evaluation_times(N, args.repeat).items():
            print(f"{N:>6}  {what:<24}{t * 1e6:>10.2f} us{t * 1e9 / N:>10.1f} ns")
    print("target: F + J for N = 10 <= 5 us")


if __name__ == "__main__":
    main()
