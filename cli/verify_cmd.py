"""``diskfriction verify [SCENE]``: which complex pairs make the chain slide.

From the branch (0 .. the scene's F_x range end, the scene's or --matrix's stability matrix),
run the dynamics at the midpoint of every complex window and every all-real interval between
collisions (studies/verify.py) and tabulate: window, F_x, sigma predicted (M^-1 J), sigma
measured, max M, slid ("not resolved" where the run's energy budget did not close). Writes
DIR/verify.json, DIR/verify.md and DIR/verify.png (the Im lambda diagram with each window
shaded by whether its run slid, stayed or is not resolved, over the growth rate measured
against the predicted one per window).

On a packing scene: shear over the scene's strain range, then run the dynamics from up to 8
states with complex pairs (along the fastest pair's eigenvector) and 2 with every eigenvalue
real (random velocities); tabulate the growth rate measured against the spectrum's, whether
contacts slid, and what the run's end relaxes to at rest (rearranged, slipped or came back).
Writes DIR/verify.json and DIR/verify.md (docs/packings.md).
"""
from __future__ import annotations

import argparse

from diskfriction.cli.common import (add_matrix_argument, add_scene_argument, front_for,
                                     scene_from_args)
from diskfriction.cli.simulate_cmd import SINGLE_AMPLITUDE


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "verify", help="run the dynamics in every complex window and real interval",
        description=__doc__.split("\n\n", 1)[1])
    add_scene_argument(parser)
    add_matrix_argument(parser, "matrix defining the windows")
    parser.add_argument("--t-end", type=float, default=1000.0, metavar="T", help="duration of each run, raw time")
    parser.add_argument("--amplitude", type=float, default=SINGLE_AMPLITUDE, metavar="A",
                        help="perturbation amplitude, raw (default 1e-10: room for the growth fit)")
    parser.add_argument("--out", metavar="DIR", help="output directory (default: out/verify/SCENE)")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    return front_for("verify", scene)(args, scene)
