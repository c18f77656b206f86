"""Accuracy of the generated Jacobian: worst row-relative error against the 50-digit
finite-difference reference, per effect combination, and the cost of one F + J against one
double-precision central-difference Jacobian (2n force evaluations).

Run: python benchmarks/jacobian_accuracy.py [--states 50]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from jacobian_check import all_effects, effects_id, worst_errors  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--states", type=int, default=50)
    args = ap.parse_args()
    print(f"{'effects':<36}{'contact':>10}{'assembled':>11}{'delta~1e-10':>13}  ({args.states} states, N = 3)")
    overall = 0.0
    for effects in all_effects():
        t0 = time.perf_counter()
        w = worst_errors(effects, args.states)
        overall = max(overall, w["contact"], w["assembled"])
        print(f"{effects_id(effects):<36}{w['contact']:>10.2e}{w['assembled']:>11.2e}{w['tiny']:>13.2e}"
              f"  [{time.perf_counter() - t0:.1f} s]")
    print(f"worst over all: {overall:.2e} (tolerance 1e-6)")
    _cost()


def _cost() -> None:
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    s = System.from_scene(Scene())
    q, xi = s.rest_state()
    q[:s.N] += np.random.default_rng(0).normal(0, 1e-4, s.N)
    s.forces_and_jacobian(q, xi, 0.01)
    reps = 2000
    t0 = time.perf_counter()
    for _ in range(reps):
        s.forces_and_jacobian(q, xi, 0.01)
    exact = (time.perf_counter() - t0) / reps
    t0 = time.perf_counter()
    for _ in range(reps // 10):
        h = 1e-7
        for c in range(s.ndof):
            e = np.zeros(s.ndof)
            e[c] = h
            s.forces(q + e, xi, 0.01) - s.forces(q - e, xi, 0.01)
    fd = (time.perf_counter() - t0) / (reps // 10)
    print(f"N = 10: generated F + dense J {exact * 1e6:.1f} us (Python call); "
          f"central-difference J {fd * 1e6:.0f} us ({fd / exact:.0f}x slower, and inexact)")


if __name__ == "__main__":
    main()
