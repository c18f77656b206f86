"""``diskfriction bifurcate --problem FILE.py[:NAME] [--p A:B]``: a problem from the user's file.

FILE.py is the user's own code: it is imported as a module (its folder first on sys.path, as
`python FILE.py` would have it), never evaluated from a string of a scene. NAME (default
`problem`) must be a continuation.BifurcationProblem. Everything that can be wrong with the
file is one line naming it, exit 2, before anything is computed: no such file, not a .py
file, an exception or syntax error while importing (with its line), no object NAME, an object
of another type, a parameter name that would clash with the outputs' keys, functions that
raise or return arrays of the wrong shape or non-finite values at the start. Warnings raised
while importing (e.g. derivatives computed by differences) are one line each.
"""
from __future__ import annotations

import argparse
import hashlib
import importlib.util
import sys
import traceback
import warnings
from dataclasses import replace
from pathlib import Path

from diskfriction.cli.common import EXIT_FAILED, CommandError, number, output_dir, path
from diskfriction.cli.progress import Progress
from diskfriction.words import count
from diskfriction.files import warn

DEFAULT_NAME = "problem"
SHOWN_WARNINGS = 5
"""Warnings of the run printed at most (the detector may warn once per retried location)."""


def split_target(text: str) -> tuple[Path, str]:
    """'FILE.py[:NAME]' -> (FILE.py, NAME or 'problem')."""
    path, sep, name = text.rpartition(":")
    if sep and name.isidentifier() and path:
        return Path(path), name
    return Path(text), DEFAULT_NAME


def _fail(path: Path, what: str) -> CommandError:
    return CommandError(f"bifurcate error: {path}: {what}")


def _error_line(path: Path, error: BaseException) -> str:
    """'ExcType: message (line N)', the line the last frame in `path` was at."""
    if isinstance(error, SyntaxError):
        return f"SyntaxError: {error.msg} (line {error.lineno})"
    frames = [f for f in traceback.extract_tb(error.__traceback__)
              if Path(f.filename).resolve() == path.resolve()]
    where = f" (line {frames[-1].lineno})" if frames else ""
    message = (str(error).splitlines() or [""])[0]
    return f"{type(error).__name__}: {message}{where}"


def import_file(path: Path):
    """The module of the user's file `path`, imported under a name of its own; a CommandError
    (one line, exit 2) if it is missing, not .py, or raises while importing. Warnings it
    raises are printed, one line each, but the DerivativeWarnings of its problems: only the
    problem that runs says its own (run_problem)."""
    if not path.is_file():
        raise _fail(path, "no such file")
    if path.suffix != ".py":
        raise _fail(path, "not a Python file (.py)")
    name = f"diskfriction_user_{hashlib.sha256(str(path.resolve()).encode()).hexdigest()[:12]}"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # as an import does: dataclasses and pickle look modules up
    sys.path.insert(0, str(path.resolve().parent))
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            spec.loader.exec_module(module)
    except BaseException as error:  # noqa: BLE001 - SystemExit too: the user's code may do anything
        del sys.modules[name]
        if isinstance(error, KeyboardInterrupt):
            raise
        raise _fail(path, f"failed to import: {_error_line(path, error)}") from None
    finally:
        sys.path.remove(str(path.resolve().parent))
    from diskfriction.continuation.stepping.differences import DerivativeWarning

    for w in caught:  # a problem's derivative warning is said for the one that runs (run_problem)
        if not issubclass(w.category, DerivativeWarning):
            warn(f"{path}: {w.message}")
    return module


def load_problem(text: str):
    """(path, name, BifurcationProblem) from 'FILE.py[:NAME]'; a CommandError otherwise."""
    from diskfriction.continuation.api import BifurcationProblem

    path, name = split_target(text)
    module = import_file(path)
    if not hasattr(module, name):
        found = [k for k, v in vars(module).items() if isinstance(v, BifurcationProblem)]
        hint = f"; it defines {', '.join(found)}" if found else "; it defines no BifurcationProblem"
        raise _fail(path, f"no object named {name!r}{hint}")
    spec = getattr(module, name)
    if not isinstance(spec, BifurcationProblem):
        raise _fail(path, f"{name} is a {type(spec).__name__}, not a "
                          "diskfriction.continuation.BifurcationProblem")
    return path, name, spec


def run_problem(args: argparse.Namespace) -> int:
    """The --problem form of `bifurcate` (module docstring); exit 0 if the branch reached the
    end of the span, 1 if it stopped before (what was reached is written and said)."""
    given = [option for option, value in (("SCENE", args.scene), ("--fx", args.fx),
                                          ("--matrix", args.matrix), ("--window", args.window),
                                          ("--spectra", args.spectra), ("--damping", args.damping))
             if value is not None]
    if given:
        raise CommandError(f"bifurcate error: --problem: takes no {', '.join(given)} "
                           "(the problem file defines the equations and the matrix, whose whole "
                           "spectrum is tracked)")
    from diskfriction.cli.bifurcate_cmd import parse_range

    span = parse_range(args.p, "p", nonnegative=False) if args.p is not None else None
    switch = parse_switch(args.switch) if args.switch is not None else None
    if args.ds_max is not None:
        number("bifurcate", "ds-max", args.ds_max)
    path, name, spec = load_problem(args.problem)
    label = f"{path}:{name}"
    from diskfriction.continuation.stepping.differences import differenced

    if (line := differenced(spec.problem)) is not None:
        warn(f"{label}: {line}")
    if span is None and spec.p_span is None:
        raise CommandError(f"bifurcate error: --p: needed, {label} has no p_span")
    span = span or spec.p_span
    from diskfriction.reports.problem import RESERVED

    if spec.parameter in RESERVED:
        raise _fail(path, f"{name}: parameter name {spec.parameter!r} clashes with the outputs' "
                          f"keys ({', '.join(sorted(RESERVED))})")
    stem = path.stem if name == DEFAULT_NAME else f"{path.stem}-{name}"
    out = output_dir("bifurcate", args.out, Path("out") / "bifurcate" / stem)
    options = replace(spec.options, detection=replace(spec.options.detection, mode=args.detection),
                      workers=spec.options.workers if args.workers is None else args.workers,
                      ds_max=args.ds_max or spec.options.ds_max)
    return _continue(spec, label, span, options, out, args.json, switch)


def parse_switch(text: str) -> tuple[int, int]:
    """'K' or 'K:-1' -> (K - 1, side), K >= 1; else a one-line CommandError."""
    number_, _, side = text.partition(":")
    try:
        k, side = int(number_), int(side or 1)
    except ValueError:
        k = side = 0
    if k < 1 or side not in (1, -1):
        raise CommandError(f"bifurcate error: --switch: expected K or K:-1, K >= 1 the branch "
                           f"point's number (got {text!r})")
    return k - 1, side


def _continue(spec, label: str, span, options, out: Path, as_json: bool,
              switch: tuple[int, int] | None = None) -> int:
    """Check the problem at the start, continue it (with `switch`, (k, side): then the second
    branch through its branch point k, switch_branch), write and print the results."""
    from diskfriction.files import json_text

    from diskfriction.continuation.api import ProblemError, check_problem, solve_branch
    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.models.chain.memory import sweep_bytes
    from diskfriction.memory import NotEnoughMemory, require_memory
    from diskfriction.continuation.records import brief
    from diskfriction.reports.problem import collision_json, plot_problem_diagram, save_outputs

    a, b = span
    try:
        u0 = check_problem(spec.problem, spec.start(a), a)
        n = u0.size
        require_memory(sweep_bytes(n), f"{label}: a branch of {n} x {n} dense matrices")
    except (ProblemError, NotEnoughMemory) as error:
        raise CommandError(f"bifurcate error: {label}: {error}") from None
    progress = Progress("bifurcate")
    reached = {"p": a}

    def on_point(k, p, u, eigenvalues) -> None:
        reached["p"] = p
        progress(abs(p - a) / abs(b - a), f"{spec.parameter} = {p:.6g}")

    try:
        progress.stage(f"continuation {spec.parameter} {a:g} -> {b:g}")
        try:
            result = solve_branch(spec.problem, u0, span, options, callback=on_point)
            if switch is not None:
                result = _switched(spec, label, result, switch, b, options, progress, on_point)
        except ContinuationError as error:
            raise CommandError(f"bifurcate error: {label}: {error}", EXIT_FAILED) from None
        except CommandError:
            raise
        except Exception as error:  # noqa: BLE001 - the user's functions run inside the core
            raise CommandError(f"bifurcate error: {label}: the run stopped at {spec.parameter} = "
                               f"{reached['p']:.10g}: {type(error).__name__}: {error}", EXIT_FAILED) from None
        progress.stage(f"writing {out}/branch.npz, collisions.json, special_points.json")
        save_outputs(out, result, spec)
        progress.stage(f"plotting {out}/diagram.png")
        plot_problem_diagram(result, spec, f"{label}: spectrum of {spec.matrix}", out / "diagram.png")
    finally:
        progress.close()
    records = collision_json(result, spec)
    if as_json:
        print(json_text(brief(records)))
    else:
        if switch is not None:
            print(f"the second branch through branch point {switch[0] + 1}"
                  f"{' (its other half)' if switch[1] < 0 else ''}:")
        _print_summary(result, spec, out)
    if not result.success:
        raise CommandError(f"bifurcate error: {label}: the branch did not reach {spec.parameter} = "
                           f"{b:g}: {result.branch.status.sentence(len(result.p))}; what it reached is "
                           f"written",
                           EXIT_FAILED)
    return 0


def _switched(spec, label: str, result, switch: tuple[int, int], p_stop: float, options,
              progress: Progress, on_point):
    """The second branch through branch point switch[0] of `result`, toward p_stop; a one-line
    CommandError (exit 1) when the run has no such branch point."""
    from diskfriction.continuation.api import switch_branch

    k, side = switch
    points = result.branch_points
    if k >= len(points):
        raise CommandError(f"bifurcate error: --switch: the branch has {len(points)} branch "
                           f"point{'s' if len(points) != 1 else ''}, so none numbered {k + 1} "
                           f"({label})", EXIT_FAILED)
    progress.stage(f"switching at the branch point {spec.parameter} = {points[k].p:.10g} "
                   f"toward {p_stop:g}")
    return switch_branch(spec.problem, result, k, p_stop, options, side=side, callback=on_point)


def _print_summary(result, spec, out: Path) -> None:
    """What was reached and located, in the problem's names and units."""
    from diskfriction.reports.problem import special_points

    units = f" {spec.units}" if spec.units else ""
    print(f"{count(len(result.p), 'point')}, {spec.parameter} {path(result.p, [f.p for f in result.folds])}{units}, max residual "
          f"{result.branch.residual.max():.1e}, status {result.message}")
    print(f"{count(len(result.collisions), 'collision')} ({spec.matrix}):")
    for c in result.collisions:
        print(f"  {c.kind:5s}  {spec.parameter} = {c.p:.12g}{units}  lambda = {c.eigenvalue:.9g}")
    for s in special_points(result):
        value = f"  lambda = {complex(s.value):.6g}" if s.kind == "hopf" else ""
        what = "branch point" if s.kind == "branch" else s.kind
        print(f"  {what:5s}  {spec.parameter} = {s.p:.12g}{units}{value}")
    for line in result.warnings[:SHOWN_WARNINGS]:
        print(f"  warning: {line}")
    if len(result.warnings) > SHOWN_WARNINGS:
        print(f"  ... and {len(result.warnings) - SHOWN_WARNINGS} more warnings")
    print(f"wrote {out}/branch.npz, collisions.json, special_points.json, diagram.png")
