"""``diskfriction report [SCENE ...] [--out DIR] [--only FIG] [--set KEY=VALUE] [--cache DIR]``."""
from __future__ import annotations

import argparse

from diskfriction.cli.common import CommandError, front_for
from diskfriction.scenes.load import default_scene_path, load_scene


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "report", help="build the report: the paper's figures, paper vs ours, readings, accuracy",
        description="Compute what each figure and table needs (cached on disk by scene, "
                    "parameters and code version; a rebuild recomputes only what changed) and "
                    "write DIR/report.md with PNG figures in the paper's units. One progress "
                    "line per computation. Details: docs/report.md.")
    parser.add_argument("scenes", nargs="*", metavar="SCENE",
                        help="scene TOML files (default: the paper scene, scenes/paper.toml)")
    parser.add_argument("--out", metavar="DIR",
                        help="output directory (default: out/report)")
    parser.add_argument("--only", metavar="FIG", action="append",
                        help="build only these sections (fig2, fig3, ..., paper, readings, "
                             "accuracy); repeat or separate by commas")
    parser.add_argument("--set", metavar="KEY=VALUE", action="append", default=[],
                        dest="settings", help="change a setting (reports/settings.py), e.g. "
                                              "--set t_end=500 or --set loads=0.03,0.083")
    parser.add_argument("--cache", metavar="DIR",
                        help="cache directory (default: $DISKFRICTION_CACHE/report, else DIR/.cache)")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    files = args.scenes or [default_scene_path()]
    scenes = [load_scene(file) for file in files]
    other = next((s for s in scenes if s.geometry != scenes[0].geometry), None)
    if other is not None:
        raise CommandError(f"report error: {other.source}: geometry = \"{other.geometry}\": a "
                           f"report takes scenes of one geometry (the first is a "
                           f"{scenes[0].geometry})")
    return front_for("report", scenes[0])(args, files, scenes)
