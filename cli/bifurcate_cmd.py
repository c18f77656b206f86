"""``diskfriction bifurcate [SCENE] [--fx A:B] [--matrix J|M^-1J] [--detection fast|exhaustive]
[--out DIR] [--json]``, or ``diskfriction bifurcate --problem FILE.py[:NAME] [--p A:B] ...``
for any problem (cli/problem_cmd.py)."""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from diskfriction.cli.common import (EXIT_FAILED, CommandError, add_matrix_argument,
                                     add_scene_argument, bracketed_only, check_memory,
                                     matrix_from_args, number, output_dir, path, scene_from_args)
from diskfriction.cli.progress import Progress
from diskfriction.files import json_text
from diskfriction.words import count
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.scene import NEGATIVE_LOAD


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "bifurcate", help="continue the equilibria (a chain in F_x, a packing in shear strain) "
                          "and locate every eigenvalue collision",
        description="Follow the equilibrium branch with the tangential history carried along, "
                    "store the eigenvalues of the stability matrix, and locate every birth and "
                    "death of a complex pair. A chain scene: from rest through the F_x range; "
                    "writes DIR/branch.npz, DIR/collisions.json and DIR/diagram.png (raw units "
                    "in files, the paper's units in the figure). A packing scene: prepares the "
                    "packing without friction, then shears it quasistatically through the "
                    "scene's [shear] gamma range, passing plastic events (relaxed with friction); "
                    "writes DIR/packing.npz, branch.npz, collisions.json, plastic.json and "
                    "diagram.png together at the end, each naming the scene (raw units; "
                    "docs/packings.md); a rerun resumes after the segments an interrupted one "
                    "kept in DIR/segments/.")
    add_scene_argument(parser)
    parser.add_argument("--fx", metavar="A:B",
                        help="a chain scene: sweep F_x from A to B (raw units); A > B unloads "
                             "after loading to A (default: the scene's F_x range). A packing is "
                             "sheared over its scene's [shear] gamma instead")
    add_matrix_argument(parser, "stability matrix")
    parser.add_argument("--out", metavar="DIR",
                        help="output directory (default: out/bifurcate/SCENE); a packing scene's "
                             "run refuses one holding another scene's results")
    parser.add_argument("--ds-max", type=float, metavar="DS",
                        help="largest arclength step (default: a chain scene's F_x span / 60; "
                             "with --problem the file's options.ds_max, else its p span / 50)")
    parser.add_argument("--detection", default="fast", metavar="fast|exhaustive",
                        help="collision detection: fast (eigenvalue slopes, Hermite "
                             "certification, Newton locator; the default) or exhaustive "
                             "(bisection with full spectra, version 0.1; slow, for checking)")
    parser.add_argument("--workers", type=int, metavar="K",
                        help="processes that scan steps for collisions while the branch goes on "
                             "(default: 2 from 20 disks with rotation, 30 without, on 2 cores or "
                             "more; 0: scan each step before the next)")
    parser.add_argument("--window", metavar="LO:HI",
                        help="track only the eigenvalues with LO <= Re lambda <= HI (the "
                             "diagram's units: lambda / k_n for J; raw for a packing) by sparse "
                             "shift-invert, for chains and packings too large for full spectra; "
                             "collisions are certified and listed in the window only (fast "
                             "detection)")
    parser.add_argument("--spectra", default="auto", metavar="cpu|gpu|auto",
                        help="where dense spectra run: cpu (LAPACK), gpu (CuPy's cuSOLVER; "
                             "scans then run inline), auto (the GPU from n = 1000 where CuPy "
                             "and a CUDA device are present; the default)")
    parser.add_argument("--json", action="store_true", help="print the collision list to stdout")
    parser.add_argument("--problem", metavar="FILE.py[:NAME]",
                        help="continue the BifurcationProblem NAME (default: problem) defined in "
                             "the Python file FILE.py instead of a scene (docs/api.md)")
    parser.add_argument("--switch", metavar="K[:-1]",
                        help="with --problem: follow the second branch through the run's K-th "
                             "branch point (1: the first) toward B instead; :-1 takes its other "
                             "half (docs/api.md, Branch points)")
    parser.add_argument("--p", metavar="A:B",
                        help="with --problem: continue the problem's parameter from A to B "
                             "(default: the problem's p_span)")
    parser.set_defaults(run=run)


def parse_range(text: str, option: str = "fx", nonnegative: bool = True,
                command: str = "bifurcate") -> tuple[float, float]:
    """'A:B' -> (A, B), both finite and different (and >= 0 for F_x); else a one-line
    CommandError naming COMMAND and --OPTION."""
    parts = text.split(":")
    try:
        a, b = (float(p) for p in parts) if len(parts) == 2 else (None, None)
    except ValueError:
        a = b = None
    if a is None or not (math.isfinite(a) and math.isfinite(b)):
        raise CommandError(f"{command} error: --{option}: expected A:B with two numbers (got {text!r})")
    if nonnegative and (a < 0 or b < 0):
        raise CommandError(f"{command} error: --{option}: F_x must be >= 0: {NEGATIVE_LOAD} "
                           f"(got {text!r})")
    if a == b:
        raise CommandError(f"{command} error: --{option}: empty range (got {text!r})")
    return a, b


def parse_window(text: str, command: str = "bifurcate") -> tuple[float, float]:
    """'LO:HI' -> (LO, HI), finite with LO < HI; else a one-line CommandError naming COMMAND."""
    parts = text.split(":")
    try:
        lo, hi = (float(p) for p in parts) if len(parts) == 2 else (None, None)
    except ValueError:
        lo = hi = None
    if lo is None or not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
        raise CommandError(f"{command} error: --window: expected LO:HI with two numbers, LO < HI "
                           f"(got {text!r})")
    return lo, hi


def run(args: argparse.Namespace) -> int:
    """bifurcate with its dense spectra where --spectra says (continuation/spectra/tracking.py)."""
    from diskfriction.continuation.spectra.tracking import NoGpu, SpectraDevice, spectra_on

    names = [device.value for device in SpectraDevice]
    if args.spectra not in names:
        raise CommandError(f"bifurcate error: --spectra: must be {', '.join(names[:-1])} or "
                           f"{names[-1]} (got {args.spectra!r})")
    try:
        with spectra_on(args.spectra):
            return _run(args)
    except NoGpu as err:
        raise CommandError(f"bifurcate error: --spectra gpu: {err}") from None


def _run(args: argparse.Namespace) -> int:
    from diskfriction.continuation.detection.detectors import DETECTORS

    if args.detection not in DETECTORS:
        raise CommandError(f"bifurcate error: --detection: must be {' or '.join(DETECTORS)} "
                           f"(got {args.detection!r})")
    detector = DETECTORS[args.detection]
    if args.workers is not None and args.workers > 0 and not detector.parallel:
        raise CommandError(f"bifurcate error: --workers: scan workers serve the fast detection; "
                           f"--detection {args.detection} scans each step inline (got {args.workers})")
    if args.problem is not None:
        from diskfriction.cli.problem_cmd import run_problem

        return run_problem(args)
    if args.switch is not None:
        raise CommandError(f"bifurcate error: --switch: only with --problem FILE.py (got {args.switch!r})")
    window = parse_window(args.window) if args.window is not None else None
    if window is not None and not detector.window:
        raise CommandError("bifurcate error: --window: needs the fast detection (eigenvalue "
                           f"slopes), not --detection {args.detection}")
    scene = scene_from_args(args)
    if isinstance(scene, PackingScene):
        from diskfriction.cli.packing_cmd import run_packing

        return run_packing(args, scene, window)
    if args.p is not None:
        raise CommandError("bifurcate error: --p: only with --problem FILE.py (a chain scene's load "
                           f"is --fx; got {args.p!r})")
    F_from, F_to = parse_range(args.fx) if args.fx is not None else scene.F_x_range
    if args.ds_max is not None:
        number("bifurcate", "ds-max", args.ds_max)
    if args.workers is not None and args.workers < 0:
        raise CommandError(f"bifurcate error: --workers: must be >= 0 (got {args.workers})")
    matrix = matrix_from_args("bifurcate", args, scene)
    out = output_dir("bifurcate", args.out, Path("out") / "bifurcate" / scene.name)

    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.continuation.detection.collisions import DetectionParams
    from diskfriction.models.chain.equilibria import EquilibriumError
    from diskfriction.continuation.detection.scans import planned_workers
    from diskfriction.continuation.spectra.window import WindowCrowded
    from diskfriction.models.chain.sweep import SweepParams, sweep
    from diskfriction.reports.bifurcation import collision_records, plot_diagram, save_branch
    from diskfriction.symbolic import System

    detection = DetectionParams(mode=args.detection)
    workers = planned_workers(scene.ndof, detection, args.workers, dense=window is None)
    check_memory("bifurcate", scene, 1 + workers, dense=window is None and scene.eps > 0)

    progress = Progress("bifurcate")
    total = F_from + abs(F_to - F_from)  # preparation leg plus the sweep
    done = {"F": 0.0, "last": 0.0}

    def on_point(F_x: float) -> None:
        done["F"] += abs(F_x - done["last"])
        done["last"] = F_x
        progress(done["F"] / total, f"F_x = {F_x:.5f}")

    try:
        system = System.from_scene(scene, progress.part("kernels"))
        progress.stage(f"sweep F_x {F_from:g} -> {F_to:g}" + (f" (from rest via {F_from:g})"
                                                              if F_from else ""))
        try:
            if window is not None:
                from diskfriction.reports.units import PaperUnits

                unit = PaperUnits.of(scene).eigenvalue(matrix)
                window = (window[0] * unit, window[1] * unit)
            params = SweepParams(ds_max=args.ds_max, window=window, detection=detection,
                                 workers=args.workers)
            branch = sweep(system, F_from, F_to, matrix, params, on_point)
        except (EquilibriumError, ContinuationError, WindowCrowded) as error:
            raise CommandError(f"bifurcate error: {scene.source}: {error}", EXIT_FAILED) from None
        if window is not None:
            check_window_covered(branch, args.window, matrix, unit)
        progress.stage(f"writing {out}/branch.npz, collisions.json")
        save_branch(out, branch, scene)
        progress.stage(f"plotting {out}/diagram.png")
        plot_diagram(branch, scene, out / "diagram.png")
    finally:
        progress.close()
    records = collision_records(branch)
    if args.json:
        print(json_text([{k: r[k] for k in ("F_x", "kind", "lambda_re", "lambda_im", "matrix")}
                         for r in records]))
    else:
        print(f"{count(len(branch), 'equilibrium', 'equilibria')}, max residual {branch.residual.max():.1e}, "
              f"{branch.events} contact events split")
        for line in leg_lines(branch, F_to):
            print(f"  {line}")
        if branch.free.any():
            print(f"free rolling modes (disks held by the substrate alone, excluded from the "
                  f"collisions): {branch.free[0]} at F_x = {branch.F_x[0]:.3g}, "
                  f"{branch.free[-1]} at F_x = {branch.F_x[-1]:.3g}")
        print(f"{count(len(records), 'collision')} ({matrix})" + (
            "" if branch.window is None else f" with Re lambda in [{branch.window[0]:.6g}, "
            f"{branch.window[1]:.6g}] (raw; {branch.eigenvalues.shape[1]} eigenvalues tracked "
            "through it and its guard bands, a column each in branch.npz"
            + (f"; it crowded and was widened {count(branch.widenings, 'time')}"
               if branch.widenings else "") + ")") + bracketed_only(records) + ":")
        for r in records:
            unlocated = ("" if r["resolved"] else
                         "  bracketed only: F_x in [{:.10f}, {:.10f}]".format(*r["bracket"]))
            print(f"  {r['kind']:5s}  F_x = {r['F_x']:.10f}  lambda = {r['lambda_re']:.6g}  "
                  f"(lambda/k_n = {r['lambda_re'] / scene.k_n:.5g}){unlocated}")
        print(f"wrote {out}/branch.npz, collisions.json, diagram.png")
    if not branch.status[-1].reached:
        from diskfriction.models.chain.equilibrium import contact_states

        raise CommandError(f"bifurcate error: {scene.source}: the sweep ended at F_x = "
                           f"{branch.F_x[-1]:.6g}, short of {F_to:g}: "
                           f"{branch.status[-1].sentence(len(branch))}; there "
                           f"{contact_states(system, branch.q[-1], branch.xi[-1])}; what it "
                           f"reached is written", EXIT_FAILED)
    return 0


def check_window_covered(branch, given: str, matrix: str, unit: float) -> None:
    """A CommandError (exit 1) when no eigenvalue of the branch ever had its real part in the
    window: there is nothing to report for a band of the spectrum the branch never reached.
    unit: the raw value of one unit of --window (PaperUnits.eigenvalue)."""
    import numpy as np

    lo, hi = branch.window
    lam = branch.eigenvalues.real  # nan where a column holds no eigenvalue near the window
    if ((lam >= lo) & (lam <= hi)).any():
        return
    near = lam[np.isfinite(lam)] / unit
    seen = f"; the guard bands saw {near.min():.4g}:{near.max():.4g}" if near.size else ""
    raise CommandError(f"bifurcate error: --window: no eigenvalue of {matrix} has its real part in "
                       f"the window anywhere on the branch{seen}: nothing to report (got "
                       f"{given!r})", EXIT_FAILED)


def leg_lines(branch, F_to: float) -> list[str]:
    """What each leg of a sweep did, one line each: its direction, the loads it passed through
    (cli.common.path), its points and how it ended."""
    import numpy as np

    lines = []
    for leg, status in zip(sorted(set(branch.leg.tolist())), branch.status):
        rows = np.flatnonzero(branch.leg == leg)
        F = branch.F_x[np.r_[rows[0] - 1, rows] if rows[0] > 0 else rows]  # from where one ended
        what = ("preparation: loading from rest" if leg == 0 else
                ("loading" if F[-1] > F[0] else "unloading"))
        floor = (" (the rest state F_x = 0 is singular: unloading ends where loading started)"
                 if leg == 1 and F_to == 0 and status.reached else "")
        lines.append(f"leg {leg}, {what}: F_x {path(F)}, {count(rows.size, 'equilibrium', 'equilibria')}, "
                     f"{status.sentence(rows.size)}{floor}")
    return lines
