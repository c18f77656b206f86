"""How well a run's energy budget closes against dt, and where runs stop being resolved.

Run: python benchmarks/budget_closure.py [--t-end 1000] [--fx 0.03,0.09]

For each load F_x of the paper's scene (the branch point, perturbed along the largest complex
pair of M^-1 J with amplitude 1e-10, as `diskfriction simulate` does) and each dt given as a
fraction of the stability limit 2 / omega_max of the start, one run to t_end: the budget error
relative to the energy exchanged (dynamics/trajectory.py: budget_relative), whether the run is
accurate (<= BUDGET_BOUND), whether it slid, its max M and wall time. Fractions at or beyond 1
are refused by plan_run (UnstableStep); those between the default 0.05 and 1 show where the
nonlinear run goes unstable although the start state's spectrum is resolved.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from diskfriction.models.chain.equilibrium import equilibrium_at
from diskfriction.dynamics.simulate import UnstableStep, simulate, stability_limit, summarize
from diskfriction.dynamics.start import Perturbation, spectrum
from diskfriction.dynamics.trajectory import BUDGET_BOUND
from diskfriction.scenes import Scene
from diskfriction.symbolic import System

FRACTIONS = (0.0125, 0.025, 0.05, 0.1, 0.2, 0.4, 0.6, 0.8, 0.95, 1.05)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--t-end", type=float, default=1000.0)
    parser.add_argument("--fx", default="0.03,0.09")
    args = parser.parse_args()
    system = System.from_scene(Scene())
    print(f"paper scene, t_end = {args.t_end:g} raw, eigenvector start 1e-10; bound {BUDGET_BOUND:g}")
    print(f"{'F_x':>6} {'dt/limit':>8} {'dt':>9} {'relative':>9} {'accurate':>8} {'slid':>5} "
          f"{'max M':>9} {'seconds':>7}")
    for F_x in (float(v) for v in args.fx.split(",")):
        eq = equilibrium_at(system, F_x)
        limit = stability_limit(spectrum(system, eq.q, eq.xi))
        simulate(system, eq.q, eq.xi, F_x, 1e-3)  # compiled stepper loaded
        for fraction in FRACTIONS:
            t0 = time.perf_counter()
            try:
                traj = simulate(system, eq.q, eq.xi, F_x, args.t_end, dt=fraction * limit,
                                perturbation=Perturbation("eigenvector", 1e-10))
            except UnstableStep:
                print(f"{F_x:6.3f} {fraction:8.4f} {fraction * limit:9.3g}  refused: not below "
                      f"the stability limit")
                continue
            seconds = time.perf_counter() - t0
            s = summarize(traj)
            rel = np.inf if s["budget_relative"] is None else s["budget_relative"]
            M = np.inf if s["M_max"] is None else s["M_max"]
            print(f"{F_x:6.3f} {fraction:8.4f} {traj.dt:9.3g} {rel:9.2g} {str(s['accurate']):>8} "
                  f"{str(s['slid']):>5} {M:9.2g} {seconds:7.2f}")


if __name__ == "__main__":
    main()
