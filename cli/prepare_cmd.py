"""``diskfriction prepare [FILE] --out DIR``: prepare a packing scene's packing (
docs/packings.md): packing.npz (every field of models.packing.prepare.Packing, loads back bit for
bit) and packing.json (what it is: N, L, phi, the pressure reached, contacts, rattlers), both
naming the scene (reports/packing_outputs.scene_record); a DIR holding another scene's files is
refused."""
from __future__ import annotations

import argparse
from importlib import resources

from diskfriction.cli.common import front_for, scene_from_args

PACKING_SCENE = resources.files("diskfriction.scenes") / "packing.toml"
"""prepare's scene without FILE: the packaged packing scene."""


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``prepare`` subcommand."""
    parser = subparsers.add_parser(
        "prepare", help="prepare a packing scene's frictionless packing",
        description="Place a packing scene's disks at random from its seed and relax them "
                    "without friction (FIRE) to its target pressure; write packing.npz and "
                    "packing.json. The same scene gives the same packing bit for bit.")
    parser.add_argument("scene", nargs="?", metavar="FILE", default=str(PACKING_SCENE),
                        help="packing scene TOML file, geometry = \"packing\" (default: the "
                             "packaged packing scene, scenes/packing.toml: 256 disks)")
    parser.add_argument("--out", metavar="DIR",
                        help="output directory (default: out/prepare/SCENE); one holding another "
                             "scene's packing is refused")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    return front_for("prepare", scene)(args, scene)
