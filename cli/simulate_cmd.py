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

from diskfriction.cli.common import CommandError, add_scene_argument, front_for, scene_from_args
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
    return front_for("simulate", scene)(args, scene)
