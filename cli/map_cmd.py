"""``diskfriction map [SCENE] --vary KEY=LO:HI:COUNT[:log] [--vary KEY2=...] [--fx A:B]
[--matrix J|M^-1J] [--slide] [--window LO:HI] [--scheduler ADDRESS] [--workers K] [--out DIR]``

A full bifurcate in every cell of a grid of one or two numeric scene keys and, with --slide,
one dynamics run per window between collisions (as verify does): which windows slide, the
lowest sliding load F_slide and mu_eff = F_slide / (N F_y) against the Coulomb limit mu.
On a packing scene every cell prepares its packing and shears it over the scene's strain
(as bifurcate does; --window as bifurcate's): how often its states carry complex pairs, how
fast the fastest grows, its collisions and plastic events.
Cells run as tasks on dask.distributed (a local cluster of this machine's cores, or
--scheduler ADDRESS), each written to DIR/cells/ the moment it finishes; a rerun resumes.
Writes DIR/map.csv (one row per cell), DIR/map.json and DIR/map.png (studies/maps.py,
studies/packing_maps.py, reports/maps.py, reports/packing_maps.py). Raw units on the command
line and in files; a chain's figure uses the paper's.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from diskfriction.cli.bifurcate_cmd import parse_range, parse_window
from diskfriction.cli.common import (CommandError, add_matrix_argument, add_scene_argument, check_memory,
                                     number, output_dir, matrix_from_args, scene_from_args)
from diskfriction.cli.progress import Progress
from diskfriction.words import count, duration
from diskfriction.cli.simulate_cmd import SCHEDULER, SINGLE_AMPLITUDE
from diskfriction.cli.packing_cmd import PLASTIC_EVENTS
from diskfriction.scenes.packing import PackingScene

VARY = "KEY=LO:HI:COUNT[:log]"
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
                             "log; give it twice for a map of two keys")
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
    parser.add_argument("--out", metavar="DIR", help="output directory (default: out/map/SCENE)")
    parser.set_defaults(run=run)


def parse_vary(text: str, geometry: str = "chain"):
    """'KEY=LO:HI:COUNT[:log]' -> studies.maps.Axis of a `geometry`'s scene key; else a
    one-line CommandError naming the specification (unknown or non-numeric key, malformed
    numbers, a grid grid_values refuses)."""
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
    """(axes, cells) of the --vary specifications: one or two distinct keys, every cell a
    valid scene (a bad value is one line naming its --vary and key), else a CommandError."""
    from diskfriction.studies.maps import map_cells
    from diskfriction.scenes.load import SceneError

    geometry = "packing" if isinstance(scene, PackingScene) else "chain"
    axes = [parse_vary(text, geometry) for text in texts]
    keys = [axis.key for axis in axes]
    if len(axes) > 2:
        raise CommandError(f"map error: --vary: a map varies one or two keys (got {len(axes)}: "
                           f"{', '.join(keys)})")
    if len(set(keys)) < len(keys):
        raise CommandError(f"map error: --vary: {keys[0]} given twice (got {texts[1]!r})")
    if "shear.damping" in keys and scene.relaxation != "damped":
        raise CommandError(f"map error: --vary {texts[keys.index('shear.damping')]}: shear.damping acts only "
                           f"where [shear] relaxation = \"damped\" (the scene's is {scene.relaxation!r})")
    try:
        return axes, map_cells(scene, axes, scene.source)
    except SceneError as error:
        spec = texts[keys.index(error.key)]
        raise CommandError(f"map error: --vary {spec}: cell {error.key} = {error.value!r}: "
                           f"{error.what}") from None


def run(args: argparse.Namespace) -> int:
    scene = scene_from_args(args)
    packing = isinstance(scene, PackingScene)
    axes, cells = grid(scene, args.vary)
    params = packing_params(args, scene) if packing else chain_params(args, scene)
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
    from diskfriction.models.packing.limits import preparation_problem

    for cell in cells:
        if packing:
            check_memory("map", cell.scene, at_once, dense=params.window is None)
            problem = preparation_problem(cell.scene)  # models/packing/limits.py: what FIRE cannot make
            if problem is not None:
                values = ", ".join(f"{key} = {value!r}" for key, value in cell.values)
                raise CommandError(f"map error: --vary: cell {values}: {problem[0]}: {problem[1]}")
        else:
            check_memory("map", cell.scene, at_once, spectra=at_once if args.slide else 0)
    out = output_dir("map", args.out, Path("out") / "map" / scene.name)
    args.keeps = ("cells", out / "cells")  # what Ctrl-C leaves to resume from (cli.common)

    from diskfriction.reports.maps import plot_map, save_map
    from diskfriction.reports.packing_maps import plot_packing_map
    from diskfriction.studies.maps import COLUMNS, map_cell, run_map
    from diskfriction.studies.packing_maps import PACKING_COLUMNS, packing_cell

    progress = Progress("map")
    try:
        # compiled here once, so that the workers load them from the cache
        what = compile_kernels(cells, params, progress)
        progress.stage(f"{count(len(cells), 'cell')}: {what}; "
                       f"{estimate(cells, params, out, at_once, args.scheduler is not None)}")
        records = run_map(cells, params, out, args.scheduler, args.workers,
                          lambda done, total: progress(done / total, f"{done}/{total} cells"),
                          compute=packing_cell if packing else map_cell)
        progress.stage(f"writing {out}/map.csv, map.json")
        save_map(out, scene, axes, params, code_version(), cells, records,
                 PACKING_COLUMNS if packing else COLUMNS)
        progress.stage(f"plotting {out}/map.png")
        title = f"{scene.name}: {' x '.join(a.key for a in axes)}, {params.matrix}"
        if packing:
            plot_packing_map(axes, cells, records, out / "map.png",
                             f"{title}, gamma 0 -> {scene.gamma_range[1]:g}")
        else:
            plot_map(axes, cells, records, params, out / "map.png", title
                     + (f", runs to t = {params.slide.t_end:g}" if args.slide else ""))
    finally:
        progress.close()
    for cell, record in zip(cells, records):
        print((describe_packing if packing else describe)(cell, record["summary"]))
    print(f"wrote {out}/map.csv, map.json, map.png and {out}/cells/")
    return 0


def chain_params(args: argparse.Namespace, scene):
    """A chain map's studies.maps.MapParams from --fx, --matrix, --slide, --t-end and
    --amplitude (checked: one line, exit 2)."""
    from diskfriction.studies.maps import MapParams, SlideParams

    if args.window is not None:
        raise CommandError(f"map error: --window: for packing scenes only; a chain's cells take "
                           f"full spectra (got {args.window!r})")
    F_from, F_to = parse_range(args.fx, command="map") if args.fx is not None else scene.F_x_range
    if F_from > F_to:
        raise CommandError(f"map error: --fx: a map loads, A < B (got {args.fx!r})")
    for option, value in (("t-end", args.t_end), ("amplitude", args.amplitude)):
        if value is not None and not args.slide:
            raise CommandError(f"map error: --{option}: sets the slide runs; add --slide "
                               f"(got {value!r})")
    t_end = number("map", "t-end", args.t_end if args.t_end is not None else T_END)
    amplitude = number("map", "amplitude",
                       args.amplitude if args.amplitude is not None else SINGLE_AMPLITUDE, zero=True)
    return MapParams(F_from, F_to, str(matrix_from_args("map", args, scene)),
                     SlideParams(t_end, amplitude) if args.slide else None)


NO_DYNAMICS = "a packing map runs no dynamics; `verify` runs them on one scene"
PACKING_REFUSES = {"fx": "a packing's load is its strain: [shear] gamma in the scene",
                   "slide": NO_DYNAMICS, "t_end": NO_DYNAMICS, "amplitude": NO_DYNAMICS}
"""map's options a packing scene does not take, and why."""


def packing_params(args: argparse.Namespace, scene):
    """A packing map's studies.packing_maps.PackingMapParams from --matrix and --window
    (checked: one line, exit 2); the chain's options are refused (PACKING_REFUSES)."""
    from diskfriction.studies.packing_maps import PackingMapParams

    for option, why in PACKING_REFUSES.items():
        if getattr(args, option) not in (None, False):
            flag = "--" + option.replace("_", "-")
            raise CommandError(f"map error: {flag}: {why} (got {getattr(args, option)!r})")
    window = parse_window(args.window, "map") if args.window is not None else None
    return PackingMapParams(str(matrix_from_args("map", args, scene)), window, PLASTIC_EVENTS)


def compile_kernels(cells, params, progress: Progress) -> str:
    """Generate and compile the kernels every cell needs (a packing cell's effects may differ
    with mu: mu = 0 has no tangential law), and say what each cell runs."""
    if isinstance(cells[0].scene, PackingScene):
        from diskfriction.symbolic.kernels import load_packing_kernels

        for effects in dict.fromkeys(c.scene.resolved_effects for c in cells):
            load_packing_kernels(effects, progress.part("kernels"))
        g1 = cells[0].scene.gamma_range[1]
        inside = "" if params.window is None else f", Re lambda in {params.window[0]:g}:{params.window[1]:g}"
        return f"prepare and shear gamma 0 -> {g1:g} ({params.matrix}{inside})"
    from diskfriction.dynamics.stepper import load_stepper
    from diskfriction.symbolic import System

    system = System.from_scene(cells[0].scene, progress.part("kernels"))
    if params.slide is not None:
        load_stepper(system.kernels, progress.part("stepper"))
    return (f"bifurcate F_x {params.F_from:g} -> {params.F_to:g} ({params.matrix})"
            + (f", one run per window to t = {params.slide.t_end:g}" if params.slide else ""))


def estimate(cells, params, out: Path, at_once: int, remote: bool) -> str:
    """The rough wall time of the cells not on disk yet (studies.maps.cell_seconds, a packing's
    studies.packing_maps.packing_cell_seconds), on the
    local cluster's workers (at_once), or per worker of a remote scheduler."""
    from diskfriction.studies.cluster import code_version
    from diskfriction.studies.maps import cell_path, cell_seconds
    from diskfriction.studies.packing_maps import packing_cell_seconds

    version = code_version()
    todo = [c for c in cells if not cell_path(out, c.scene, params, version).exists()]
    if not todo:
        return "all on disk"
    cost = packing_cell_seconds if isinstance(todo[0].scene, PackingScene) else cell_seconds
    seconds = sum(cost(c.scene, params) for c in todo)
    done = f"{len(cells) - len(todo)} on disk, " if len(todo) < len(cells) else ""
    where = "divided by the scheduler's workers" if remote else f"on {count(at_once, 'worker')}"
    return f"{done}about {duration(seconds / (1 if remote else at_once))} {where} (a rough estimate)"


def describe(cell, s: dict) -> str:
    """One printed line per cell: its values, status, collisions, F_slide and mu_eff, or why
    it failed or ended (raw units)."""
    values = ", ".join(f"{key} = {value:g}" for key, value in cell.values)
    if s["status"] == "failed":
        return f"{values}: failed: {s['reason']}"
    line = f"{values}: {s['status']}, {count(s['collisions'], 'collision')}, {count(s['windows'], 'window')}"
    if s["runs"] is not None:
        lo = "the first run" if s["F_slide_lo"] is None else f"stuck at {s['F_slide_lo']:.5g}"
        line += (f", no run slid (of {s['runs']})" if s["F_slide"] is None else
                 f", F_slide = {s['F_slide']:.5g} ({lo}), mu_eff = {s['mu_eff']:.4g}")
    return line + (f"; {s['reason']}" if s["reason"] else "")


def describe_packing(cell, s: dict) -> str:
    """One printed line per packing cell: its values, status, states, how many carry complex
    pairs, the fastest growth rate, collisions and plastic events, or why it failed or ended."""
    values = ", ".join(f"{key} = {value:g}" for key, value in cell.values)
    if s["status"] == "failed":
        return f"{values}: failed: {s['reason']}"
    fastest = ("" if s["sigma_max"] is None else
               f", sigma_max = {s['sigma_max']:.4g} ({s['sigma_max'] / s['omega_c']:.3g} omega_c)")
    line = (f"{values}: {s['status']} to gamma = {s['gamma_end']:.4g}, "
            f"{count(s['states'], 'state')}, complex pairs at {100 * s['complex_fraction']:.0f} %"
            f"{fastest}, {count(s['collisions'], 'collision')}, "
            f"{count(s['plastic_events'], 'plastic event')}")
    return line + (f"; {s['reason']}" if s["reason"] else "")
