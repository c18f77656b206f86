"""How often a sheared packing's equilibria carry complex pairs, and how fast they grow, against
the friction coefficient mu and the pressure P (docs/packings.md#what-the-tool-finds).

For each (mu, P) and seed: prepare N disks at P, shear with friction from gamma = 0 to
GAMMA_END (P / 0.1)^(2/3) passing every plastic event (every eigenvalue tracked, dense spectra):
the strain is scaled with the typical overlap, delta ~ (P R / k_n)^(2/3) for Hertz contacts, so
that every pressure is sheared by the same multiple of its overlaps. Printed:
- complex: the fraction of the strain with at least one complex pair of M^-1 J, per unit strain
  (models/packing/strain_statistics.py) and, after "/", per accepted state (the states crowd
  near events, where pairs are born);
- pairs: the mean number of complex pairs over the strain;
- sigma/omega: the fastest pair's growth rate sigma = |Im sqrt(lambda)| over the typical
  frequency omega = sqrt(median lambda at gamma = 0): its median over the strain with a pair
  (and over the states with one, after "/"), and its largest;
- coll/1e-3: collisions (births and deaths) per 1e-3 of strain; plastic/1e-3: plastic events
  (branch lost and relaxed) per 1e-3 of strain, and the largest relative drop of sigma_xy;
- seconds of the whole run. Measured in this run, scans inline.

Run: python benchmarks/packing_physics.py [N] [GAMMA_END] [SEEDS] [MU,...] [P,...]
     (default: 32 0.005 3 0.3,1,10 0.01,0.1)
"""
from __future__ import annotations

import sys
import time

import numpy as np

from diskfriction.models.packing.dynamics import fastest_pair
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, shear
from diskfriction.models.packing.strain_statistics import strain_statistics
from diskfriction.scenes.packing import PackingScene

MUS = (0.3, 1.0, 10.0)
PRESSURES = (0.01, 0.1)


def run(N: int, mu: float, pressure: float, seed: int, gamma_end: float) -> str:
    start = time.perf_counter()
    gamma_end *= (pressure / 0.1) ** (2.0 / 3.0)
    scene = PackingScene(N=N, seed=seed, mu=mu, pressure=pressure, gamma_range=(0.0, gamma_end),
                         spectra="full")
    branch = shear(scene, prepare_scene(scene), ShearParams(workers=0), plastic_events=1000)
    lam0 = branch.eigenvalues[0]
    omega = float(np.sqrt(np.median(lam0[lam0 != 0].real)))
    sigma = np.array([fastest_pair(e)[1] for e in branch.eigenvalues]) / omega
    stats = strain_statistics(branch)
    per = 1e-3 / max(branch.gamma[-1], 1e-300)
    drops = [(e.stress_before - e.stress_after) / e.stress_before for e in branch.plastic]
    return (f"{mu:>5g} {pressure:>6g} {seed:>4} {branch.gamma[-1]:>9.2e} "
            f"{stats.complex_fraction:>5.2f}/{np.mean(branch.n_complex > 0):.2f} {stats.pairs_mean:>6.1f} "
            f"{(stats.growth_median[0] or 0.0) / omega:>9.2e}/{np.median(sigma[sigma > 0]):.2e} "
            f"{sigma.max():>9.2e} {len(branch.collisions) * per:>11.0f} "
            f"{len(branch.plastic) * per:>11.1f} {max(drops, default=0.0):>9.3f} "
            f"{time.perf_counter() - start:>7.1f}")


def main(N: int, gamma_end: float, seeds: int, mus=MUS, pressures=PRESSURES) -> None:
    print(f"N = {N}, gamma 0 -> {gamma_end:g} (P / 0.1)^(2/3), seeds 1..{seeds}")
    print(f"{'mu':>5} {'P':>6} {'seed':>4} {'gamma end':>9} {'complex':>10} {'pairs':>6} "
          f"{'sigma/omega':>18} {'max':>9} {'coll/1e-3':>11} {'plastic/1e-3':>11} "
          f"{'max drop':>9} {'s':>7}")
    for pressure in pressures:
        for mu in mus:
            for seed in range(1, seeds + 1):
                print(run(N, mu, pressure, seed, gamma_end), flush=True)


if __name__ == "__main__":
    args = sys.argv[1:]
    numbers = lambda i, default: (tuple(float(v) for v in args[i].split(","))  # noqa: E731
                                  if len(args) > i else default)
    main(int(args[0]) if args else 32, float(args[1]) if len(args) > 1 else 0.005,
         int(args[2]) if len(args) > 2 else 3, numbers(3, MUS), numbers(4, PRESSURES))
