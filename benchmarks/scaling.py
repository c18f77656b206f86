"""Continuation cost against N: the paper's scene with N disks, F_x 0 -> 0.12, J.

For every N: wall time of the sweep (warm kernels), full spectra computed and partial ones (the
shift-inverts of split samples: continuation/spectra/nearest.py), LU factorizations and solves,
collisions located, peak memory of the sweep's process and of its largest scan worker
(continuation/detection/scans.py); eps = 1e-4 and eps = 0; the fitted exponent of time against N; the
fast detection against the exhaustive one (same collisions?) up to --exhaustive-up-to. The
fast detection scans on --workers processes (default: the sweep's own choice, 2 from N = 20 on
a machine with 2 cores); the exhaustive one always inline. Each run is a subprocess with a time budget: a run that would exceed
it is stopped when the budget is spent (at the end of the LAPACK or ARPACK call running then,
even inside a step), prints how far it got (the last accepted F_x) and is left out of the fit.

Run: python benchmarks/scaling.py [--N 10,20,40,100,200,400,1000] [--budget 600]
                                  [--exhaustive-up-to 100] [--eps 1e-4,0]
                                  [--window-N 1000 --window 0.0715:0.08] [--workers K]
                                  [--spectra cpu|gpu|auto[,...]] [--refine-from n|inf[,...]]
                                  [--progress SECONDS]
With --window-N, also a run tracking only that spectral window (bifurcate --window; lambda / k_n)
at each of those N. --spectra: where the dense spectra run (bifurcate --device; default auto);
with several, each fast run is repeated for each and compared with the first. --refine-from:
the n from which full spectra are refined from the previous sample's (continuation/spectra/refinement.py;
inf: never), several compared the same way; "refined (repaired) + declined" counts the full
spectra so refined, of them those certified only after their failing pairs were repaired by
shift-invert, and the refinements whose certificate failed (a dense spectrum was taken instead).
--progress S: each fast run prints the F_x it reached, with the seconds since its sweep started,
to stderr at most every S seconds (where a long sweep spends its time).
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time

import numpy as np

CHILD = r"""
import ctypes, json, resource, signal, sys, time
try:  # end with the benchmark: a signal that stops it leaves no sweep running (Linux prctl)
    ctypes.CDLL(None).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
except (OSError, AttributeError):
    pass
from diskfriction.continuation.detection.collisions import DetectionParams
from diskfriction.models.chain.equilibria import DiskEquilibria
from diskfriction.continuation.spectra import refinement
from diskfriction.continuation.linalg.solves import measured
from diskfriction.continuation.detection.scans import default_workers
from diskfriction.continuation.spectra.tracking import spectra_on
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.reports.units import PaperUnits
from diskfriction.scenes import Scene
from diskfriction.symbolic import System

N, eps, mode, budget = int(sys.argv[1]), float(sys.argv[2]), sys.argv[3], float(sys.argv[4])
scene = Scene(N=N, eps=eps)
unit = PaperUnits.of(scene).eigenvalue("J")
window = None if sys.argv[5] == "-" else tuple(float(w) * unit for w in sys.argv[5].split(":"))
workers = None if sys.argv[6] == "auto" else int(sys.argv[6])
DEVICE = spectra_on(sys.argv[7])  # held for the whole child process (a dropped one restores "auto")
DEVICE.__enter__()
refinement.REFINE_FROM = float(sys.argv[8])
every = float(sys.argv[9])  # seconds between progress lines on stderr (0: none)
system = System.from_scene(scene)
reached = {"F_x": 0.0}


class OutOfTime(Exception):
    pass


def progress(F_x):
    reached["F_x"] = F_x
    elapsed = time.perf_counter() - t0
    if every and (elapsed - reached.get("said", -every) >= every or F_x >= 0.12):
        reached["said"] = elapsed
        print(f"N = {N}: F_x = {F_x:.6f} at {elapsed:.1f} s", file=sys.stderr, flush=True)


def out_of_time(signum, frame):
    reached["out of time"] = True
    raise OutOfTime


params = SweepParams(detection=DetectionParams(mode=mode), workers=workers, window=window)
used = default_workers(DiskEquilibria(system, *system.rest_state(), 0.0), system.ndof, params.detection,
                       params.workers)
# compile and warm up on at most N = 100 (n = 300: the sparse path too), not on the big chain
sweep(System.from_scene(Scene(N=min(N, 100), eps=eps)), 0.0, 1e-3, "J",
      SweepParams(detection=DetectionParams(mode=mode)))
signal.signal(signal.SIGALRM, out_of_time)  # the budget also stops a run inside a step
signal.alarm(max(1, round(budget)))
t0 = time.perf_counter()
out = {"N": N, "eps": eps, "mode": mode + ("" if window is None else " " + sys.argv[5]), "workers": used}
with measured() as work:
    try:
        branch = sweep(system, 0.0, 0.12, "J", params, progress)
        out.update(done=branch.status.reached, points=len(branch),
                   collisions=[c.p for c in branch.collisions], free=int(branch.free[-1]))
    except Exception:  # OutOfTime, or what a compiled function makes of it (SystemError)
        if not reached.get("out of time"):
            raise
        out.update(done=False, points=None, collisions=None)
signal.alarm(0)
out.update(seconds=time.perf_counter() - t0, reached=reached["F_x"], spectra=work.spectra,
           partial=work.spectra_partial, refined=work.spectra_refined, repaired=work.refinements_repaired, declined=work.refinements_declined, factorizations=work.factorizations, solves=work.solves,
           peak_mb=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
           worker_mb=resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024)
print(json.dumps(out))
"""


def run(N: int, eps: float, mode: str, budget: float, window: str = "-", workers: str = "auto",
        spectra: str = "auto", refine_from: str = "default", progress: float = 0.0) -> dict:
    from diskfriction.continuation.spectra.refinement import REFINE_FROM

    refine = str(REFINE_FROM) if refine_from == "default" else refine_from
    proc = subprocess.run([sys.executable, "-c", CHILD, str(N), str(eps), mode, str(budget), window, workers,
                           spectra, refine, str(progress)], stdout=subprocess.PIPE,
                          stderr=None if progress else subprocess.PIPE, text=True)
    if proc.returncode != 0:
        return {"N": N, "eps": eps, "mode": mode, "done": False,
                "error": proc.stderr.strip().splitlines()[-1] if proc.stderr else "failed"}
    return json.loads(proc.stdout.strip().splitlines()[-1])


def row(r: dict, spectra: str = "auto", refine_from: str = "default") -> str:
    """A table row; the detection column names the spectra's device unless it is "auto", and
    the refinement's threshold unless it is the default."""
    if spectra != "auto":
        r = dict(r, mode=f"{r['mode']}, spectra {spectra}")
    if refine_from != "default":
        r = dict(r, mode=f"{r['mode']}, refine from n = {refine_from}")
    if "error" in r:
        return f"| {r['N']} | {r['eps']:g} | {r['mode']} | failed: {r['error']} |"
    coll = "-" if r["collisions"] is None else len(r["collisions"])
    status = "0.12" if r["done"] else f"stopped at F_x = {r['reached']:.4g}"
    memory = f"{r['peak_mb']:.0f}" + (f" + {r['workers']} x {r['worker_mb']:.0f}" if r["workers"] else "")
    return (f"| {r['N']} | {r['eps']:g} | {r['mode']} | {r['workers']} | {r['seconds']:.1f} | {status} | "
            f"{r['spectra']} + {r['partial']} | {r['refined']} ({r['repaired']}) + {r['declined']} | {r['factorizations']} | {r['solves']} | {coll} | {memory} |")


def agreement(fast: dict, exhaustive: dict) -> str:
    a, b = fast.get("collisions"), exhaustive.get("collisions")
    if a is None or b is None:
        return "not compared (a run did not finish)"
    if len(a) != len(b):
        return f"{len(a)} against {len(b)} collisions"
    diff = np.abs(np.array(a) - b)
    worst = int(np.argmax(diff)) if diff.size else 0
    return (f"same {len(a)} collisions, max |dF_x| = {np.max(diff, initial=0):.1e}"
            + (f" (at F_x = {a[worst]:.6f}; {np.sum(diff > 1e-9)} beyond 1e-9)" if diff.size else ""))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--N", default="10,20,40,100,200,400,1000")
    ap.add_argument("--budget", type=float, default=600.0, help="seconds per run")
    ap.add_argument("--exhaustive-up-to", type=int, default=100)
    ap.add_argument("--eps", default="1e-4,0")
    ap.add_argument("--window-N", default="", help="N values for a spectral-window run")
    ap.add_argument("--window", default="0.0715:0.08", help="LO:HI in lambda / k_n")
    ap.add_argument("--workers", default="auto", help="scan workers of the fast detection (auto: the sweep's choice)")
    ap.add_argument("--spectra", default="auto", help="cpu, gpu or auto; several (gpu,cpu): each fast run for each")
    ap.add_argument("--refine-from", default="default",
                    help="n from which full spectra are refined (refinement.REFINE_FROM; inf: never); several: "
                         "each fast run for each")
    ap.add_argument("--progress", type=float, default=0.0,
                    help="print the F_x each fast run reached to stderr, at most every this many seconds")
    args = ap.parse_args()
    if args.progress < 0:
        ap.error(f"--progress: seconds between lines must be >= 0 (got {args.progress:g})")
    devices, refines = args.spectra.split(","), args.refine_from.split(",")
    sizes = [int(n) for n in args.N.split(",") if n]
    eps_values = [float(e) for e in args.eps.split(",")]
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load average {open('/proc/loadavg').read().split()[0]}")
    print("| N | eps | detection | workers | s | reached | spectra full + partial | refined (repaired) + declined | LU | "
          "solves | collisions | peak MB (sweep + workers x largest) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    results = {}
    for N in [int(n) for n in args.window_N.split(",") if n]:
        print(row(run(N, eps_values[0], "fast", args.budget, args.window, args.workers)), flush=True)
    for eps in eps_values:
        for N in sizes:
            variants = [(device, refine) for device in devices for refine in refines]
            r = results[(N, eps, "fast")] = run(N, eps, "fast", args.budget, workers=args.workers,
                                                 spectra=devices[0], refine_from=refines[0], progress=args.progress)
            print(row(r, *variants[0]), flush=True)
            for device, refine in variants[1:]:
                other = run(N, eps, "fast", args.budget, workers=args.workers, spectra=device, refine_from=refine,
                            progress=args.progress)
                print(row(other, device, refine) + f" {agreement(other, r)}", flush=True)
            if eps and N <= args.exhaustive_up_to:
                e = results[(N, eps, "exhaustive")] = run(N, eps, "exhaustive", args.budget)
                print(row(e) + f" {agreement(r, e)}", flush=True)
    for eps in eps_values:
        done = [(N, results[(N, eps, "fast")]["seconds"]) for N in sizes
                if results[(N, eps, "fast")].get("done")]
        if len(done) >= 2:
            slope = np.polyfit(np.log([n for n, _ in done]), np.log([s for _, s in done]), 1)[0]
            print(f"eps = {eps:g}: time ~ N^{slope:.2f} over N = {', '.join(str(n) for n, _ in done)}")


if __name__ == "__main__":
    main()
