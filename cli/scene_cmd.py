"""``diskfriction scene [FILE]``: print the resolved scene as TOML with derived quantities."""
from __future__ import annotations

import argparse

from diskfriction.cli.common import add_scene_argument, scene_from_args
from diskfriction.scenes.load import format_scene


def register(subparsers: argparse._SubParsersAction) -> None:
    """Add the ``scene`` subcommand."""
    parser = subparsers.add_parser(
        "scene", help="print a scene resolved against the defaults",
        description="Validate a scene file and print it with every key resolved, "
                    "followed by its derived quantities as comments.")
    add_scene_argument(parser)
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    """Print the resolved scene; exit code 0."""
    print(format_scene(scene_from_args(args)), end="")
    return 0
