"""``diskfriction crosscheck lammps [SCENE] --fx F --t-end T [--start rest|branch] [--dt DT]
[--every K] [--out DIR]``

Runs our dynamics and LAMMPS from the same state (peers/crosscheck.py) and prints the largest
deviation of x, y and theta over the disks against time; writes DIR/crosscheck.json,
DIR/deviation.npz, DIR/deviation.png and LAMMPS's files in DIR/lammps/. One line if LAMMPS is
not installed (diskfriction[lammps]).
"""
from __future__ import annotations

import argparse

from diskfriction.cli.common import add_scene_argument, code_targets, front_for, scene_from_args
from diskfriction.cli.export_cmd import add_start_argument

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
    lammps.add_argument("--fx", type=float, metavar="F", help="load on disk 1, raw force (required)")
    lammps.add_argument("--t-end", type=float, metavar="T", help="duration, raw time (required)")
    add_start_argument(lammps, "rest")
    lammps.add_argument("--dt", type=float, default=None,
                        help="largest time step: T is split into equal steps of at most DT "
                             "(default: 0.05 x 2 / omega_max at the start, as simulate)")
    lammps.add_argument("--every", type=int, default=None, metavar="K",
                        help="steps between compared frames (default: about 1000 frames)")
    lammps.add_argument("--out", metavar="DIR",
                        help="output directory (default: out/crosscheck/SCENE)")
    lammps.set_defaults(run=run, usage=lammps)


def run(args: argparse.Namespace) -> int:
    """The scene's crosscheck: a scene of another geometry is refused first (one line), then a
    missing --fx or --t-end as argparse refuses a missing required option (exit 2)."""
    scene = scene_from_args(args)
    front = front_for("crosscheck", scene)
    missing = [flag for flag, value in (("--fx", args.fx), ("--t-end", args.t_end)) if value is None]
    if missing:
        args.usage.error(f"the following arguments are required: {', '.join(missing)}")
    return front(args, scene)


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
