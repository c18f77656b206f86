"""Packing preparation benchmark (issue 25): seconds to prepare a packing at a target pressure
with the O(N^2) numpy reference force (tests/packing_reference.py), the FIRE steps, relaxations
and force calls it took.

Run: python benchmarks/prepare_packing.py [--sizes 64 256] [--pressure 1e-2] [--f-tol 1e-8]
[--seeds 3]. One line per N and seed, measured in this run. N = 1024 is left out by default:
one reference force call takes ~50 ms there (printed) and N = 256 took 1.1 - 2.5 10^4 calls,
so it would take a quarter of an hour or more; the generated kernels' time per call replaces
the reference's.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from packing_reference import K_N, hertz_pair_forces  # noqa: E402

from diskfriction.packings.prepare import bidisperse_radii, box_side, prepare  # noqa: E402

R = 0.5


def seconds_per_call(N: int, repeat: int = 20) -> float:
    """Median seconds of one reference force call at phi = 0.84, random positions."""
    rng = np.random.default_rng(0)
    radii = bidisperse_radii(N, R, rng=rng)
    L = box_side(radii, 0.84)
    positions = rng.random((N, 2)) * L
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        hertz_pair_forces(positions, radii, L)
        times.append(time.perf_counter() - start)
    return float(np.median(times))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--sizes", type=int, nargs="+", default=[64, 256])
    ap.add_argument("--pressure", type=float, default=1e-2)
    ap.add_argument("--f-tol", type=float, default=1e-8)
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args()
    print(f"P = {args.pressure:g}, f_tol = {args.f_tol:g}, k_n = {K_N:g}, R = {R}, "
          f"bidisperse 1.4 50:50")
    print(f"{'N':>6}{'seed':>5}{'seconds':>9}{'FIRE steps':>12}{'relaxations':>13}"
          f"{'force calls':>13}{'ms/call':>9}{'phi':>8}{'rattlers':>10}")
    for N in args.sizes:
        for seed in range(args.seeds):
            calls = 0

            def counted(positions, radii, L):
                nonlocal calls
                calls += 1
                return hertz_pair_forces(positions, radii, L)

            start = time.perf_counter()
            p = prepare(N, seed, R, K_N, pressure=args.pressure, pair_forces=counted,
                        f_tol=args.f_tol)
            seconds = time.perf_counter() - start
            print(f"{N:>6}{seed:>5}{seconds:>9.2f}{p.steps:>12}{p.relaxations:>13}{calls:>13}"
                  f"{seconds / calls * 1e3:>9.3f}{p.phi:>8.4f}{int(p.rattlers.sum()):>10}",
                  flush=True)
    if 1024 not in args.sizes:
        ms = seconds_per_call(1024) * 1e3
        print(f"N = 1024 left out: one reference force call takes {ms:.0f} ms (--sizes 1024)")
    print(f"machine: {os.cpu_count()} cores; numpy {np.__version__}")


if __name__ == "__main__":
    main()
