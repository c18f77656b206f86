"""The ``diskfriction`` command line.

Each subcommand is one module in cli/ with ``register(subparsers)``, which adds its parser and
sets ``run`` (args -> exit code). Subcommands import their physics inside ``run``, so that
importing this module stays light (no numba, no sympy).
"""
from __future__ import annotations

import argparse
import gc
import sys

from diskfriction.cli import (bifurcate_cmd, crosscheck_cmd, export_cmd, map_cmd, prepare_cmd,
                              report_cmd, scene_cmd, simulate_cmd, verify_cmd)
from diskfriction.cli.common import run_command

SUBCOMMANDS = (scene_cmd, bifurcate_cmd, simulate_cmd, verify_cmd, map_cmd, report_cmd, export_cmd,
               crosscheck_cmd, prepare_cmd)


class VersionAction(argparse.Action):
    """--version: prints ``diskfriction VERSION`` and exits; the version is looked up only
    then (diskfriction.__version__)."""

    def __init__(self, option_strings, dest, **kwargs) -> None:
        super().__init__(option_strings, dest, nargs=0, help="print the version and exit")

    def __call__(self, parser, namespace, values, option_string=None) -> None:
        import diskfriction

        print(f"diskfriction {diskfriction.__version__}")
        parser.exit()


class OneLineParser(argparse.ArgumentParser):
    """argparse with usage errors reported as one line on stderr (exit code 2), no usage dump."""

    def error(self, message: str):
        sys.stderr.write(f"{self.prog}: error: {message}\n")
        sys.exit(2)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    parser = OneLineParser(
        prog="diskfriction",
        description="Bifurcation analysis of frictional disks: the chain on a substrate loaded by "
                    "F_x (the paper's scene, scenes/paper.toml) or a 2D packing sheared in "
                    "strain gamma (a scene with geometry = \"packing\", scenes/packing.toml). "
                    "Every command takes either scene unless it says otherwise.")
    parser.add_argument("--version", action=VersionAction)
    subparsers = parser.add_subparsers(metavar="COMMAND", required=True, dest="command")
    for module in SUBCOMMANDS:
        module.register(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line on ``argv`` (default: sys.argv[1:]); returns the exit code.

    Without argv (the program itself, which exits next) every object left is frozen out of
    the garbage collector first: the interpreter's last collections would walk all the run
    made (numba's, sympy's, matplotlib's objects): the README's first command took 0.8-1.4 s
    from its return to its exit, 0.12-0.16 s frozen (docs/notes/chain-performance.md, "The
    first command")."""
    code = run_command(build_parser().parse_args(argv))
    if argv is None:
        gc.freeze()
    return code
