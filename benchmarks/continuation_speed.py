"""Continuation benchmark (issue #3): cost per accepted point, the whole paper diagram, N = 100.

Run: python benchmarks/continuation_speed.py [--repeat 5]. Medians over repeats, warm (kernels compiled).
"""
from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from diskfriction.continuation.collisions import DetectionParams
from diskfriction.continuation.sweep import SweepParams, sweep
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
    system = System.from_scene(Scene())
    sweep(system, 0.0, 0.12)  # warm up
    off = SweepParams(detection=DetectionParams(enabled=False))
    t, branch = timed(lambda: sweep(system, 0.0, 0.12, "J", off), args.repeat)
    print(f"N = 10, detection off: {len(branch)} points in {t * 1e3:.0f} ms = "
          f"{t / len(branch) * 1e3:.2f} ms per accepted point (Newton + full spectrum + history)"
          f"  (target <= 0.1 ms)")
    q, xi = branch.q[len(branch) // 2], branch.xi[len(branch) // 2]
    F, J = system.forces_and_jacobian(q, xi, 0.06)
    parts = {"F + dense J": per_call(lambda: system.forces_and_jacobian(q, xi, 0.06)),
             "trial history": per_call(lambda: system.history_step(q, q, xi)),
             "linear solve (31 x 31 bordered)": per_call(lambda: np.linalg.solve(J, F)),
             "eigenvalues (30 x 30, LAPACK dgeev)": per_call(lambda: np.linalg.eigvals(J))}
    for what, tp in parts.items():
        print(f"    {what:<38}{tp * 1e6:8.1f} us")
    for matrix in ("J", "M^-1 J"):
        t, branch = timed(lambda: sweep(system, 0.0, 0.12, matrix), args.repeat)
        print(f"paper diagram 0..0.12, {matrix:<6}: {t:.2f} s warm, {len(branch)} points, "
              f"{len(branch.collisions)} collisions located  (target <= 0.5 s)")
    # eps = 0 cannot be continued at N = 100: disks the load has not reached keep their pairs at
    # delta = 0 and roll freely, so J is singular; a slight pre-compression closes every pair.
    big = System.from_scene(Scene(N=100, eps=1e-4))
    t, branch = timed(lambda: sweep(big, 0.0, 0.12), 1)
    print(f"N = 100 (eps = 1e-4), 0..0.12, J: {t:.1f} s, {len(branch)} points, "
          f"{len(branch.collisions)} collisions, status {branch.status}")


if __name__ == "__main__":
    main()
