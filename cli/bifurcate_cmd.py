"""``diskfriction bifurcate [SCENE] [--fx A:B] [--matrix J|M^-1J] [--detection fast|exhaustive]
[--spectra none|sample:DGAMMA|full] [--window LO:HI] [--damping D1,D2,... [--dashpots]]
[--device cpu|gpu|auto] [--out DIR] [--json]``, or ``diskfriction bifurcate --problem
FILE.py[:NAME] [--p A:B] ...`` for any problem (cli/problem_cmd.py)."""
from __future__ import annotations

import argparse
import math

from diskfriction.cli.common import (CommandError, add_matrix_argument, add_scene_argument,
                                     front_for, scene_from_args)
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
    parser.add_argument("--spectra", metavar="none|sample:DGAMMA|full",
                        help="a packing scene: what the shear computes of the spectrum: none "
                             "(the equilibria, contact and plastic events, stress), "
                             "sample:DGAMMA (the spectrum at the strains k DGAMMA, or its "
                             "--window; no collision located), full (every collision, in the "
                             "--window if one) (default: the scene's [stability] spectra, auto: "
                             "chosen from N). A chain's sweep is always full")
    parser.add_argument("--damping", metavar="D1,D2,...",
                        help="a packing scene with the matrix M^-1J: its damped stability at "
                             "each drag D (units of omega_0, each >= 0): with spectra full the "
                             "onsets and ends of damped instability located along the shear, with "
                             "sample:DGAMMA the samples' damped growth rates (contact dashpots "
                             "instead of the drag: --dashpots); writes "
                             "DIR/damped.json and precursors.csv (the plastic events against "
                             "their precursors) with the other outputs (docs/packings.md, "
                             "Damped stability)")
    parser.add_argument("--dashpots", action="store_true",
                        help="with --damping: each D is the rate D omega_0 of dashpots on the "
                             "contacts' relative velocities (normal, and tangential at half the "
                             "rate, as LAMMPS's gran/hooke), not a drag on every disk; their "
                             "damped modes are solved at every accepted state, with any --spectra "
                             "and --matrix, and the onsets and ends located are the states' (the "
                             "first mode to grow, the last to recover)")
    parser.add_argument("--device", default="auto", metavar="cpu|gpu|auto",
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


def parse_drags(text: str, command: str = "bifurcate") -> tuple[float, ...]:
    """'D1,D2,...' -> (D1, D2, ...): drags in units of omega_0, at least one, each a finite
    number >= 0 and given once; else a one-line CommandError naming COMMAND and --damping."""
    try:
        drags = tuple(float(part) for part in text.split(","))
    except ValueError:
        drags = ()
    if not drags or not all(math.isfinite(d) and d >= 0 for d in drags):
        raise CommandError(f"{command} error: --damping: expected D1,D2,... with numbers >= 0, "
                           f"the drags in units of omega_0 (got {text!r})")
    if len(set(drags)) < len(drags):
        raise CommandError(f"{command} error: --damping: each drag once (got {text!r})")
    return drags


def run(args: argparse.Namespace) -> int:
    """bifurcate with its dense spectra where --device says (continuation/spectra/tracking.py)."""
    from diskfriction.continuation.spectra.tracking import NoGpu, SpectraDevice, spectra_on

    names = [device.value for device in SpectraDevice]
    if args.device not in names:
        raise CommandError(f"bifurcate error: --device: must be {', '.join(names[:-1])} or "
                           f"{names[-1]} (got {args.device!r})")
    try:
        with spectra_on(args.device):
            return _run(args)
    except NoGpu as err:
        raise CommandError(f"bifurcate error: --device gpu: {err}") from None


def _run(args: argparse.Namespace) -> int:
    from diskfriction.continuation.detection.detectors import DETECTORS

    if args.detection not in DETECTORS:
        raise CommandError(f"bifurcate error: --detection: must be {' or '.join(DETECTORS)} "
                           f"(got {args.detection!r})")
    detector = DETECTORS[args.detection]
    if args.workers is not None and args.workers > 0 and not detector.parallel:
        raise CommandError(f"bifurcate error: --workers: scan workers serve the fast detection; "
                           f"--detection {args.detection} scans each step inline (got {args.workers})")
    if args.dashpots and args.damping is None:
        raise CommandError("bifurcate error: --dashpots: only with --damping D1,D2,... (the "
                           "dashpots' rates, in units of omega_0)")
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
    return front_for("bifurcate", scene)(args, scene, window)
