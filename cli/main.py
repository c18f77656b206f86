"""The ``diskfriction`` command line.

Each subcommand is one module in cli/ with ``register(subparsers)``, which adds its parser and
sets ``run`` (args -> exit code). Subcommands import their physics inside ``run``, so that
importing this module stays light (no numba, no sympy).
"""
from __future__ import annotations

import argparse

from cli import bifurcate_cmd, scene_cmd
from cli.common import run_command

SUBCOMMANDS = (scene_cmd, bifurcate_cmd)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    parser = argparse.ArgumentParser(
        prog="diskfriction",
        description="Bifurcation analysis of frictional disks on a substrate.")
    subparsers = parser.add_subparsers(metavar="COMMAND", required=True)
    for module in SUBCOMMANDS:
        module.register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line on ``argv`` (default: sys.argv[1:]); returns the exit code."""
    return run_command(build_parser().parse_args(argv))
