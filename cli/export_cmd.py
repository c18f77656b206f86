"""``diskfriction export lammps [SCENE] [--fx F] [--start rest|branch] [--out DIR]``

Writes DIR/scene.data and DIR/in.scene: the scene as LAMMPS input (peers/lammps_deck.py), from
the branch point at F_x with zero histories (or the rest state with F_x switched on), saying
which on stdout and in the deck. What LAMMPS cannot represent is refused with one line, exit 2.
"""
from __future__ import annotations

import argparse

from diskfriction.cli.common import add_scene_argument, code_targets, front_for, scene_from_args

STARTS = ("branch", "rest")
DEFAULT_STEPS, DEFAULT_EVERY = 1000, 10
"""The deck's default run (lmp -var steps N -var every K change it)."""


def add_start_argument(parser: argparse.ArgumentParser, default: str) -> None:
    parser.add_argument("--start", choices=STARTS, default=default,
                        help="branch: the equilibrium on the branch from rest at F_x, with zero "
                             "tangential histories (LAMMPS cannot be given any); rest: the F_x = 0 "
                             f"equilibrium with F_x switched on at t = 0 (default: {default})")


def register(subparsers: argparse._SubParsersAction) -> None:
    lammps = code_targets(subparsers, "export", "write a scene as input for another code").add_parser(
        "lammps", help="a LAMMPS data file and input deck",
        description="Write DIR/scene.data and DIR/in.scene, a LAMMPS data file and input deck "
                    "reproducing the scene (docs/lammps.md): Hertz and linear Mindlin contacts "
                    "mapped with R_eff, no damping, nve/sphere disc, enforce2d, addforce; every "
                    "number to 17 digits. Refuses (one line, exit 2) what LAMMPS cannot "
                    "represent: the smoothed Mindlin law, c other than 1/2 or 2/5, N = 2.")
    add_scene_argument(lammps)
    lammps.add_argument("--fx", type=float, default=0.0, metavar="F",
                        help="load on disk 1, raw force (default 0: the rest state)")
    add_start_argument(lammps, "branch")
    lammps.add_argument("--out", metavar="DIR", help="output directory (default: out/export/SCENE)")
    lammps.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    return front_for("export", scene)(args, scene)
