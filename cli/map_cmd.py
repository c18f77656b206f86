"""``diskfriction map [SCENE] --vary KEY=LO:HI:COUNT[:log]|KEY=V1,V2,... [--vary KEY2=...] [--fx A:B]
[--matrix J|M^-1J] [--slide] [--window LO:HI] [--damping D1,D2,... [--causality]]
[--scheduler ADDRESS] [--workers K] [--out DIR]``

A full bifurcate in every cell of a grid of numeric scene keys and, with --slide,
one dynamics run per window between collisions (as verify does): which windows slide, the
lowest sliding load F_slide and mu_eff = F_slide / (N F_y) against the Coulomb limit mu.
On a packing scene every cell prepares its packing and shears it over the scene's strain
(as bifurcate does; --window as bifurcate's): how often its states carry complex pairs, how
fast the fastest grows, its collisions and plastic events; with --damping, the damped study
(studies/damped_study.py): its damped onsets and its plastic events against their precursors at
each drag, pooled over the seeds with confidence intervals; with --causality also the damped
dynamics from every onset, counted per outcome.
Cells run as tasks on dask.distributed (a local cluster of this machine's cores, or
--scheduler ADDRESS), each written to DIR/cells/ the moment it finishes; a rerun resumes.
Writes DIR/map.csv (one row per cell), DIR/map.json and, for one or two keys, DIR/map.png (studies/maps.py,
studies/packing_maps.py, reports/maps.py, reports/packing_maps.py). Raw units on the command
line and in files; a chain's figure uses the paper's.
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from dataclasses import dataclass
from typing import Callable, Optional

from diskfriction.cli.common import (CommandError, add_matrix_argument, add_scene_argument, front_for,
                                     number, output_dir, scene_from_args)
from diskfriction.cli.progress import Progress
from diskfriction.cli.simulate_cmd import SCHEDULER, SINGLE_AMPLITUDE
from diskfriction.words import count, duration

VARY = "KEY=LO:HI:COUNT[:log] | KEY=V1,V2,..."
T_END = 1000.0
"""Default duration of a slide run [raw time], verify's: sigma t_end > ln(1e-4 / 1e-10) = 14
for every pair growing faster than sigma = 0.014 [1 / time], enough for the growth to reach
the substrate's breach (studies/maps.py); the paper's sliding windows grow at 0.02 .. 0.3."""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "map", help="bifurcate (and with --slide, verify) over a grid of scene parameters",
        description=__doc__.split("\n\n", 1)[1])
    add_scene_argument(parser)
    parser.add_argument("--vary", action="append", required=True, metavar=VARY,
                        help="vary a numeric scene key (contacts.mu, disks.N, disks.eps, ...) "
                             "over COUNT values from LO to HI, evenly or, with :log, evenly in "
                             "log, or over the values listed; once per key (map.png draws one "
                             "or two keys)")
    parser.add_argument("--fx", metavar="A:B",
                        help="sweep F_x from A to B in every cell (raw units, A < B; default: "
                             "the scene's F_x range)")
    add_matrix_argument(parser, "matrix whose collisions define the windows")
    parser.add_argument("--slide", action="store_true",
                        help="run the dynamics once per window: which slide, F_slide, mu_eff")
    parser.add_argument("--t-end", type=float, default=None, metavar="T",
                        help=f"with --slide: duration of each run, raw time (default {T_END:g})")
    parser.add_argument("--amplitude", type=float, default=None, metavar="A",
                        help=f"with --slide: perturbation amplitude, raw (default "
                             f"{SINGLE_AMPLITUDE:g}, as verify)")
    parser.add_argument("--scheduler", default=None, metavar="ADDRESS",
                        help="dask scheduler to use instead of a local cluster")
    parser.add_argument("--workers", type=int, default=None, metavar="K",
                        help="worker processes of the local cluster (default: one per core)")
    parser.add_argument("--window", metavar="LO:HI",
                        help="packing scenes: track only the eigenvalues with Re lambda in "
                             "[LO, HI] (raw) by sparse shift-invert, as bifurcate --window")
    parser.add_argument("--damping", metavar="D1,D2,...",
                        help="packing scenes: the damped study at these drags (units of omega_0): "
                             "every cell's damped onsets and plastic events against their "
                             "precursors; writes events.csv, damped.csv, precursors.csv and "
                             "precursors.png (docs/packings-study.md)")
    parser.add_argument("--causality", action="store_true",
                        help="with --damping: run the damped dynamics from every onset of damped "
                             "instability at each drag above 0 and count what they become; "
                             "writes runs.csv (minutes per cell)")
    parser.add_argument("--out", metavar="DIR", help="output directory (default: out/map/SCENE)")
    parser.set_defaults(run=run)


def parse_vary(text: str, geometry: str = "chain"):
    """'KEY=LO:HI:COUNT[:log]' (an even grid) or 'KEY=V1,V2,...' (the values listed, in that
    order, distinct) -> studies.maps.Axis of a `geometry`'s scene key; else a one-line
    CommandError naming the specification (unknown or non-numeric key, malformed numbers, a
    grid grid_values refuses, a value listed twice)."""
    from diskfriction.studies.maps import Axis, grid_values
    from diskfriction.scenes.load import number_keys
    from diskfriction.scenes.schema import SCHEMAS

    def bad(what: str) -> CommandError:
        return CommandError(f"map error: --vary: {what} (got {text!r})")

    key, equals, spec = text.partition("=")
    if not equals:
        raise bad(f"expected {VARY}")
    numeric = number_keys(geometry)
    if key not in numeric:
        kind = "not a numeric scene key" if key in SCHEMAS[geometry] else "no scene key"
        raise bad(f"{key} is {kind} of a {geometry}; a map varies one of {', '.join(numeric)}")
    if ":" not in spec:
        try:
            values = tuple(float(v) for v in spec.split(","))
        except ValueError:
            raise bad(f"expected {VARY} with numbers V1, V2, ...") from None
        if not all(math.isfinite(v) for v in values):
            raise bad("the values listed must be finite numbers")
        if len(set(values)) < len(values):
            raise bad("a value listed twice")
        return Axis(key, values)
    parts = spec.split(":")
    log = parts[3:] == ["log"]
    try:
        if len(parts) - log != 3:
            raise ValueError(len(parts))
        lo, hi, count = float(parts[0]), float(parts[1]), int(parts[2])
    except ValueError:
        raise bad(f"expected {VARY} with numbers LO, HI and an integer COUNT") from None
    try:
        return Axis(key, grid_values(lo, hi, count, log), log)
    except ValueError as error:
        raise bad(str(error)) from None


def grid(scene, texts: list[str]):
    """(axes, cells) of the --vary specifications: distinct keys, every cell a valid scene (a
    bad value is one line naming its --vary and key), else a CommandError."""
    from diskfriction.studies.maps import map_cells
    from diskfriction.scenes.load import SceneError

    axes = [parse_vary(text, scene.geometry) for text in texts]
    keys = [axis.key for axis in axes]
    twice = next((i for i, key in enumerate(keys) if key in keys[:i]), None)
    if twice is not None:
        raise CommandError(f"map error: --vary: {keys[twice]} given twice (got {texts[twice]!r})")
    if "shear.damping" in keys and scene.relaxation != "damped":
        raise CommandError(f"map error: --vary {texts[keys.index('shear.damping')]}: shear.damping acts only "
                           f"where [shear] relaxation = \"damped\" (the scene's is {scene.relaxation!r})")
    try:
        return axes, map_cells(scene, axes, scene.source)
    except SceneError as error:
        spec = texts[keys.index(error.key)]
        raise CommandError(f"map error: --vary {spec}: cell {error.key} = {error.value!r}: "
                           f"{error.what}") from None


@dataclass(frozen=True)
class MapPlan:
    """What a geometry's front (its ``map_plan(args, scene)``) gives the map: the parameters
    every cell runs with (checked), and
    check_cell(cell, at_once): a one-line CommandError for a cell it cannot run;
    kernels(cells, params, progress) -> str: compile what the cells need once, say what each runs;
    cell(scene, params) -> dict: one cell's record (a dask task);
    cell_seconds(scene, params): its rough wall time [s];
    columns: the summary's keys, in the table's order;
    plot(axes, cells, records, path, title): map.png (one or two keys);
    describe(cell, summary) -> str: the line printed for a cell;
    study(out, axes, cells, records) -> names: the files a study writes beside the map (a
    packing's damped study: reports/packing_study.py), None where the map runs none."""

    params: object
    check_cell: Callable
    kernels: Callable
    cell: Callable
    cell_seconds: Callable
    columns: tuple
    plot: Callable
    describe: Callable
    study: Optional[Callable] = None


def run(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    axes, cells = grid(scene, args.vary)
    plan = front_for("map", scene)(args, scene)
    if args.scheduler is not None and not SCHEDULER.match(args.scheduler):
        raise CommandError(f"map error: --scheduler: expected a dask scheduler address "
                           f"[tcp://]HOST:PORT (got {args.scheduler!r})")
    if args.workers is not None:
        number("map", "workers", args.workers, integer=True)
        if args.scheduler is not None:
            raise CommandError(f"map error: --workers: sizes the local cluster; the scheduler "
                               f"has its own workers (got {args.workers!r})")
    from diskfriction.studies.cluster import code_version, local_workers

    at_once = 1 if args.scheduler is not None else min(len(cells), local_workers(args.workers))
    for cell in cells:
        plan.check_cell(cell, at_once)
    out = output_dir("map", args.out, Path("out") / "map" / scene.name)
    args.keeps = ("cells", out / "cells")  # what Ctrl-C leaves to resume from (cli.common)

    from diskfriction.reports.maps import save_map
    from diskfriction.studies.maps import run_map

    progress = Progress("map")
    try:
        # compiled here once, so that the workers load them from the cache
        what = plan.kernels(cells, plan.params, progress)
        progress.stage(f"{count(len(cells), 'cell')}: {what}; "
                       f"{estimate(cells, plan, out, at_once, args.scheduler is not None)}")
        records = run_map(cells, plan.params, out, args.scheduler, args.workers,
                          lambda done, total: progress(done / total, f"{done}/{total} cells"),
                          compute=plan.cell)
        progress.stage(f"writing {out}/map.csv, map.json")
        save_map(out, scene, axes, plan.params, code_version(), cells, records, plan.columns)
        written = ["map.csv", "map.json"]
        if len(axes) <= 2:  # a plane holds two keys; the tables hold every cell of more
            progress.stage(f"plotting {out}/map.png")
            plan.plot(axes, cells, records, out / "map.png",
                      f"{scene.name}: {' x '.join(a.key for a in axes)}, {plan.params.matrix}")
            written.append("map.png")
        if plan.study is not None:
            progress.stage(f"writing the study beside the map in {out}")
            written += plan.study(out, axes, cells, records)
    finally:
        progress.close()
    for cell, record in zip(cells, records):
        print(plan.describe(cell, record["summary"]))
    print(f"wrote {out}/{', '.join(written)} and {out}/cells/"
          + ("" if len(axes) <= 2 else f" (no map.png: it draws one or two keys, not {len(axes)})"))
    return 0


def estimate(cells, plan: MapPlan, out: Path, at_once: int, remote: bool) -> str:
    """The rough wall time of the cells not on disk yet (the plan's cell_seconds), on the
    local cluster's workers (at_once), or per worker of a remote scheduler."""
    from diskfriction.studies.cluster import code_version
    from diskfriction.studies.maps import cell_path

    version = code_version()
    todo = [c for c in cells if not cell_path(out, c.scene, plan.params, version).exists()]
    if not todo:
        return "all on disk"
    seconds = sum(plan.cell_seconds(c.scene, plan.params) for c in todo)
    done = f"{len(cells) - len(todo)} on disk, " if len(todo) < len(cells) else ""
    where = "divided by the scheduler's workers" if remote else f"on {count(at_once, 'worker')}"
    return f"{done}about {duration(seconds / (1 if remote else at_once))} {where} (a rough estimate)"
