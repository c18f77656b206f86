"""``diskfriction export lammps [SCENE] [--fx F] [--start rest|branch] [--out DIR]`` (a chain)
``diskfriction export lammps PACKING.toml [--rate R] [--damping ETA] [--out DIR]`` (a packing)

Writes DIR/scene.data and DIR/in.scene: a chain scene as LAMMPS input (peers/lammps_deck.py),
from the branch point at F_x with zero histories (or the rest state with F_x switched on), saying
which on stdout and in the deck; a packing scene's prepared packing with a deck that shears it by
damped MD at the strain rate R to its [shear] gamma (peers/packing_deck.py). What LAMMPS cannot
represent is refused with one line, exit 2, and so are the options of the other geometry.
"""
from __future__ import annotations

import argparse

from diskfriction.cli.common import (CommandError, add_scene_argument, code_targets, front_for,
                                     number, scene_from_args)

STARTS = ("branch", "rest")
DEFAULT_STEPS, DEFAULT_EVERY = 1000, 10
"""The deck's default run (lmp -var steps N -var every K change it)."""
CHAIN_DEFAULTS = {"fx": 0.0, "start": "branch"}
"""A chain scene's options and their defaults."""
NOT_FOR_PACKINGS = {"fx": "a packing's load is its strain: the deck shears it at --rate to "
                          "[shear] gamma of the scene",
                    "start": "a packing's deck starts from its prepared packing at gamma = 0"}
NOT_FOR_CHAINS = "a chain's deck has no shear: --rate and --damping are for packing scenes"
DEFAULT_RATE = 1e-5
"""A packing deck's strain rate unless --rate is given [1 / time]."""


def add_start_argument(parser: argparse.ArgumentParser, default: str | None,
                       shown: str | None = None) -> None:
    """--start rest|branch with `default`; the help names `shown` (default: `default`)."""
    parser.add_argument("--start", choices=STARTS, default=default,
                        help="branch: the equilibrium on the branch from rest at F_x, with zero "
                             "tangential histories (LAMMPS cannot be given any); rest: the F_x = 0 "
                             f"equilibrium with F_x switched on at t = 0 (default: "
                             f"{shown or default})")


def register(subparsers: argparse._SubParsersAction) -> None:
    lammps = code_targets(subparsers, "export", "write a scene as input for another code").add_parser(
        "lammps", help="a LAMMPS data file and input deck",
        description="Write DIR/scene.data and DIR/in.scene, a LAMMPS data file and input deck "
                    "reproducing the scene (docs/lammps.md): Hertz and linear Mindlin contacts "
                    "mapped with R_eff, no damping, nve/sphere disc, enforce2d, addforce; every "
                    "number to 17 digits. Refuses (one line, exit 2) what LAMMPS cannot "
                    "represent: the smoothed Mindlin law, c other than 1/2 or 2/5, N = 2. "
                    "A packing scene: its prepared packing in a tilted periodic box and a deck "
                    "shearing it by damped MD (fix deform xy erate R remap v, gamma = R t) to "
                    "[shear] gamma, writing the contact stress to stress.txt; the smoothed "
                    "Mindlin law is written as the linear one with a sharp cap, and said so.")
    add_scene_argument(lammps)
    lammps.add_argument("--fx", type=float, default=None, metavar="F",
                        help="a chain: load on disk 1, raw force (default 0: the rest state)")
    add_start_argument(lammps, None, f"{CHAIN_DEFAULTS['start']}, a chain")
    lammps.add_argument("--rate", type=float, default=None, metavar="R",
                        help=f"a packing: the strain rate of the shear, gamma = R t, raw 1 / time "
                             f"(default {DEFAULT_RATE:g})")
    lammps.add_argument("--damping", type=float, default=None, metavar="ETA",
                        help="a packing: the drag rate in units of omega_0, as [shear] damping "
                             "(default: the scene's damping)")
    lammps.add_argument("--out", metavar="DIR", help="output directory (default: out/export/SCENE)")
    lammps.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """The scene's export, once the options that do not apply to its geometry are refused (one
    line, exit 2) and the others checked and given their defaults."""
    scene = scene_from_args(args)
    front = front_for("export", scene)
    if scene.geometry == "packing":
        for option, why in NOT_FOR_PACKINGS.items():
            if getattr(args, option) is not None:
                raise CommandError(f"export error: --{option}: {why} (got {getattr(args, option)!r})")
        args.rate = number("export", "rate", DEFAULT_RATE if args.rate is None else args.rate)
        if args.damping is not None:
            number("export", "damping", args.damping)
    else:
        for option in ("rate", "damping"):
            if getattr(args, option) is not None:
                raise CommandError(f"export error: --{option}: {NOT_FOR_CHAINS} (got "
                                   f"{getattr(args, option)!r})")
        for option, default in CHAIN_DEFAULTS.items():
            if getattr(args, option) is None:
                setattr(args, option, default)
    return front(args, scene)
