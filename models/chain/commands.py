"""The chain's front: what each command does with a chain scene (models/__init__.py). cli/
parses the arguments, checks what every geometry shares and calls these; they run the chain's
physics (models/chain/, dynamics/, studies/, peers/), write through reports/ and print. Values
on the command line and in files are raw units."""
from __future__ import annotations

import argparse
from pathlib import Path

from diskfriction.cli.common import (EXIT_FAILED, CommandError, bracketed_only, check_memory,
                                     check_window_covered, load,
                                     matrix_from_args, number, output_dir, path, run_length)
from diskfriction.cli.crosscheck_cmd import shortened, table
from diskfriction.cli.export_cmd import DEFAULT_EVERY, DEFAULT_STEPS
from diskfriction.cli.map_cmd import T_END, MapPlan
from diskfriction.cli.progress import Progress
from diskfriction.cli.bifurcate_cmd import parse_range
from diskfriction.cli.simulate_cmd import ENSEMBLE_AMPLITUDE, SCHEDULER, SINGLE_AMPLITUDE, parse_loads
from diskfriction.files import json_text
from diskfriction.scenes.scene import Scene
from diskfriction.words import count, duration


def bifurcate(args: argparse.Namespace, scene: Scene, window) -> int:
    """bifurcate a chain scene: sweep F_x (from rest), locate every collision, write
    branch.npz, collisions.json and diagram.png. window: --window parsed (paper units) or None."""
    if args.p is not None:
        raise CommandError("bifurcate error: --p: only with --problem FILE.py (a chain scene's load "
                           f"is --fx; got {args.p!r})")
    if args.spectra not in (None, "full"):
        raise CommandError(f"bifurcate error: --spectra: a chain's sweep computes every spectrum "
                           f"and locates every collision (full); none and sample:DGAMMA are a "
                           f"packing's (got {args.spectra!r})")
    if args.damping is not None:
        raise CommandError(f"bifurcate error: --damping: damped stability along a shear is a "
                           f"packing's; a chain scene takes no drag (got {args.damping!r})")
    F_from, F_to = parse_range(args.fx) if args.fx is not None else scene.F_x_range
    if args.ds_max is not None:
        number("bifurcate", "ds-max", args.ds_max)
    if args.workers is not None and args.workers < 0:
        raise CommandError(f"bifurcate error: --workers: must be >= 0 (got {args.workers})")
    matrix = matrix_from_args("bifurcate", args, scene)
    out = output_dir("bifurcate", args.out, Path("out") / "bifurcate" / scene.name)

    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.models.chain.equilibria import EquilibriumError
    from diskfriction.continuation.detection.scans import planned_workers
    from diskfriction.continuation.spectra.window import WindowCrowded
    from diskfriction.models.chain.sweep import SweepParams, sweep
    from diskfriction.continuation.records import brief
    from diskfriction.reports.bifurcation import collision_records, plot_diagram, save_branch
    from diskfriction.symbolic import System

    detection = DetectionParams(mode=args.detection)
    workers = planned_workers(scene.ndof, detection, args.workers, dense=window is None)
    check_memory("bifurcate", scene, 1 + workers, dense=window is None and scene.eps > 0)

    progress = Progress("bifurcate")
    total = F_from + abs(F_to - F_from)  # preparation leg plus the sweep
    done = {"F": 0.0, "last": 0.0}

    def on_point(F_x: float) -> None:
        done["F"] += abs(F_x - done["last"])
        done["last"] = F_x
        progress(done["F"] / total, f"F_x = {F_x:.5f}")

    try:
        system = System.from_scene(scene, progress.part("kernels"))
        progress.stage(f"sweep F_x {F_from:g} -> {F_to:g}" + (f" (from rest via {F_from:g})"
                                                              if F_from else ""))
        try:
            if window is not None:
                from diskfriction.reports.units import PaperUnits

                unit = PaperUnits.of(scene).eigenvalue(matrix)
                window = (window[0] * unit, window[1] * unit)
            params = SweepParams(ds_max=args.ds_max, window=window, detection=detection,
                                 workers=args.workers)
            branch = sweep(system, F_from, F_to, matrix, params, on_point)
        except (EquilibriumError, ContinuationError, WindowCrowded) as error:
            raise CommandError(f"bifurcate error: {scene.source}: {error}", EXIT_FAILED) from None
        if window is not None:
            check_window_covered(branch, args.window, matrix, unit)
        progress.stage(f"writing {out}/branch.npz, collisions.json")
        save_branch(out, branch, scene)
        progress.stage(f"plotting {out}/diagram.png")
        plot_diagram(branch, scene, out / "diagram.png")
    finally:
        progress.close()
    records = collision_records(branch)
    if args.json:
        print(json_text(brief(records)))
    else:
        print(f"{count(len(branch), 'equilibrium', 'equilibria')}, max residual {branch.residual.max():.1e}, "
              f"{branch.events} contact events split")
        for line in leg_lines(branch, F_to):
            print(f"  {line}")
        if branch.free.any():
            print(f"free rolling modes (disks held by the substrate alone, excluded from the "
                  f"collisions): {branch.free[0]} at F_x = {branch.F_x[0]:.3g}, "
                  f"{branch.free[-1]} at F_x = {branch.F_x[-1]:.3g}")
        print(f"{count(len(records), 'collision')} ({matrix})" + (
            "" if branch.window is None else f" with Re lambda in [{branch.window[0]:.6g}, "
            f"{branch.window[1]:.6g}] (raw; {branch.eigenvalues.shape[1]} eigenvalues tracked "
            "through it and its guard bands, a column each in branch.npz"
            + (f"; it crowded and was widened {count(branch.widenings, 'time')}"
               if branch.widenings else "") + ")") + bracketed_only(records) + ":")
        for r in records:
            unlocated = ("" if r["resolved"] else
                         "  bracketed only: F_x in [{:.10f}, {:.10f}]".format(*r["bracket"]))
            print(f"  {r['kind']:5s}  F_x = {r['p']:.10f}  lambda = {r['lambda']:.6g}  "
                  f"(lambda/k_n = {r['lambda'] / scene.k_n:.5g}){unlocated}")
        print(f"wrote {out}/branch.npz, collisions.json, diagram.png")
    if not branch.status.reached:
        from diskfriction.models.chain.equilibrium import contact_states

        raise CommandError(f"bifurcate error: {scene.source}: the sweep ended at F_x = "
                           f"{branch.F_x[-1]:.6g}, short of {F_to:g}: "
                           f"{branch.status.sentence(len(branch))}; there "
                           f"{contact_states(system, branch.q[-1], branch.xi[-1])}; what it "
                           f"reached is written", EXIT_FAILED)
    return 0


def leg_lines(branch, F_to: float) -> list[str]:
    """What each leg of a sweep did, one line each: its direction, the loads it passed through
    (cli.common.path), its points and how it ended."""
    import numpy as np

    lines = []
    for leg, status in ((piece.label, piece.status) for piece in branch.of_kind("leg")):
        rows = np.flatnonzero(branch.leg == leg)
        F = branch.F_x[np.r_[rows[0] - 1, rows] if rows[0] > 0 else rows]  # from where one ended
        what = ("preparation: loading from rest" if leg == 0 else
                ("loading" if F[-1] > F[0] else "unloading"))
        floor = (" (the rest state F_x = 0 is singular: unloading ends where loading started)"
                 if leg == 1 and F_to == 0 and status.reached else "")
        lines.append(f"leg {leg}, {what}: F_x {path(F)}, {count(rows.size, 'equilibrium', 'equilibria')}, "
                     f"{status.sentence(rows.size)}{floor}")
    return lines


def simulate(args: argparse.Namespace, scene: Scene) -> int:
    """simulate a chain scene: one run from the equilibrium at --fx, or an ensemble on dask."""
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


def verify(args: argparse.Namespace, scene: Scene) -> int:
    """verify a chain scene: one run per window between collisions (studies/verify.py)."""
    number("verify", "t-end", args.t_end)
    number("verify", "amplitude", args.amplitude, zero=True)
    matrix = matrix_from_args("verify", args, scene)
    out = output_dir("verify", args.out, Path("out") / "verify" / scene.name)
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.continuation.detection.scans import planned_workers

    check_memory("verify", scene, 1 + planned_workers(scene.ndof, DetectionParams()), spectra=1)

    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.models.chain.equilibria import EquilibriumError
    from diskfriction.dynamics.stepper import load_stepper
    from diskfriction.studies.verify import verify_windows
    from diskfriction.files import save_json, save_text
    from diskfriction.reports.verify import plot_verify, verify_table
    from diskfriction.symbolic import System

    progress = Progress("verify")
    try:
        load_stepper(System.from_scene(scene, progress.part("kernels")).kernels,
                     progress.part("stepper"))
        try:
            branch, rows = verify_windows(scene, matrix, args.t_end, args.amplitude,
                                          progress.part("windows"))
        except (EquilibriumError, ContinuationError) as error:  # the branch cannot start
            raise CommandError(f"verify error: {scene.source}: {error}", EXIT_FAILED) from None
        table = verify_table(rows, matrix)
        progress.stage(f"writing {out}/verify.json, verify.md, verify.png")
        save_json(out / "verify.json", rows)
        save_text(out / "verify.md", table)
        plot_verify(branch, rows, scene, args.t_end, out / "verify.png")
    finally:
        progress.close()
    print(table, end="")
    print(f"wrote {out}/verify.json, verify.md, verify.png")
    return 0


def report(args: argparse.Namespace, files: list, scenes: list) -> int:
    """report on chain scenes: the report builder's sections (reports/builder.py)."""
    from diskfriction.reports.builder import build_report, sections_named
    from diskfriction.reports.settings import SettingError, Settings, with_setting

    only = tuple(k.strip() for item in args.only or () for k in item.split(",") if k.strip())
    if args.only is not None and not only:
        raise CommandError(f"report error: --only: no section named (got "
                           f"{','.join(args.only)!r})")
    try:
        sections_named(only)
    except ValueError as error:
        raise CommandError(f"report error: --only: {error}") from None
    settings = Settings()
    try:
        for assignment in args.settings:
            settings = with_setting(settings, assignment)
    except SettingError as error:
        raise CommandError(f"report error: {error}") from None
    if args.cache == "":
        raise CommandError("report error: --cache: empty path (got '')")
    for scene in scenes:
        check_memory("report", scene, spectra=1)
    out = output_dir("report", args.out, Path("out/report"))
    from diskfriction.reports.builder import default_cache_dir

    cache = Path(args.cache) if args.cache else default_cache_dir(out)
    args.keeps = ("computations", cache)  # what Ctrl-C leaves to resume from (cli.common)
    log = build_report(scenes, out, only or None, settings, cache)
    computed = sum(e.status == "computed" for e in log)
    failed = sum("failed" in e.status for e in log)
    print(f"wrote {out / 'report.md'} ({len(log)} computations: {computed} computed, "
          f"{len(log) - computed} from the cache, {failed} failed)")
    return 0


def export(args: argparse.Namespace, scene: Scene) -> int:
    """export lammps: the chain scene as a LAMMPS deck (peers/lammps_deck.py)."""
    from diskfriction.peers.lammps_deck import check_representable

    F_x = load("export", args.fx)
    check_representable(scene)
    out = output_dir("export", args.out, Path("out") / "export" / scene.name)
    check_memory("export", scene, dense=False, spectra=1)  # the deck's dt: the start's spectrum

    from diskfriction.peers.crosscheck import default_dt
    from diskfriction.peers.lammps_deck import DUMP_FILE, deck, start_state
    from diskfriction.symbolic import System

    progress = Progress("export")
    try:
        system = System.from_scene(scene, progress.part("kernels"))
        progress.stage(f"{args.start} state at F_x = {F_x:g}")
        start = start_state(system, F_x, args.start)
        written = deck(scene, start, default_dt(system, start), DEFAULT_STEPS, DEFAULT_EVERY)
        paths = written.save(out)
    finally:
        progress.close()
    print(f"start: {start.note}")
    print(f"deck defaults: dt = {written.dt:.17g}, steps = {written.steps}, a dump every "
          f"{written.every} steps to {DUMP_FILE} (lmp -var dt|steps|every VALUE)")
    if scene.effects.conventions == "model":
        print('conventions: the scene uses "model"; LAMMPS integrates with its own (lever arm '
              'R - delta/2, end-of-step increment, whole increment on first contact): expect '
              'O(delta) differences (docs/physics.md)')
    print(f"wrote {', '.join(str(p) for p in paths)}; run: cd {out} && lmp -in {paths[1].name}")
    return 0


def crosscheck(args: argparse.Namespace, scene: Scene) -> int:
    """crosscheck lammps: one run here and in LAMMPS from the same state (peers/)."""
    from diskfriction.peers.lammps_deck import check_representable
    from diskfriction.peers.lammps_run import find_lammps

    F_x = load("crosscheck", args.fx)
    run_length("crosscheck", args.t_end, args.dt)
    if args.every is not None:
        number("crosscheck", "every", args.every, integer=True)
    check_representable(scene)
    out = output_dir("crosscheck", args.out, Path("out") / "crosscheck" / scene.name)
    check_memory("crosscheck", scene, dense=False, spectra=1)  # dt: the start's spectrum
    lammps = find_lammps()

    from diskfriction.files import save_json, save_npz
    from diskfriction.dynamics.simulate import UnstableStep
    from diskfriction.peers.crosscheck import crosscheck, lever_arm_band, plan_steps
    from diskfriction.peers.lammps_deck import start_state
    from diskfriction.reports.crosscheck import plot_deviation
    from diskfriction.symbolic import System

    progress = Progress("crosscheck")
    try:
        system = System.from_scene(scene, progress.part("kernels"))
        progress.stage(f"{args.start} state at F_x = {F_x:g}")
        start = start_state(system, F_x, args.start)
        try:
            steps = plan_steps(system, start, args.t_end, args.dt, args.every)
        except UnstableStep as error:
            raise CommandError(f"crosscheck error: --dt: {error} (got {args.dt!r})") from None
        progress.stage(f"both codes to t = {args.t_end:g} ({steps.steps} steps of {steps.dt:.4g}"
                       f"{shortened(args.dt, steps)}): about {duration(steps.seconds(system.N))} "
                       f"(a rough estimate)")
        result = crosscheck(system, start, steps, lammps, out / "lammps")
        summary = result.summary()
        band = None
        if scene.effects.conventions == "model" and scene.resolved_effects.rotation:
            band = lever_arm_band(system, result.ours, float(result.t[-1]))
            summary["lever_arm_band"] = list(band)
        progress.stage(f"writing {out}/crosscheck.json, deviation.npz, deviation.png")
        save_json(out / "crosscheck.json", summary)
        save_npz(out / "deviation.npz", t=result.t, **result.deviations())
        plot_deviation(result, scene, out / "deviation.png")
    finally:
        progress.close()
    print(f"start: {start.note}")
    print(f"LAMMPS {result.lammps_version}, conventions {scene.effects.conventions!r}, "
          f"{steps.steps} steps of dt = {steps.dt:.17g}{shortened(args.dt, steps)}, compared every "
          f"{steps.every} steps")
    print(table(result))
    if band is not None:
        print(f'conventions "model": the lever arm alone accounts for a theta deviation between '
              f'{band[0]:.2g} and {band[1]:.2g} at t = {result.t[-1]:g} (docs/physics.md)')
    print(f"wrote {out}/crosscheck.json, deviation.npz, deviation.png, lammps/")
    return 0


def chain_params(args: argparse.Namespace, scene):
    """A chain map's studies.maps.MapParams from --fx, --matrix, --slide, --t-end and
    --amplitude (checked: one line, exit 2)."""
    from diskfriction.studies.maps import MapParams, SlideParams

    if args.window is not None:
        raise CommandError(f"map error: --window: for packing scenes only; a chain's cells take "
                           f"full spectra (got {args.window!r})")
    if args.damping is not None or args.causality:
        flag, value = ("--damping", args.damping) if args.damping is not None else ("--causality", True)
        raise CommandError(f"map error: {flag}: the damped study is a packing's; a chain "
                           f"scene takes no drag (got {value!r})")
    F_from, F_to = parse_range(args.fx, command="map") if args.fx is not None else scene.F_x_range
    if F_from > F_to:
        raise CommandError(f"map error: --fx: a map loads, A < B (got {args.fx!r})")
    for option, value in (("t-end", args.t_end), ("amplitude", args.amplitude)):
        if value is not None and not args.slide:
            raise CommandError(f"map error: --{option}: sets the slide runs; add --slide "
                               f"(got {value!r})")
    t_end = number("map", "t-end", args.t_end if args.t_end is not None else T_END)
    amplitude = number("map", "amplitude",
                       args.amplitude if args.amplitude is not None else SINGLE_AMPLITUDE, zero=True)
    return MapParams(F_from, F_to, str(matrix_from_args("map", args, scene)),
                     SlideParams(t_end, amplitude) if args.slide else None)


def describe(cell, s: dict) -> str:
    """One printed line per cell: its values, status, collisions, F_slide and mu_eff, or why
    it failed or ended (raw units)."""
    values = ", ".join(f"{key} = {value:g}" for key, value in cell.values)
    if s["status"] == "failed":
        return f"{values}: failed: {s['reason']}"
    line = f"{values}: {s['status']}, {count(s['collisions'], 'collision')}, {count(s['windows'], 'window')}"
    if s["runs"] is not None:
        lo = "the first run" if s["F_slide_lo"] is None else f"stuck at {s['F_slide_lo']:.5g}"
        line += (f", no run slid (of {s['runs']})" if s["F_slide"] is None else
                 f", F_slide = {s['F_slide']:.5g} ({lo}), mu_eff = {s['mu_eff']:.4g}")
    return line + (f"; {s['reason']}" if s["reason"] else "")


def map_plan(args: argparse.Namespace, scene: Scene) -> MapPlan:
    """A chain map (cli/map_cmd.py): every cell sweeps F_x and, with --slide, runs the dynamics
    once per window (studies/maps.py)."""
    from diskfriction.reports.maps import plot_map
    from diskfriction.studies.maps import COLUMNS, cell_seconds, map_cell

    params = chain_params(args, scene)

    def check_cell(cell, at_once: int) -> None:
        check_memory("map", cell.scene, at_once, spectra=at_once if args.slide else 0)

    def plot(axes, cells, records, path: Path, title: str) -> None:
        plot_map(axes, cells, records, params, path, title
                 + (f", runs to t = {params.slide.t_end:g}" if args.slide else ""))

    return MapPlan(params, check_cell, map_kernels, map_cell, cell_seconds, COLUMNS, plot, describe)


def map_kernels(cells, params, progress: Progress) -> str:
    """Compile the kernels (and with slide runs the stepper) the cells need, and say what
    each cell runs."""
    from diskfriction.dynamics.stepper import load_stepper
    from diskfriction.symbolic import System

    system = System.from_scene(cells[0].scene, progress.part("kernels"))
    if params.slide is not None:
        load_stepper(system.kernels, progress.part("stepper"))
    return (f"bifurcate F_x {params.F_from:g} -> {params.F_to:g} ({params.matrix})"
            + (f", one run per window to t = {params.slide.t_end:g}" if params.slide else ""))
