"""Dynamics benchmark: microseconds per disk-step of the velocity-Verlet loop.

Run: python benchmarks/dynamics_speed.py [--repeat 7]. Prints medians over repeats, measured in this run.

A step is everything the integrator does per step: two kicks, the drift, the midpoint history
increment of every contact, the history rule (reset, first contact, Coulomb cap), forces and the
tangential force of every contact, the tangential work and the breach bookkeeping (frames are
recorded every 1000 steps, as in a long run). States:
  ring     N disks, pre-compressed (eps = 1e-3) so every contact is closed, kicked with random
           velocities of 1e-3 at F_x = 0.01: every contact active and sticking, histories moving;
  paper    the paper's scene (N = 10) at F_x = 0.083 from its branch point along the growing
           pair, sliding: caps, openings and closings happen (the case the paper's runs are).
"""
from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time

import numpy as np


STARTUP = """
import time; t0 = time.perf_counter()
import numpy as np
from diskfriction.scenes import Scene
from diskfriction.symbolic import System
from diskfriction.dynamics import Stepper
s = System.from_scene(Scene()); q, xi = s.rest_state()
Stepper(s, q, np.zeros_like(q), xi, 0.0, 1e-3, 1, 4).advance(1)
print(time.perf_counter() - t0)
"""


def per_disk_step(stepper, N: int, repeat: int, target_seconds: float = 0.2) -> float:
    """Median over `repeat` batches of the time of one step divided by N [s]."""
    stepper.advance(10)  # compiled or loaded, caches warm
    t0 = time.perf_counter()
    stepper.advance(100)
    steps = max(100, int(target_seconds / max(time.perf_counter() - t0, 1e-9) * 100))
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        stepper.advance(steps)
        times.append((time.perf_counter() - t0) / steps / N)
    return statistics.median(times)


def frames_for(N: int, repeat: int, extra_steps: int = 0) -> int:
    """Frame buffer for every step the timing can take (at >= 10 ns per disk-step) / 1000."""
    return 2 + (extra_steps + int((repeat + 2) * 0.3 / (10e-9 * N))) // 1000


def ring_stepper(N: int, repeat: int):
    from diskfriction.dynamics import Perturbation, Stepper
    from diskfriction.dynamics.start import perturb
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    s = System.from_scene(Scene(N=N, eps=1e-3))
    q, v, xi = perturb(s, *s.rest_state(), Perturbation("random-velocity", 1e-3, seed=0))
    return Stepper(s, q, v, xi, 0.01, 1e-3, 1000, frames_for(N, repeat))


def paper_stepper(repeat: int):
    from diskfriction.models.chain.sweep import sweep
    from diskfriction.dynamics import Perturbation, Stepper, choose_dt, spectrum
    from diskfriction.dynamics.start import perturb
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    s = System.from_scene(Scene())
    b = sweep(s, 0.0, 0.083)
    spec = spectrum(s, b.q[-1], b.xi[-1])
    q, v, xi = perturb(s, b.q[-1], b.xi[-1], Perturbation("eigenvector", 1e-10), spec)
    dt = choose_dt(spec)
    st = Stepper(s, q, v, xi, 0.083, dt, 1000, frames_for(10, repeat, int(200 / dt)))
    st.advance(int(200 / dt))  # past the instability: sliding
    return st


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    starts = [float(subprocess.run([sys.executable, "-c", STARTUP], env=dict(os.environ),
                                   check=True, capture_output=True, text=True).stdout)
              for _ in range(3)]
    print(f"cached start to first step (new process, after the interpreter): median "
          f"{statistics.median(starts):.2f} s")
    print(f"\n{'state':<8}{'N':>7}{'per disk-step':>16}{'per step':>14}   target")
    targets = {10: 0.03, 1000: 0.04}
    for N in (10, 100, 1000, 10000):
        t = per_disk_step(ring_stepper(N, args.repeat), N, args.repeat)
        target = f"<= {targets[N]} us" if N in targets else ""
        print(f"{'ring':<8}{N:>7}{t * 1e6:>13.4f} us{t * N * 1e6:>11.2f} us   {target}")
    t = per_disk_step(paper_stepper(args.repeat), 10, args.repeat)
    print(f"{'paper':<8}{10:>7}{t * 1e6:>13.4f} us{t * 10 * 1e6:>11.2f} us   (sliding, F_x = 0.083)")
    print(f"\nmachine: {os.cpu_count()} cores; single-threaded loop; numpy {np.__version__}")


if __name__ == "__main__":
    main()
