"""``diskfriction crosscheck lammps [SCENE] --fx F --t-end T [--start rest|branch] [--dt DT]
[--every K] [--out DIR]``

Runs our dynamics and LAMMPS from the same state (peers/crosscheck.py) and prints the largest
deviation of x, y and theta over the disks against time; writes DIR/crosscheck.json,
DIR/deviation.npz, DIR/deviation.png and LAMMPS's files in DIR/lammps/. One line if LAMMPS is
not installed (diskfriction[lammps]).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from diskfriction.cli.common import (CommandError, add_scene_argument, check_memory, code_targets, load,
                                     number, output_dir, run_length, scene_from_args)
from diskfriction.cli.export_cmd import add_start_argument
from diskfriction.cli.progress import Progress
from diskfriction.words import duration

TABLE_ROWS = 10


def register(subparsers: argparse._SubParsersAction) -> None:
    lammps = code_targets(subparsers, "crosscheck", "run another code beside ours and compare").add_parser(
        "lammps", help="our dynamics against LAMMPS from the same state",
        description="Export the scene to LAMMPS (as `export lammps`), run LAMMPS and our "
                    "dynamics from the same state with the same steps, and print the largest "
                    "deviation of x, y and theta over the disks against time. They agree to "
                    "rounding for the linear Mindlin law with [effects] conventions = "
                    "\"lammps\" (docs/lammps.md). Raw units.")
    add_scene_argument(lammps)
    lammps.add_argument("--fx", type=float, required=True, metavar="F", help="load on disk 1, raw force")
    lammps.add_argument("--t-end", type=float, required=True, metavar="T", help="duration, raw time")
    add_start_argument(lammps, "rest")
    lammps.add_argument("--dt", type=float, default=None,
                        help="largest time step: T is split into equal steps of at most DT "
                             "(default: 0.05 x 2 / omega_max at the start, as simulate)")
    lammps.add_argument("--every", type=int, default=None, metavar="K",
                        help="steps between compared frames (default: about 1000 frames)")
    lammps.add_argument("--out", metavar="DIR",
                        help="output directory (default: out/crosscheck/SCENE)")
    lammps.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from diskfriction.peers.lammps_deck import check_representable
    from diskfriction.peers.lammps_run import find_lammps

    scene = scene_from_args(args, "crosscheck")
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


def shortened(dt, steps) -> str:
    """Why the step is shorter than --dt asked for, if it is by more than rounding: equal
    steps end exactly at T, on a compared frame (a whole number of strides of --every)."""
    if dt is None or steps.dt >= dt * (1 - 1e-9):
        return ""
    return (f"; --dt {dt:g} shortened: equal steps, {steps.every} per compared frame, end "
            f"exactly at T")


def table(result) -> str:
    """Deviations at TABLE_ROWS evenly spaced frames, and the largest over the run."""
    import numpy as np

    names = list(result.deviations())
    rows = [f"{'t':>10}" + "".join(f"{'max |d' + n + '|':>14}" for n in names)]
    for k in np.unique(np.linspace(0, result.t.size - 1, TABLE_ROWS + 1).round().astype(int)):
        rows.append(f"{result.t[k]:>10.4g}" + "".join(f"{d[k]:>14.3e}" for d in result.deviations().values()))
    rows.append(f"{'whole run':>10}" + "".join(f"{d.max():>14.3e}" for d in result.deviations().values()))
    return "\n".join(rows)
