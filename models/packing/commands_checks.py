"""The packing front's checks at the door (models/packing/commands.py calls them): the spectra a
shear takes (--spectra or the scene's, resolved), what a packing command cannot compute (memory,
what the preparation can make, run length) refused in one line, exit 2, and the rough wall time
printed before any work; and the line bifurcate prints of the spectra it took. On the command
line's layer, as the front (tests/test_layers.py)."""
from __future__ import annotations

import argparse
import dataclasses
import sys
from typing import Optional

from diskfriction.cli.common import CommandError, bracketed_only, number, run_length
from diskfriction.scenes.packing import PackingScene
from diskfriction.words import count


def spectra_line(branch, scene: PackingScene, records: list, window) -> str:
    """What bifurcate prints of the shear's spectra: the collisions located and the states with
    complex pairs (full), the grid strains' pairs (sample), or that none was computed (none)."""
    band = "" if window is None else f", Re lambda in [{window[0]:.6g}, {window[1]:.6g}] (raw)"
    if scene.resolved_spectra == "none":
        return (f"spectra none: no eigenvalue computed, no collision looked for (--spectra "
                f"sample:DGAMMA or full for the {scene.matrix} spectrum)")
    if scene.sample_spacing is not None:
        n = [x.n_complex for x in branch.sample]
        return (f"spectra sampled at {count(len(n), 'grid strain')} (every {scene.sample_spacing:g}"
                f"{band}): complex pairs of {scene.matrix} at "
                f"{100 * sum(k > 0 for k in n) / max(len(n), 1):.0f} % of them, at most "
                f"{max(n, default=0)}; no collision located")
    if branch.widenings:
        band += f" (the window crowded and was widened {count(branch.widenings, 'time')})"
    g0 = scene.gamma_range[0]
    return (f"{count(len(records), 'collision')} ({scene.matrix}) with gamma >= {g0:g}{band}"
            f"{bracketed_only(records)}; complex pairs at "
            f"{100 * (branch.n_complex > 0).mean():.0f} % of the equilibria, at most "
            f"{branch.n_complex.max()}")


def spectra_from_args(args: argparse.Namespace, scene: PackingScene,
                      window: Optional[tuple[float, float]]) -> str:
    """The shear's spectra, resolved (PackingScene.resolved_spectra): --spectra, else the
    scene's; a one-line CommandError (exit 2) for a value it does not take, a sample grid wider
    than the strain range, or --window with spectra none."""
    from diskfriction.scenes.rules import Invalid, spectra_choice
    from diskfriction.scenes.scene import SceneValueError

    given = scene.spectra if args.spectra is None else args.spectra
    try:  # the scene's own spectra were checked when it was loaded: only --spectra fails here
        chosen = dataclasses.replace(scene, spectra=spectra_choice(given)).resolved_spectra
    except Invalid as error:
        raise CommandError(f"bifurcate error: --spectra: {error.what} (got {given!r})") from None
    except SceneValueError as error:
        raise CommandError(f"bifurcate error: --spectra: {error.what}, [{scene.gamma_range[0]:g}, "
                           f"{scene.gamma_range[1]:g}] (got {given!r})") from None
    if window is not None and chosen == "none":
        auto = f" (auto for {scene.N} disks)" if given == "auto" else ""
        raise CommandError(f"bifurcate error: --window: a window of the spectrum needs --spectra "
                           f"full or sample:DGAMMA; the shear's spectra are none{auto} (got "
                           f"{args.window!r})")
    return chosen


def check_packing(command: str, scene: PackingScene, strain: Optional[float] = None,
                  processes: int = 1, window: bool = False, runs: int = 0,
                  t_end: Optional[float] = None, dt: Optional[float] = None) -> None:
    """Before any work on a packing scene, refuse in one line (exit 2) what `command` cannot
    compute, and print on stderr the rough wall time of what it will do. Refused, in this order:
    - more memory than this machine has (models/packing/memory.py), naming N and what it counted: the
      preparation, and with `strain` a shear from gamma = 0 to it with the scene's spectra
      (resolved_spectra; memory.shear_needs: dense 3N x 3N spectra in each of `processes`
      processes, the shear's and its scan workers', or with `window` or spectra none only the
      points it stores);
    - a scene the preparation cannot make (models/packing/limits.py: a box too narrow for its
      contacts, a pressure below what double precision resolves), naming the key and value;
    - with `runs` dynamics runs to t_end (step dt, default models/packing/cost.time_step), --t-end
      and --dt as run_length takes them, and a run of more than MAX_RUN_STEPS time steps.
    The estimate (models/packing/cost.py) is one line, ``COMMAND: about T (a rough estimate) to
    prepare N disks, shear ...``, as the chain's long commands print theirs."""
    from diskfriction.memory import NotEnoughMemory, require_memory
    from diskfriction.models.packing import cost, limits, memory
    from diskfriction.words import duration

    N = scene.N
    if runs:
        run_length(command, t_end, dt)
    needs = [(memory.prepare_bytes(N), f"a preparation of {N} disks")]
    seconds = [cost.prepare_seconds(N)]
    parts = [f"prepare {N} disks"]
    if strain is not None:
        spectra = scene.resolved_spectra
        needs.append(memory.shear_needs(N, strain, spectra, window, processes))
        seconds.append(cost.shear_seconds(N, strain, spectra, window))
        parts.append(f"shear them to gamma = {strain:g} {cost.spectra_words(spectra, window)}")
    nbytes, what = max(needs)
    try:
        require_memory(nbytes, f"N = {N}: {what}")
    except NotEnoughMemory as error:
        raise CommandError(f"{command} error: {scene.source}: {error}") from None
    problem = limits.preparation_problem(scene)
    if problem is not None:
        key, why = problem
        value = scene.N if key == "packing.N" else scene.pressure
        raise CommandError(f"{command} error: {scene.source}: {key} = {value!r}: {why}")
    if runs:
        steps = cost.run_steps(scene, t_end, dt)
        step = (f"--dt = {dt:g}" if dt is not None else
                f"dt = {cost.time_step(scene):.2g}, {cost.STABLE_FRACTION:g} of the stability "
                f"limit 2 / omega_max with omega_max about {cost.OMEGA_MAX_OVER_OMEGA_0:g} omega_0")
        if steps > cost.MAX_RUN_STEPS:
            option, given = ("dt", dt) if dt is not None else ("t-end", t_end)
            raise CommandError(f"{command} error: --{option}: a run to t = {t_end:g} takes "
                               f"about {steps:.2g} time steps ({step}), more than the "
                               f"{cost.MAX_RUN_STEPS:.0e} a run may take: the slowest growth "
                               f"measured shows within about {cost.GROWTH_STEPS:.0e} steps "
                               f"(got {given!r})")
        seconds.append(runs * cost.run_seconds(scene, steps))
        parts.append(f"run {'once' if runs == 1 else f'up to {runs} times'} for about "
                     f"{steps:.2g} time steps")
    listed = ", ".join(parts[:-1]) + " and " + parts[-1] if len(parts) > 1 else parts[0]
    print(f"{command}: about {duration(sum(seconds))} (a rough estimate) to {listed}",
          file=sys.stderr, flush=True)


def check_packing_bifurcate(args: argparse.Namespace, scene: PackingScene,
                            window: Optional[tuple[float, float]]) -> None:
    """check_packing for bifurcate on a packing: a shear over the scene's strain, its dense
    spectra in the main process and the scan workers it will start (planned_workers, from
    --workers and --detection), or with --window its points."""
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.continuation.detection.scans import planned_workers

    asked = None if args.workers is None else max(args.workers, 0)  # < 0: bifurcate refuses it
    workers = (planned_workers(scene.ndof, DetectionParams(mode=args.detection), asked,
                               dense=window is None) if scene.resolved_spectra == "full" else 0)
    check_packing("bifurcate", scene, strain=scene.gamma_range[1], processes=1 + workers,
                  window=window is not None)


def check_packing_simulate(args: argparse.Namespace, scene: PackingScene) -> None:
    """check_packing for simulate on a packing: --gamma G a number in [0, the scene's strain
    stop] (simulate runs from a state of the scene's shear, which [shear] gamma bounds), then a
    shear to G and one run to --t-end. Nothing without --gamma, which simulate asks for next."""
    if args.gamma is None:
        return
    number("simulate", "gamma", args.gamma, zero=True)
    stop = scene.gamma_range[1]
    if args.gamma > stop:
        raise CommandError(f"simulate error: --gamma: beyond the scene's strain range [0, "
                           f"{stop:g}] ([shear] gamma of {scene.source}): simulate runs from a "
                           f"state of the scene's shear; widen its range to go further "
                           f"(got {args.gamma!r})")
    check_packing("simulate", dataclasses.replace(scene, spectra="none"), strain=args.gamma, runs=1,
                  t_end=args.t_end, dt=args.dt)
