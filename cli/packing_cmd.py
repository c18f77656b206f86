"""``diskfriction bifurcate PACKING_SCENE [--matrix J|M^-1J] [--window LO:HI] [--workers K]
[--out DIR] [--json]``: prepare the scene's packing, shear it quasistatically with friction and locate
every birth and death of a complex pair (issue 25, docs/packings.md#shear)."""
from __future__ import annotations

import argparse
import dataclasses
import json
from pathlib import Path

from diskfriction.cli.common import EXIT_FAILED, CommandError, matrix_from_args, output_dir
from diskfriction.cli.progress import Progress
from diskfriction.scenes.packing import PackingScene
from diskfriction.words import count

CHAIN_ONLY = {"fx": "a packing's load is its strain: [shear] gamma in the scene",
              "p": "only with --problem FILE.py", "ds_max": "a packing's step follows its strain"}
"""bifurcate's options a packing scene does not take, and why."""

PLASTIC_EVENTS = 1000
"""The plastic events a command passes (packings/plastic.py) before it stops at the next."""


def run_packing(args: argparse.Namespace, scene: PackingScene) -> int:
    """bifurcate on a packing scene: prepare, shear, write branch.npz, collisions.json,
    diagram.png and packing.npz; exit 1 with one line when the branch ends short of the scene's
    strain (a plastic event, a fold in gamma), after writing what it reached."""
    for option, why in CHAIN_ONLY.items():
        if getattr(args, option) is not None:
            flag = "--" + option.replace("_", "-")
            raise CommandError(f"bifurcate error: {flag}: {why} (got {getattr(args, option)!r})")
    if args.workers is not None and args.workers < 0:
        raise CommandError(f"bifurcate error: --workers: must be >= 0 (got {args.workers})")
    from diskfriction.cli.bifurcate_cmd import check_window_covered, parse_window

    window = parse_window(args.window) if args.window is not None else None
    matrix = matrix_from_args("bifurcate", args, scene)
    out = output_dir("bifurcate", args.out, Path("out") / "bifurcate" / scene.name)

    from diskfriction.continuation.arclength import ContinuationError
    from diskfriction.continuation.branch import StopCode
    from diskfriction.continuation.collisions import DetectionParams
    from diskfriction.continuation.spectral_window import WindowCrowded
    from diskfriction.packings.equilibria import MissedContact
    from diskfriction.packings.plastic import RelaxationFailed
    from diskfriction.packings.prepare import save_packing
    from diskfriction.packings.prepared import prepare_scene
    from diskfriction.packings.shear import ShearParams, shear
    from diskfriction.reports.packing_outputs import (collision_records, plot_packing_diagram,
                                                      save_packing_branch)

    scene = dataclasses.replace(scene, matrix=str(matrix))
    g0, g1 = scene.gamma_range
    progress = Progress("bifurcate")
    try:
        progress.stage(f"prepare {scene.N} disks to pressure {scene.pressure:g}")
        packing = prepare_scene(scene, progress.part("relax"))
        save_packing(out / "packing.npz", packing)
        progress.stage(f"shear gamma 0 -> {g1:g}")
        params = ShearParams(detection=DetectionParams(mode=args.detection), workers=args.workers)
        try:
            branch = shear(scene, packing, params,
                           lambda gamma: progress(gamma / g1, f"gamma = {gamma:.3e}"),
                           plastic_events=PLASTIC_EVENTS, window=window)
        except (ContinuationError, MissedContact, RelaxationFailed, WindowCrowded) as error:
            raise CommandError(f"bifurcate error: {scene.source}: {error}", EXIT_FAILED) from None
        if window is not None:
            check_window_covered(branch, args.window, matrix, 1.0)
        progress.stage(f"writing {out}/branch.npz, collisions.json")
        save_packing_branch(out, branch, scene)
        progress.stage(f"plotting {out}/diagram.png")
        plot_packing_diagram(branch, scene, out / "diagram.png")
    finally:
        progress.close()
    records = collision_records(branch)
    if args.json:
        print(json.dumps(records, indent=1))
    else:
        print(f"{count(len(branch), 'equilibrium', 'equilibria')} from gamma = 0 to "
              f"{branch.gamma[-1]:.6g}, max residual {branch.residual.max():.1e}, "
              f"{branch.events} contact events split; {branch.contacts[0]} -> "
              f"{branch.contacts[-1]} contacts, {branch.loose[-1]} loose disks")
        print(f"{count(len(branch.plastic), 'plastic event')} passed (branch lost, relaxed "
              f"with friction):")
        for e in branch.plastic:
            print(f"  gamma = {e.gamma:.9f} ({e.kind}): sigma_xy {e.stress_before:.6g} -> "
                  f"{e.stress_after:.6g}")
        inside = ("" if branch.window is None else f", Re lambda in [{branch.window[0]:.6g}, "
                  f"{branch.window[1]:.6g}] (raw)")
        print(f"{count(len(records), 'collision')} ({matrix}) with gamma >= {g0:g}{inside}; "
              f"complex pairs at {100 * (branch.n_complex > 0).mean():.0f} % of the equilibria, "
              f"at most {branch.n_complex.max()}")
        print(f"wrote {out}/branch.npz, collisions.json, diagram.png, packing.npz")
    if not branch.status.reached:
        why = ("a plastic event: the quasistatic branch folds back in gamma (a saddle-node)"
               if branch.status.code is StopCode.FOLD else branch.status.sentence(len(branch)))
        raise CommandError(f"bifurcate error: {scene.source}: the branch ended at gamma = "
                           f"{branch.gamma[-1]:.9g}, short of {g1:g}: {why}; what it reached "
                           f"is written", EXIT_FAILED)
    return 0


def run_packing_simulate(args: argparse.Namespace, scene: PackingScene) -> int:
    """simulate on a packing scene: prepare, shear to --gamma (exit 1 with one line if the
    branch ends before it), perturb the equilibrium there (default: along the eigenvector of its
    fastest-growing complex pair, else random velocities), integrate, and compare the measured
    growth rate with the spectrum's. Writes run.npz, summary.json, run.png and snapshot.png
    (the packing at G, its contact forces and the perturbation)."""
    from diskfriction.cli.common import number, run_length

    for option, why in {"fx": "a packing's load is its strain: --gamma G",
                        "realizations": "ensembles are not yet offered for packings",
                        "scheduler": "ensembles are not yet offered for packings"}.items():
        if getattr(args, option) is not None:
            raise CommandError(f"simulate error: --{option}: {why} (got {getattr(args, option)!r})")
    if args.gamma is None:
        raise CommandError("simulate error: --gamma: a packing scene needs the strain to start "
                           "from (got nothing)")
    number("simulate", "gamma", args.gamma, zero=True)
    run_length("simulate", args.t_end, args.dt)
    number("simulate", "seed", args.seed, zero=True, integer=True)
    amplitude = 1e-10 if args.amplitude is None else number("simulate", "amplitude", args.amplitude,
                                                            zero=True)
    out = output_dir("simulate", args.out, Path("out") / "simulate" / scene.name)

    import numpy as np

    from diskfriction.files import save_json, save_npz
    from diskfriction.packings.dynamics import (distance, fastest_pair, growth_rate, simulate,
                                                time_step)
    from diskfriction.packings.equilibria import PackingEquilibria, mass_diagonal
    from diskfriction.packings.prepared import prepare_scene
    from diskfriction.packings.shear import ShearParams, network_of, shear
    from diskfriction.reports.packing_outputs import plot_packing_run, plot_packing_snapshot

    scene = dataclasses.replace(scene, gamma_range=(0.0, args.gamma) if args.gamma > 0 else (0.0, 1e-12))
    progress = Progress("simulate")
    try:
        progress.stage(f"prepare {scene.N} disks to pressure {scene.pressure:g}")
        packing = prepare_scene(scene, progress.part("relax"))
        progress.stage(f"shear gamma 0 -> {args.gamma:g}")
        branch = shear(scene, packing, ShearParams(workers=0),
                       lambda g: progress(g / max(args.gamma, 1e-300), f"gamma = {g:.3e}"),
                       plastic_events=PLASTIC_EVENTS)
        if not branch.status.reached:
            raise CommandError(f"simulate error: {scene.source}: no equilibrium beyond gamma = "
                               f"{branch.gamma[-1]:.9g} (asked for {args.gamma:g}): the branch "
                               f"ends there ({branch.status.sentence(len(branch))})", EXIT_FAILED)
        network = network_of(scene, packing)
        mass = mass_diagonal(network, scene.m, scene.inertia)
        lam = branch.eigenvalues[-1]
        q0, xi0, rows0, gamma = branch.q[-1], branch.xi[-1], branch.rows[-1], branch.gamma[-1]
        limit = 2.0 / float(np.sqrt(np.abs(lam).max()))
        if args.dt is not None and args.dt >= limit:
            raise CommandError(f"simulate error: --dt: not below velocity Verlet's stability "
                               f"limit 2 / omega_max = {limit:.4g} of the start (got {args.dt!r})")
        dt = args.dt or time_step(lam)
        i, sigma = fastest_pair(lam)
        kind = args.perturbation or ("eigenvector" if i >= 0 else "random-velocity")
        rng = np.random.default_rng(args.seed)
        q, v = q0.copy(), np.zeros_like(q0)
        if kind == "eigenvector":
            if i < 0:
                raise CommandError(f"simulate error: --perturbation: eigenvector needs a complex "
                                   f"pair at gamma = {gamma:g}, and there is none")
            problem = PackingEquilibria(network, q0, xi0, rows0, gamma, mass, scene.matrix)
            system = problem.eigensystem(q0, gamma, vectors=True)
            mode = np.real(system.vectors(int(np.argmin(np.abs(system.values - lam[i]))))[0])
            q += amplitude * mode / np.sqrt(np.sum(mass * mode * mode))
        elif kind == "random-position":
            shift = rng.normal(size=q.size)
            q += amplitude * shift / np.sqrt(np.sum(mass * shift * shift))
        elif kind == "random-velocity":
            v = amplitude * rng.normal(size=q.size)
        progress.stage(f"run to t = {args.t_end:g} ({int(round(args.t_end / dt))} steps)")
        run = simulate(network, q, v, xi0, rows0, gamma, mass, dt, args.t_end, frames=2000)
        d = distance(run, q0, mass)
        measured, used = growth_rate(run.t, d, 10 * max(d[0], 1e-300), 1e-3 * scene.delta_0)
        drift = float(np.abs(run.budget - run.budget[0]).max())
        summary = {"scene": scene.name, "gamma": gamma, "perturbation": kind,
                   "amplitude": amplitude, "dt": dt, "t_end": float(run.t[-1]),
                   "sigma_predicted": sigma, "sigma_measured": measured, "maxima_fitted": used,
                   "budget_drift": drift, "kinetic_max": float(run.kinetic.max()),
                   "sliding_updates": int(run.capped[-1]), "complex_pairs": int(branch.n_complex[-1])}
        save_npz(out / "run.npz", t=run.t, q=run.q, distance=d, budget=run.budget,
                 kinetic=run.kinetic, capped=run.capped)
        save_json(out / "summary.json", summary)
        plot_packing_run(run.t, d, sigma, measured, scene, gamma, out / "run.png")
        delta = network.overlaps(q0, rows0, gamma)
        force = np.where(delta > 0, network.kernels.normal_force(np.maximum(delta, 0.0),
                                                                 scene.k_n), 0.0)
        plot_packing_snapshot(q0, network.radii, network.L, gamma, rows0, force, q - q0 + v,
                              f"{scene.name} at gamma = {gamma:.4g}: contact forces (red, width "
                              f"~ F_n) and the perturbation ({kind}, blue)", out / "snapshot.png")
    finally:
        progress.close()
    print(f"gamma = {gamma:g}: {count(int(branch.n_complex[-1]), 'complex pair')}, the fastest "
          f"growing at sigma = {sigma:.6g} (|Im sqrt(lambda)| of M^-1 J)")
    print(f"run to t = {run.t[-1]:g} ({kind}, amplitude {amplitude:g}, dt {dt:.4g}): measured "
          f"sigma = {measured:.6g} from {used} maxima; energy budget drift {drift:.2e} "
          f"(max kinetic {run.kinetic.max():.2e}); {int(run.capped[-1])} sliding updates")
    print(f"wrote {out}/run.npz, summary.json, run.png, snapshot.png")
    return 0
