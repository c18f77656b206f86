"""``diskfriction verify [SCENE]``: which complex pairs make the chain slide.

From the branch (0 .. the scene's F_x range end, the scene's or --matrix's stability matrix),
run the dynamics at the midpoint of every complex window and every all-real interval between
collisions (studies/verify.py) and tabulate: window, F_x, sigma predicted (M^-1 J), sigma
measured, max M, slid ("not resolved" where the run's energy budget did not close). Writes
DIR/verify.json, DIR/verify.md and DIR/verify.png (the Im lambda diagram with each window
shaded by whether its run slid, stayed or is not resolved, over the growth rate measured
against the predicted one per window).

On a packing scene: shear over the scene's strain range, then run the dynamics from up to 8
states with complex pairs (along the fastest pair's eigenvector) and 2 with every eigenvalue
real (random velocities); tabulate the growth rate measured against the spectrum's, whether
contacts slid, and what the run's end relaxes to at rest (rearranged, slipped or came back).
Writes DIR/verify.json and DIR/verify.md (docs/packings.md).
"""
from __future__ import annotations

import argparse
from pathlib import Path

from diskfriction.cli.common import (EXIT_FAILED, CommandError, add_matrix_argument, add_scene_argument,
                                     check_memory, number, output_dir, matrix_from_args, scene_from_args)
from diskfriction.cli.progress import Progress
from diskfriction.cli.simulate_cmd import SINGLE_AMPLITUDE


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "verify", help="run the dynamics in every complex window and real interval",
        description=__doc__.split("\n\n", 1)[1])
    add_scene_argument(parser)
    add_matrix_argument(parser, "matrix defining the windows")
    parser.add_argument("--t-end", type=float, default=1000.0, metavar="T", help="duration of each run, raw time")
    parser.add_argument("--amplitude", type=float, default=SINGLE_AMPLITUDE, metavar="A",
                        help="perturbation amplitude, raw (default 1e-10: room for the growth fit)")
    parser.add_argument("--out", metavar="DIR", help="output directory (default: out/verify/SCENE)")
    parser.set_defaults(run=run)


def run(args: argparse.Namespace) -> int:
    from diskfriction.scenes.packing import PackingScene

    scene = scene_from_args(args)
    if isinstance(scene, PackingScene):
        from diskfriction.cli.packing_cmd import run_packing_verify

        return run_packing_verify(args, scene)
    number("verify", "t-end", args.t_end)
    number("verify", "amplitude", args.amplitude, zero=True)
    matrix = matrix_from_args("verify", args, scene)
    out = output_dir("verify", args.out, Path("out") / "verify" / scene.name)
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.continuation.detection.scans import planned_workers

    check_memory("verify", scene, 1 + planned_workers(scene.ndof, DetectionParams()), spectra=1)

    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.models.chain.equilibria import EquilibriumError
    from diskfriction.dynamics.stepper import load_stepper
    from diskfriction.studies.verify import verify_windows
    from diskfriction.files import save_json, save_text
    from diskfriction.reports.verify import plot_verify
    from diskfriction.symbolic import System

    progress = Progress("verify")
    try:
        load_stepper(System.from_scene(scene, progress.part("kernels")).kernels,
                     progress.part("stepper"))
        try:
            branch, rows = verify_windows(scene, matrix, args.t_end, args.amplitude,
                                          progress.part("windows"))
        except (EquilibriumError, ContinuationError) as error:  # the branch cannot start
            raise CommandError(f"verify error: {scene.source}: {error}", EXIT_FAILED) from None
        table = format_table(rows, matrix)
        progress.stage(f"writing {out}/verify.json, verify.md, verify.png")
        save_json(out / "verify.json", rows)
        save_text(out / "verify.md", table)
        plot_verify(branch, rows, scene, args.t_end, out / "verify.png")
    finally:
        progress.close()
    print(table, end="")
    print(f"wrote {out}/verify.json, verify.md, verify.png")
    return 0


def format_table(rows: list[dict], matrix: str) -> str:
    """Markdown table of the verify rows (raw units); slid reads yes, no or not resolved."""
    from diskfriction.reports.figures import slid_word

    fmt = lambda v: "-" if v is None else f"{v:.4g}"
    lines = [f"Windows of {matrix}; sigma from M^-1 J (raw 1/time); M in raw length^2.", "",
             "| window F_x | pairs | F_x | sigma predicted | sigma measured | max M | slid |",
             "|---|---|---|---|---|---|---|"]
    for r in rows:
        a, b = r["window"]
        lines.append(f"| {a:.5f} .. {b:.5f} | {r['complex_pairs']} | {r['F_x']:.5f} | "
                     f"{fmt(r['sigma_predicted'])} | {fmt(r['sigma_measured'])} | {fmt(r['M_max'])} | "
                     f"{slid_word(r['slid'])} |")
    return "\n".join(lines) + "\n"
