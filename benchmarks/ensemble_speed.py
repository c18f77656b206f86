"""Ensemble benchmark: 25 realizations x 3 F_x on this machine's cores via dask.

Run: python benchmarks/ensemble_speed.py [--t-end 600] [--realizations 25]
t_end = 600 raw = 26 800 tau covers what the paper's figures need: the breach and sliding
fronts (Fig. 5) complete by t ~ 250 raw at F_x = 0.083..0.090, Fig. 4 shows t ~ 17 500 tau
(= 391 raw), and V_cm (Fig. 7) is fitted over the second half of the run, deep in sliding.
Prints wall time of a cold ensemble (fresh directory, cluster start included) and the results.
"""
from __future__ import annotations

import argparse
import tempfile
import time

from diskfriction.studies.ensemble import run_ensemble
from diskfriction.reports.units import PaperUnits
from diskfriction.scenes import Scene


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--t-end", type=float, default=600.0)
    ap.add_argument("--realizations", type=int, default=25)
    args = ap.parse_args()
    scene = Scene()
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        ens = run_ensemble(scene, [0.083, 0.087, 0.090], args.realizations, args.t_end, out)
        wall = time.perf_counter() - t0
    n = sum(map(len, ens.summaries.values()))
    print(f"{n} realizations, t_end = {args.t_end:g} raw = {args.t_end / scene.tau:.0f} tau: "
          f"{wall:.1f} s wall on a local dask cluster (target <= 60 s)")
    v = PaperUnits.of(scene).velocity
    paper = lambda e: e.value / v
    for F, e in ens.V1.items():
        print(f"  F_x = {F}: V1 = {paper(e):.4f} +- {e.error / v:.4f} "
              f"2R/tau (n = {e.n}), slid {sum(s['slid'] for s in ens.summaries[F])}")
    print(f"  V2 = {paper(ens.V2):.4f} +- {ens.V2.error / v:.4f} 2R/tau "
          f"(n = {ens.V2.n})")
    if ens.V_cm_fit:
        a, b = ens.V_cm_fit
        print(f"  V_cm = {paper(a):.3g} (+- {a.error / v:.2g}) + "
              f"{paper(b):.3g} (+- {b.error / v:.2g}) F_x  [2R/tau]")


if __name__ == "__main__":
    main()
