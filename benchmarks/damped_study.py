"""What one cell of the damped study costs, with and without collision location, and what the
default study would take (docs/packings-study.md#cost).

A cell (studies/packing_maps.packing_cell with drags): prepare N disks (seed), shear to GAMMA
passing every plastic event with full spectra, every collision located, then the damped study
at the drags (damped Hopf points, the precursor table, the strain statistics). Without
collision location: the same shear with spectra "sample:DGAMMA" (every DGAMMA of strain the
equilibrium and its dense spectrum, no collision and no onset located: per-strain statistics
only, models/packing/sampled.py), and the strain statistics at the drags from the samples.
Printed per run: the seconds of the whole cell and of its parts, states, collisions, plastic
events. Then the default study's cost from the full cells' rate, the sum over its grid of
time(N) * strain (time per unit strain fitted as a power of N through the cells measured),
and on K workers that sum / K (the cells are independent; a worker runs one at a time).

Run: python benchmarks/damped_study.py [FULL_N,...] [SAMPLED_N,...] [GAMMA] [SEED] [DGAMMA]
     (default: 64,128 64,256 0.02 1 0.0005: full spectra for 64 and 128 disks, sampled for 64
     and 256; an empty list runs none)
"""
from __future__ import annotations

import sys
import time

import numpy as np

from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, shear
from diskfriction.models.packing.strain_statistics import strain_statistics
from diskfriction.scenes.packing import PackingScene
from diskfriction.studies.packing_maps import damped_parts

DRAGS = (0.0, 0.003, 0.01, 0.03, 0.1, 0.3)
"""The drags of the default study [omega_0]."""

DEFAULT_STUDY = {"N": (64, 128, 256, 512), "seeds": 20, "mu": (0.0, 0.3, 1.0, 10.0, 1e6),
                 "P": (0.01, 0.1), "gamma": 0.02}
"""The default study (docs/packings-study.md): 20 seeds in every (N, mu, P), mu = 0 the
frictionless and mu = 1e6 the no-slip baseline, each sheared to gamma = 0.02."""


def full_cell(N: int, seed: int, gamma: float) -> dict:
    """One cell with full spectra: seconds of the preparation, the shear and the damped study."""
    scene = PackingScene(N=N, seed=seed, gamma_range=(0.0, gamma), spectra="full")
    start = time.perf_counter()
    packing = prepare_scene(scene)
    prepared = time.perf_counter()
    branch = shear(scene, packing, ShearParams(workers=0), plastic_events=1000)
    sheared = time.perf_counter()
    parts = damped_parts(scene, packing, branch, DRAGS)
    done = time.perf_counter()
    return {"prepare": prepared - start, "shear": sheared - prepared, "damped": done - sheared,
            "total": done - start, "states": len(branch), "collisions": len(branch.collisions),
            "plastic": len(branch.plastic), "gamma": float(branch.gamma[-1]),
            "onsets": [s["onsets"] for s in parts["damped"]]}


def sampled_cell(N: int, seed: int, gamma: float, every: float) -> dict:
    """The same cell with spectra sample:every and the strain statistics from its samples."""
    scene = PackingScene(N=N, seed=seed, gamma_range=(0.0, gamma), spectra=f"sample:{every!r}")
    start = time.perf_counter()
    packing = prepare_scene(scene)
    prepared = time.perf_counter()
    branch = shear(scene, packing, ShearParams(workers=0), plastic_events=1000)
    sheared = time.perf_counter()
    statistics = strain_statistics(branch, tuple(d * scene.omega_0 for d in DRAGS), sampled=True)
    done = time.perf_counter()
    return {"prepare": prepared - start, "shear": sheared - prepared, "damped": done - sheared,
            "total": done - start, "states": len(branch), "samples": len(branch.sample),
            "plastic": len(branch.plastic), "gamma": float(branch.gamma[-1]),
            "unstable": [round(f, 3) for f in statistics.unstable_fraction]}


def study_seconds(rate: dict[int, float], study: dict) -> float:
    """The default study's cell seconds summed: time per unit strain rate[N] (measured, or the
    power law through the measured N beyond them) times the strain, over every cell."""
    Ns = np.array(sorted(rate))
    if Ns.size > 1:
        slope, intercept = np.polyfit(np.log(Ns), np.log([rate[n] for n in Ns]), 1)
    else:
        slope, intercept = 2.0, np.log(rate[int(Ns[0])] / Ns[0] ** 2.0)

    def per_strain(N: int) -> float:
        return rate[N] if N in rate else float(np.exp(intercept) * N ** slope)

    cells = study["seeds"] * len(study["mu"]) * len(study["P"])
    return sum(cells * per_strain(N) * study["gamma"] for N in study["N"])


def main(full_ns, sampled_ns, gamma: float, seed: int, every: float) -> None:
    print(f"one cell: seed {seed}, gamma 0 -> {gamma:g}, drags {', '.join(map(str, DRAGS))} omega_0")
    rate = {}
    for N in full_ns:
        full = full_cell(N, seed, gamma)
        rate[N] = full["total"] / full["gamma"]
        print(f"N = {N:4}  full spectra, every collision located: {full['total']:8.1f} s (prepare "
              f"{full['prepare']:.1f}, shear {full['shear']:.1f}, damped study {full['damped']:.1f}); "
              f"{full['states']} states, {full['collisions']} collisions, {full['plastic']} plastic "
              f"events, onsets per drag {full['onsets']}", flush=True)
    for N in sampled_ns:
        sampled = sampled_cell(N, seed, gamma, every)
        print(f"N = {N:4}  sample:{every:g}, no collision located:  {sampled['total']:8.1f} s (prepare "
              f"{sampled['prepare']:.1f}, shear {sampled['shear']:.1f}, statistics {sampled['damped']:.2f}); "
              f"{sampled['samples']} samples, {sampled['plastic']} plastic events, damped-unstable "
              f"strain per drag {sampled['unstable']}", flush=True)
    if not rate:
        return
    total = study_seconds(rate, DEFAULT_STUDY)
    cells = DEFAULT_STUDY["seeds"] * len(DEFAULT_STUDY["mu"]) * len(DEFAULT_STUDY["P"]) * len(DEFAULT_STUDY["N"])
    print(f"the default study ({cells} cells: N {DEFAULT_STUDY['N']}, {DEFAULT_STUDY['seeds']} seeds, "
          f"mu {DEFAULT_STUDY['mu']}, P {DEFAULT_STUDY['P']}, gamma 0 -> {DEFAULT_STUDY['gamma']:g}) "
          f"with full spectra: {total / 3600:.0f} core-hours, from these cells' seconds per unit strain "
          f"(a power of N beyond them); on K workers about that / K hours "
          f"({', '.join(f'K = {k}: {total / 3600 / k:.0f} h' for k in (2, 16, 64, 256))})")


if __name__ == "__main__":
    args = sys.argv[1:]
    sizes = lambda i, default: (tuple(int(n) for n in args[i].split(",") if n)  # noqa: E731
                                if len(args) > i else default)
    main(sizes(0, (64, 128)), sizes(1, (64, 256)), float(args[2]) if len(args) > 2 else 0.02,
         int(args[3]) if len(args) > 3 else 1, float(args[4]) if len(args) > 4 else 0.0005)
