"""The ``diskfriction`` command line.

Each subcommand is one module in cli/ with ``register(subparsers)``, which adds its parser and
sets ``run`` (args -> exit code). Subcommands import their physics inside ``run``, so that
importing this module stays light (no numba, no sympy).
"""
from __future__ import annotations

import argparse
import sys

from diskfriction import __version__
from diskfriction.cli import bifurcate_cmd, report_cmd, scene_cmd, simulate_cmd, verify_cmd
from diskfriction.cli.common import run_command

SUBCOMMANDS = (scene_cmd, bifurcate_cmd, simulate_cmd, verify_cmd, report_cmd)


class OneLineParser(argparse.ArgumentParser):
    """argparse with usage errors reported as one line on stderr (exit code 2), no usage dump."""

    def error(self, message: str):
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        sys.exit(2)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    parser = OneLineParser(
        prog="diskfriction",
        description="Bifurcation analysis of frictional disks on a substrate.")
    parser.add_argument("--version", action="version", version=f"diskfriction {__version__}")
    subparsers = parser.add_subparsers(metavar="COMMAND", required=True)
    for module in SUBCOMMANDS:
        module.register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line on ``argv`` (default: sys.argv[1:]); returns the exit code."""
    return run_command(build_parser().parse_args(argv))
