"""Quasistatic shear of packings: for each N and seed, the seconds to prepare and to
shear with friction from gamma = 0 to GAMMA_END (or to where the branch ends), the accepted
points, the contact events, the collisions located, how often an accepted state has complex
pairs and how many, the largest force residual, how the branch ended (p_end; fold: the
saddle-node in gamma, the plastic event of quasistatic shear; ds_min; commit) and the smallest
real part of the tracked spectrum at the end over its value at the start (a fold drives it to
0). One line per run, measured in this run; the collision scans run on scan workers as in
`diskfriction bifurcate` (two on a machine with two cores or more, from n = PARALLEL_FROM), or
on --workers K (0: inline, every step's scan in this process, bit-for-bit reproducible).

Plastic events (folds) are passed up to PLASTIC_EVENTS times (models/packing/plastic.py); the column
"plastic" counts them and "ended" says how the last segment ended.

With a window LO:HI (raw units of M^-1 J) only Re lambda in [LO, HI] is tracked, by sparse
shift-invert (bifurcate --window): "collisions" and "complex" then count the window's, and
"widened" how often the window crowded and was sized anew (models/packing/shear.py).

Memory: "MB" is this process's peak resident size so far and "worker MB" the largest of its
scan workers' (both from getrusage, so a later run's figure is never below an earlier one's:
run one N per invocation to measure its memory; 1024 disks: docs/notes/packings-speed.md, "1024
disks: out of reach on two cores").

Run: python benchmarks/shear_packing.py [--workers K] [--progress S] [N:SEEDS:GAMMA_END[:LO:HI] ...]
     (default: 32:3:0.01 64:3:0.01)
"""
from __future__ import annotations

import argparse
import collections
import resource
import sys
import time

import numpy as np

from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, shear
from diskfriction.scenes.packing import PackingScene

PLASTIC_EVENTS = 1000


def smallest(eigenvalues: np.ndarray) -> float:
    """The smallest real part of the tracked (nonzero; with a window, computed) eigenvalues."""
    return float(np.nanmin(eigenvalues[eigenvalues != 0].real))


def kinds(branch) -> str:
    """How the segments were lost, e.g. "fold 10, ds_min 57, commit 1"."""
    counts = collections.Counter(event.kind for event in branch.plastic)
    return ", ".join(f"{kind} {n}" for kind, n in counts.most_common()) or "-"


def reporter(every: float, start: float):
    """A progress callback that prints the strain reached and the seconds since `start` to
    stderr, at most once every `every` seconds; None for every = 0 (no progress)."""
    if every <= 0:
        return None
    last = [start]

    def progress(gamma: float) -> None:
        now = time.perf_counter()
        if now - last[0] >= every:
            last[0] = now
            print(f"  gamma = {gamma:.4e} at {now - start:.0f} s", file=sys.stderr, flush=True)
    return progress


def run(N: int, seed: int, gamma_end: float, window=None, workers=None, every: float = 0.0) -> str:
    scene = PackingScene(N=N, seed=seed, gamma_range=(0.0, gamma_end), spectra="full")
    start = time.perf_counter()
    packing = prepare_scene(scene)
    prepared = time.perf_counter() - start
    branch = shear(scene, packing, ShearParams(workers=workers), reporter(every, start),
                   plastic_events=PLASTIC_EVENTS, window=window)
    sheared = time.perf_counter() - start - prepared
    fell = smallest(branch.eigenvalues[-1]) / smallest(branch.eigenvalues[0])
    end = branch.status.code.value
    return (f"{N:>5} {seed:>4} {prepared:>7.1f} {sheared:>7.1f} {branch.gamma[-1]:>10.3e} "
            f"{end:>12} {len(branch):>6} {branch.events:>6} {len(branch.collisions):>10} "
            f"{np.mean(branch.n_complex > 0):>8.2f} {np.mean(branch.n_complex):>7.1f} "
            f"{branch.residual.max():>9.1e} {int(branch.loose[0]):>5} {fell:>9.1e} "
            f"{len(branch.plastic):>7} {branch.stress[-1, 2]:>9.4f} {branch.widenings:>7} "
            f"{peak_mb(resource.RUSAGE_SELF):>6.0f} {peak_mb(resource.RUSAGE_CHILDREN):>9.0f}  {kinds(branch)}")


def peak_mb(who: int) -> float:
    """The peak resident size in MB of this process (RUSAGE_SELF) or of the largest of its
    finished children (RUSAGE_CHILDREN: the scan workers, ended with their shear)."""
    return resource.getrusage(who).ru_maxrss / 1024


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("runs", nargs="*", default=["32:3:0.01", "64:3:0.01"])
    ap.add_argument("--workers", type=int, default=None, help="scan workers (default: as bifurcate)")
    ap.add_argument("--progress", type=float, default=0.0, metavar="S",
                    help="print the strain reached to stderr at most every S seconds (default: never)")
    args = ap.parse_args()
    if args.workers is not None and args.workers < 0:
        ap.error(f"--workers: must be >= 0 (got {args.workers})")
    if not args.progress >= 0:
        ap.error(f"--progress: must be >= 0 seconds (got {args.progress})")
    runs = [parsed(spec, ap) for spec in args.runs]
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load average {open('/proc/loadavg').read().split()[0]}, "
          f"workers {'automatic' if args.workers is None else args.workers}")
    print(f"{'N':>5} {'seed':>4} {'prep s':>7} {'shear s':>7} {'gamma end':>10} {'ended':>12} "
          f"{'points':>6} {'events':>6} {'collisions':>10} {'complex':>8} {'pairs':>7} "
          f"{'max |F|':>9} {'loose':>5} {'min/start':>9} {'plastic':>7} {'sigma_xy':>9} "
          f"{'widened':>7} {'MB':>6} {'worker MB':>9}  kinds")
    for N, seeds, gamma_end, window in runs:
        for seed in range(1, seeds + 1):
            print(run(N, seed, gamma_end, window, args.workers, args.progress), flush=True)


def parsed(spec: str, ap: argparse.ArgumentParser) -> tuple:
    """(N, seeds, gamma_end, window or None) of N:SEEDS:GAMMA_END[:LO:HI]; a one-line usage
    error (exit 2) for anything else."""
    parts = spec.split(":")
    try:
        if len(parts) not in (3, 5):
            raise ValueError
        N, seeds, gamma_end = int(parts[0]), int(parts[1]), float(parts[2])
        window = (float(parts[3]), float(parts[4])) if len(parts) == 5 else None
    except ValueError:
        ap.error(f"run {spec!r}: expected N:SEEDS:GAMMA_END[:LO:HI], e.g. 256:1:0.002:-3:8")
    if N < 2 or seeds < 1 or not gamma_end > 0 or (window is not None and not window[0] < window[1]):
        ap.error(f"run {spec!r}: needs N >= 2, SEEDS >= 1, GAMMA_END > 0 and LO < HI")
    return N, seeds, gamma_end, window


if __name__ == "__main__":
    main()
