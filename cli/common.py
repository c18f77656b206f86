"""Helpers shared by the subcommands: the scene argument and the handling of bad input."""
from __future__ import annotations

import argparse
import sys

from diskfriction.scenes.load import SceneError, default_scene_path, load_scene
from diskfriction.scenes.scene import Scene

EXIT_BAD_INPUT = 2  # as argparse exits on a usage error
EXIT_FAILED = 1  # the computation itself failed (no equilibrium, ...)
EXIT_INTERRUPTED = 130  # as a shell reports SIGINT


class CommandError(Exception):
    """One line for stderr, ``COMMAND error: WHAT``, and the exit code it ends with."""

    def __init__(self, line: str, code: int = EXIT_BAD_INPUT) -> None:
        super().__init__(line)
        self.code = code


def add_scene_argument(parser: argparse.ArgumentParser) -> None:
    """Give ``parser`` an optional positional scene FILE (default: the paper scene)."""
    parser.add_argument("scene", nargs="?", metavar="FILE",
                        help="scene TOML file (default: the paper scene, scenes/paper.toml)")


def scene_from_args(args: argparse.Namespace) -> Scene:
    """The scene named by the FILE argument, or the paper scene; raises SceneError."""
    return load_scene(args.scene if args.scene is not None else default_scene_path())


def run_command(args: argparse.Namespace) -> int:
    """Run the chosen subcommand; a SceneError or CommandError becomes its one line on stderr
    and its exit code (2 for bad input)."""
    try:
        return args.run(args)
    except SceneError as error:
        print(error, file=sys.stderr)
        return EXIT_BAD_INPUT
    except CommandError as error:
        print(error, file=sys.stderr)
        return error.code
    except KeyboardInterrupt:
        print("interrupted: results written so far are kept; rerun to resume", file=sys.stderr)
        return EXIT_INTERRUPTED
