"""``diskfriction simulate [SCENE] --fx F --t-end T [--seed S] [--out DIR] ...``

One run (one F_x, no --realizations): trajectory.npz, summary.json, run.png in DIR.
An ensemble (--realizations K and/or several F_x, comma separated) runs on dask.distributed
(a LocalCluster of this machine's cores, or --scheduler ADDRESS), writes every finished
realization at once under DIR/runs/, resumes when rerun, and aggregates the front speeds and
V_cm(F_x) into DIR/ensemble.json. Command-line values and files are raw units.
"""
from __future__ import annotations

import argparse
import math
import re
from pathlib import Path

from diskfriction.cli.common import (EXIT_FAILED, CommandError, add_scene_argument, check_memory,
                                     number, output_dir, run_length, scene_from_args)
from diskfriction.cli.progress import Progress
from diskfriction.words import count, duration
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.scene import NEGATIVE_LOAD

KINDS = ("random-velocity", "random-position", "eigenvector", "none")
SINGLE_AMPLITUDE = 1e-10
ENSEMBLE_AMPLITUDE = 1e-6


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "simulate", help="Newtonian dynamics with Coulomb sliding from a branch point",
        description="Start at the quasistatic equilibrium at F_x (reached from rest with the "
                    "history carried), perturb it, and integrate Newton's equations with "
                    "Coulomb sliding. Raw units on the command line and in files; the plot "
                    "uses the paper's units.")
    add_scene_argument(parser)
    parser.add_argument("--fx", metavar="F[,F...]",
                        help="load(s) F_x, raw units; several make an ensemble (a chain scene)")
    parser.add_argument("--gamma", type=float, metavar="G",
                        help="the strain to start from (a packing scene, docs/packings.md)")
    parser.add_argument("--t-end", required=True, type=float, metavar="T", help="duration, raw time")
    parser.add_argument("--seed", type=int, default=0, help="seed of the (first) realization")
    parser.add_argument("--perturbation", default=None, choices=KINDS,
                        help="eigenvector (of the largest complex pair of M^-1 J; the default "
                             "for one run when there is one) or random-velocity (the default "
                             "otherwise and for ensembles)")
    parser.add_argument("--amplitude", type=float, default=None, metavar="A",
                        help="perturbation amplitude, raw length (velocity for random-velocity); "
                             "default 1e-10 for one run (leaves decades of linear growth before "
                             "the contacts' nonlinearity at ~1e-6, so sigma can be measured), "
                             "1e-6 for ensembles")
    parser.add_argument("--dt", type=float, default=None,
                        help="largest time step: the run takes ceil(T / DT) equal steps ending "
                             "exactly at T (default: 0.05 x 2 / omega_max of the start)")
    parser.add_argument("--realizations", type=int, default=None, metavar="K",
                        help="run K seeded realizations per F_x on dask")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="dask scheduler to use instead of a local cluster")
    parser.add_argument("--out", metavar="DIR", help="output directory (default: out/simulate/SCENE)")
    parser.set_defaults(run=run)


def parse_loads(text: str) -> list[float]:
    """'F[,F...]' -> distinct positive loads; else a one-line CommandError."""
    try:
        loads = [float(v) for v in text.split(",")]
    except ValueError:
        loads = []
    if loads and any(F < 0 for F in loads):
        raise CommandError(f"simulate error: --fx: F_x must be > 0: {NEGATIVE_LOAD} (got {text!r})")
    if not loads or not all(math.isfinite(F) and F > 0 for F in loads):
        raise CommandError(f"simulate error: --fx: expected positive numbers F[,F...] (got {text!r})")
    repeated = sorted({F for F in loads if loads.count(F) > 1})
    if repeated:
        raise CommandError(f"simulate error: --fx: load {repeated[0]:g} given twice; use "
                           f"--realizations for repeated runs (got {text!r})")
    return loads


SCHEDULER = re.compile(r"^((tcp|tls|ws|wss|ucx)://)?[^\s:/]+:\d+$")
"""A dask scheduler address: [PROTOCOL://]HOST:PORT."""


def run(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    if isinstance(scene, PackingScene):
        from diskfriction.cli.packing_cmd import run_packing_simulate

        return run_packing_simulate(args, scene)
    if args.gamma is not None:
        raise CommandError(f"simulate error: --gamma: only for a packing scene; a chain's load "
                           f"is --fx (got {args.gamma!r})")
    if args.fx is None:
        raise CommandError("simulate error: --fx: a chain scene needs the load(s) to start from "
                           "(got nothing)")
    loads = parse_loads(args.fx)
    run_length("simulate", args.t_end, args.dt)
    number("simulate", "seed", args.seed, zero=True, integer=True)  # numpy seeds are >= 0
    if args.realizations is not None:
        number("simulate", "realizations", args.realizations, integer=True)
    if args.scheduler is not None and not SCHEDULER.match(args.scheduler):
        raise CommandError(f"simulate error: --scheduler: expected a dask scheduler address "
                           f"[tcp://]HOST:PORT (got {args.scheduler!r})")
    single = args.realizations is None and len(loads) == 1
    if args.amplitude is None:
        args.amplitude = SINGLE_AMPLITUDE if single else ENSEMBLE_AMPLITUDE
    number("simulate", "amplitude", args.amplitude, zero=True)
    out = output_dir("simulate", args.out, Path("out") / "simulate" / scene.name)
    check_memory("simulate", scene, dense=False, spectra=1)  # equilibrium_at takes no spectra
    if not single:
        args.keeps = ("realizations", out / "runs")  # what Ctrl-C leaves to resume from (cli.common)
    progress = Progress("simulate")
    try:
        if single:
            return single_run(scene, loads[0], args, out, progress)
        return ensemble_run(scene, loads, args, out, progress)
    finally:
        progress.close()


def single_run(scene, F_x: float, args, out: Path, progress: Progress) -> int:
    from diskfriction.models.chain.equilibrium import equilibrium_at
    from diskfriction.dynamics.simulate import UnstableStep, inaccuracy, plan_run, simulate, summarize
    from diskfriction.dynamics.start import Perturbation, spectrum
    from diskfriction.dynamics.stepper import load_stepper
    from diskfriction.reports.simulation import plot_run, save_run
    from diskfriction.reports.units import PaperUnits
    from diskfriction.symbolic import System

    system = System.from_scene(scene, progress.part("kernels"))
    progress.stage(f"sweep from rest to F_x = {F_x:g}")
    eq = equilibrium_at(system, F_x)
    load_stepper(system.kernels, progress.part("stepper"))
    spec = spectrum(system, eq.q, eq.xi)
    kind = args.perturbation or ("eigenvector" if spec.pairs.size else "random-velocity")
    try:
        plan = plan_run(spec, args.t_end, args.dt)
        progress.stage(f"run to t = {args.t_end:g}: {plan.n_steps} steps, about "
                       f"{duration(plan.seconds(system.N))} (a rough estimate)")
        traj = simulate(system, eq.q, eq.xi, F_x, args.t_end, dt=args.dt,
                        perturbation=Perturbation(kind, args.amplitude, args.seed),
                        progress=lambda t: progress(t / args.t_end, f"t = {t:.1f}"), spec=spec)
    except UnstableStep as error:
        raise CommandError(f"simulate error: --dt: {error} (got {args.dt!r})") from None
    except ValueError as error:  # e.g. an eigenvector perturbation where all eigenvalues are real
        raise CommandError(f"simulate error: {error}") from None
    summary = summarize(traj)
    progress.stage(f"writing {out}/trajectory.npz, summary.json")
    save_run(out, traj, summary)
    progress.stage(f"plotting {out}/run.png")
    plot_run(traj, summary, scene, out / "run.png")
    progress.close()
    sm, sp = summary["sigma_measured"], summary["sigma_predicted"]
    print(f"F_x = {F_x:g}, t_end = {args.t_end:g}, dt = {traj.dt:.4g}, {traj.steps} steps, "
          f"perturbation {kind} {args.amplitude:g}")
    if not summary["accurate"]:
        print(f"wrote {out}/trajectory.npz, summary.json, run.png (slid: not reported)")
        raise CommandError(f"simulate error: {inaccuracy(summary)}; slid is not reported "
                           f"(use a smaller --dt)", code=EXIT_FAILED)
    print(f"sigma measured {'-' if sm is None else f'{sm:.5g}'}, predicted {sp:.5g} (raw 1/time, "
          f"M^-1 J); slid: {summary['slid']}; max M = {summary['M_max']:.3g}")
    print(f"V_cm = {summary['V_cm']:.4g} raw = {summary['V_cm'] / PaperUnits.of(scene).velocity:.4g} 2R/tau; "
          f"energy budget closes to {summary['budget_relative']:.2g} of the energy exchanged")
    print(f"wrote {out}/trajectory.npz, summary.json, run.png")
    return 0


def ensemble_estimate(scene, loads, K: int, args, out: Path) -> str:
    """The realizations not on disk yet and their rough wall time (dynamics.simulate.run_seconds)
    on the local cluster's workers, or per worker of a remote scheduler."""
    from diskfriction.studies.cluster import local_workers
    from diskfriction.studies.ensemble import RunSpec, pending
    from diskfriction.dynamics.simulate import run_seconds

    todo, _ = pending(scene, loads, K, RunSpec(args.t_end, args.amplitude, args.perturbation or
                                               "random-velocity", args.seed), out)
    if not todo:
        return "all on disk"
    at_once = 1 if args.scheduler else min(len(todo), local_workers())
    where = "divided by the scheduler's workers" if args.scheduler else f"on {count(at_once, 'worker')}"
    seconds = len(todo) * run_seconds(scene, args.t_end) / at_once
    return f"{count(len(todo), 'run')} to do, about {duration(seconds)} {where} (a rough estimate)"


def ensemble_run(scene, loads, args, out: Path, progress: Progress) -> int:
    from diskfriction.studies.ensemble import run_ensemble
    from diskfriction.dynamics.stepper import load_stepper
    from diskfriction.reports.units import PaperUnits
    from diskfriction.symbolic import System

    # compiled here once, so that the workers load it from the cache instead of compiling it
    load_stepper(System.from_scene(scene, progress.part("kernels")).kernels, progress.part("stepper"))
    K = int(args.realizations or 1)
    progress.stage(f"ensemble: {count(K, 'realization')} x {count(len(loads), 'load')} to "
                   f"t = {args.t_end:g}: {ensemble_estimate(scene, loads, K, args, out)}")
    ens = run_ensemble(scene, loads, K, args.t_end, out, seed=args.seed, amplitude=args.amplitude,
                       kind=args.perturbation or "random-velocity", scheduler=args.scheduler,
                       progress=lambda done, total: progress(done / total, f"{done}/{total} realizations"))
    progress.close()
    paper = lambda e: e.value / PaperUnits.of(scene).velocity
    for F in sorted(ens.summaries):
        slid = sum(s["slid"] is True for s in ens.summaries[F])
        unresolved = sum(not s["accurate"] for s in ens.summaries[F])
        v1 = ens.V1[F]
        print(f"F_x = {F:g}: {count(len(ens.summaries[F]), 'realization')}, {slid} slid"
              f"{f', {unresolved} not resolved (energy budget), left out' if unresolved else ''}; "
              f"V1 = {v1.value:.4g} +- {v1.error:.2g} raw ({paper(v1):.3g} 2R/tau, n = {v1.n}); "
              f"V_cm = {ens.V_cm[F].value:.4g} raw")
    print(f"V2 = {ens.V2.value:.4g} +- {ens.V2.error:.2g} raw ({paper(ens.V2):.3g} 2R/tau, n = {ens.V2.n})")
    if ens.V_cm_fit is not None:
        a, b = ens.V_cm_fit
        print(f"V_cm = {a.value:.3g} (+- {a.error:.2g}) + {b.value:.3g} (+- {b.error:.2g}) F_x  (raw); "
              f"paper units: {paper(a):.3g} + {paper(b):.3g} F_x")
    print(f"wrote {out}/ensemble.json and {out}/runs/")
    return 0
