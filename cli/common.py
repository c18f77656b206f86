"""Helpers shared by the subcommands: the scene argument and the handling of bad input."""
from __future__ import annotations

import argparse
import sys

from scenes.load import SceneError, default_scene_path, load_scene
from scenes.scene import Scene

EXIT_BAD_INPUT = 2  # as argparse exits on a usage error


def add_scene_argument(parser: argparse.ArgumentParser) -> None:
    """Give ``parser`` an optional positional scene FILE (default: the paper scene)."""
    parser.add_argument("scene", nargs="?", metavar="FILE",
                        help="scene TOML file (default: the paper scene, scenes/paper.toml)")


def scene_from_args(args: argparse.Namespace) -> Scene:
    """The scene named by the FILE argument, or the paper scene; raises SceneError."""
    return load_scene(args.scene if args.scene is not None else default_scene_path())


def run_command(args: argparse.Namespace) -> int:
    """Run the chosen subcommand; a SceneError becomes its one line on stderr and exit code 2."""
    try:
        return args.run(args)
    except SceneError as error:
        print(error, file=sys.stderr)
        return EXIT_BAD_INPUT
