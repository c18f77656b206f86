"""``diskfriction report [SCENE ...] [--out DIR] [--only FIG] [--set KEY=VALUE] [--cache DIR]``."""
from __future__ import annotations

import argparse
from pathlib import Path

from diskfriction.cli.common import (CommandError, chain_scene, check_memory, check_packing,
                                     output_dir)
from diskfriction.scenes.load import default_scene_path, load_scene
from diskfriction.scenes.packing import PackingScene


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
    from diskfriction.reports.builder import build_report, sections_named
    from diskfriction.reports.settings import SettingError, Settings, with_setting

    files = args.scenes or [default_scene_path()]
    loaded = [load_scene(file) for file in files]
    if any(isinstance(scene, PackingScene) for scene in loaded):
        return run_packing_report(args, files, loaded)
    scenes = [chain_scene("report", file, scene) for file, scene in zip(files, loaded)]
    only = tuple(k.strip() for item in args.only or () for k in item.split(",") if k.strip())
    if args.only is not None and not only:
        raise CommandError(f"report error: --only: no section named (got "
                           f"{','.join(args.only)!r})")
    try:
        sections_named(only)
    except ValueError as error:
        raise CommandError(f"report error: --only: {error}") from None
    settings = Settings()
    try:
        for assignment in args.settings:
            settings = with_setting(settings, assignment)
    except SettingError as error:
        raise CommandError(f"report error: {error}") from None
    if args.cache == "":
        raise CommandError("report error: --cache: empty path (got '')")
    for scene in scenes:
        check_memory("report", scene, spectra=1)
    out = output_dir("report", args.out, Path("out/report"))
    from diskfriction.reports.builder import default_cache_dir

    cache = Path(args.cache) if args.cache else default_cache_dir(out)
    args.keeps = ("computations", cache)  # what Ctrl-C leaves to resume from (cli.common)
    log = build_report(scenes, out, only or None, settings, cache)
    computed = sum(e.status == "computed" for e in log)
    failed = sum("failed" in e.status for e in log)
    print(f"wrote {out / 'report.md'} ({len(log)} computations: {computed} computed, "
          f"{len(log) - computed} from the cache, {failed} failed)")
    return 0


def run_packing_report(args: argparse.Namespace, files: list, scenes: list) -> int:
    """report on one packing scene (reports/packing_report.py): shear, two dynamics runs, four
    figures and report.md; the chain's sections, settings and cache do not apply."""
    if len(scenes) > 1:
        raise CommandError(f"report error: {files[0]}: a packing scene is reported alone (got "
                           f"{len(scenes)} scenes)")
    for option, given in (("only", args.only), ("set", args.settings or None),
                          ("cache", args.cache)):
        if given is not None:
            raise CommandError(f"report error: --{option}: the packing report has no sections, "
                               f"settings or cache (got {given!r})")
    from diskfriction.cli.packing_cmd import PLASTIC_EVENTS
    from diskfriction.cli.progress import Progress
    from diskfriction.reports.packing_report import build_packing_report

    scene = scenes[0]
    check_packing("report", scene, strain=scene.gamma_range[1])
    out = output_dir("report", args.out, Path("out/report") / scene.name)
    progress = Progress("report")
    try:
        written = build_packing_report(scene, out, PLASTIC_EVENTS, progress.stage)
    finally:
        progress.close()
    print(f"wrote {out / 'report.md'} and {', '.join(written[1:])}")
    return 0
