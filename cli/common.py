"""Helpers shared by the subcommands: the scene argument, checks made before anything is
computed (the output directory, the memory a sweep needs), and bad input as one line."""
from __future__ import annotations

import argparse
import contextlib
import importlib
import math
import signal
import sys
import threading
from pathlib import Path
from typing import Optional

from diskfriction.errors import OneLineError
from diskfriction.files import writable
from diskfriction.matrices import MATRIX_OPTIONS, Matrix
from diskfriction.scenes.load import SceneError, default_scene_path, load_scene
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.scene import NEGATIVE_LOAD, Scene

EXIT_BAD_INPUT = 2  # as argparse exits on a usage error
EXIT_FAILED = 1  # the computation itself failed (no equilibrium, ...)
EXIT_INTERRUPTED = 130  # as a shell reports SIGINT


class CommandError(Exception):
    """One line for stderr, ``COMMAND error: WHAT``, and the exit code it ends with."""

    def __init__(self, line: str, code: int = EXIT_BAD_INPUT) -> None:
        super().__init__(line)
        self.code = code


def add_scene_argument(parser: argparse.ArgumentParser) -> None:
    """Give ``parser`` an optional positional scene FILE (default: the paper scene)."""
    parser.add_argument("scene", nargs="?", metavar="FILE",
                        help="scene TOML file (default: the paper scene, scenes/paper.toml)")


def scene_from_args(args: argparse.Namespace) -> Scene | PackingScene:
    """The scene named by the FILE argument, or the paper scene; raises SceneError."""
    return load_scene(args.scene if args.scene is not None else default_scene_path())


COMMANDS = ("scene", "prepare", "bifurcate", "simulate", "verify", "map", "report", "export",
            "crosscheck")
"""The commands that take a scene, in the order their refusals list them."""


def front_for(command: str, scene):
    """The function of `scene`'s model that does `command` (models/<geometry>/commands.py: a
    function named after the command; map's is map_plan), or a one-line CommandError (exit 2)
    saying which geometries `command` takes and which commands take this one's scenes."""
    from diskfriction.models import GEOMETRIES

    def function(name: str, geometry: str):
        front = importlib.import_module(f"{GEOMETRIES[geometry]}.commands")
        return getattr(front, "map_plan" if name == "map" else name, None)

    found = function(command, scene.geometry)
    if found is None:
        takes = [g for g in GEOMETRIES if function(command, g) is not None]
        ours = [c for c in COMMANDS if c == "scene" or function(c, scene.geometry) is not None]
        raise CommandError(f"{command} error: {scene.source}: geometry = \"{scene.geometry}\": "
                           f"{command} takes {' or '.join(takes)} scenes; "
                           f"{', '.join(f'`{c}`' for c in ours)} take {scene.geometry} scenes")
    return found


def add_matrix_argument(parser: argparse.ArgumentParser, help: str) -> None:
    """Give ``parser`` the option --matrix J|M^-1J (diskfriction.matrices.MATRIX_OPTIONS)."""
    parser.add_argument("--matrix", metavar="J|M^-1J", help=f"{help} (default: the scene's)")


def matrix_from_args(command: str, args: argparse.Namespace, scene: Scene) -> Matrix:
    """The matrix --matrix names, or the scene's; a one-line CommandError for another name."""
    if args.matrix is None:
        return Matrix(scene.matrix)
    if args.matrix not in MATRIX_OPTIONS:
        raise CommandError(f"{command} error: --matrix: must be J or M^-1J (got {args.matrix!r})")
    return MATRIX_OPTIONS[args.matrix]


def number(command: str, option: str, value, zero: bool = False, integer: bool = False):
    """`value` if it is a finite number > 0 (>= 0 with `zero`; a whole number with `integer`),
    else a CommandError: ``COMMAND error: --OPTION: must be ... (got VALUE)``, exit 2."""
    ok = (value is not None and math.isfinite(value) and (value >= 0 if zero else value > 0)
          and (not integer or value == int(value)))
    if not ok:
        what = f"{'an integer' if integer else 'a number'} {'>= 0' if zero else '> 0'}"
        raise CommandError(f"{command} error: --{option}: must be {what} (got {value!r})")
    return value


def load(command: str, value: float) -> float:
    """A load F_x given with --fx: a finite number >= 0 (NEGATIVE_LOAD says why not below 0),
    else a CommandError, exit 2."""
    if value is not None and value < 0:
        raise CommandError(f"{command} error: --fx: F_x must be >= 0: {NEGATIVE_LOAD} (got {value!r})")
    return number(command, "fx", value, zero=True)


def run_length(command: str, t_end: float, dt: Optional[float]) -> None:
    """--t-end a number > 0 and --dt, if given, a number > 0 no longer than it; else a
    CommandError, exit 2."""
    number(command, "t-end", t_end)
    if dt is not None:
        number(command, "dt", dt)
        if dt > t_end:
            raise CommandError(f"{command} error: --dt: longer than --t-end = {t_end:g}: the run "
                               f"would not take one step (got {dt!r})")


def path(p, folds=()) -> str:
    """The values a branch's parameter passed through, in order: its start, every turning point
    (where p changes direction: the located folds' p when there are as many, else the samples
    there) and its end, e.g. "1 -> 0 -> 1"."""
    import numpy as np

    p = np.asarray(p, dtype=float)
    moved = np.flatnonzero(np.diff(p) != 0)  # the steps that moved p
    step = np.sign(np.diff(p)[moved])
    turns = [p[moved[k] + 1] for k in range(step.size - 1) if step[k] != step[k + 1]]
    turns = list(folds) if len(folds) == len(turns) else turns
    return " -> ".join(f"{v:.6g}" for v in [p[0], *turns, p[-1]])


def bracketed_only(records: list[dict]) -> str:
    """", K only bracketed" (the collisions the detection found but did not locate to its
    tolerance: its solve budget ran out, or their interval could not be certified; resolved
    false in collisions.json, each with its bracket), or "" when every one is located."""
    unlocated = sum(not r["resolved"] for r in records)
    if not unlocated:
        return ""
    return (f", {unlocated} of them only bracketed, not located to the detection's tolerance "
            "(resolved: false in collisions.json)")


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


def code_targets(subparsers: argparse._SubParsersAction, command: str, help: str
                 ) -> argparse._SubParsersAction:
    """Add `command`, whose first argument names the other code it works with (CODE); the
    subparsers to add each code to."""
    parser = subparsers.add_parser(command, help=help, description=help[0].upper() + help[1:] + ".")
    return parser.add_subparsers(metavar="CODE", required=True, dest="target")


def output_dir(command: str, given: Optional[str], default: Path) -> Path:
    """The output directory, --out or `default`, checked before anything is computed: not
    empty, not an existing file, and a directory that exists or can be made and in which
    files can be created. Else a CommandError (one line, exit 2)."""
    if given == "":
        raise CommandError(f"{command} error: --out: empty path (got '')")
    path = Path(given) if given is not None else default
    shown = repr(str(path))
    if path.exists() and not path.is_dir():
        raise CommandError(f"{command} error: --out: not a directory (got {shown})")
    problem = writable(path)
    if problem is not None:
        raise CommandError(f"{command} error: --out: cannot write there: {problem} (got {shown})")
    return path


def check_memory(command: str, scene: Scene, processes: int = 1, dense: Optional[bool] = None,
                 spectra: int = 0) -> None:
    """Refuse (one line, exit 2) a scene whose work needs more memory than this machine has,
    naming what it counted: the larger of a sweep, dense in n = ndof (unless `dense` is False: a
    spectral window, a sweep without spectra, or eps = 0, the default None meaning eps > 0) in
    each of the `processes` that take spectra at once (a sweep's and its scan workers, or a
    map's cells on this machine), with its stored points (models/chain/memory.py), and the dense
    spectrum of M^-1 J at a run's start in each of the `spectra` processes that take one at once."""
    from diskfriction.models.chain.memory import spectrum_bytes, sweep_bytes
    from diskfriction.memory import NotEnoughMemory, require_memory

    n = scene.ndof
    dense = scene.eps > 0 if dense is None else dense
    where = f" in {processes} processes" if processes > 1 else ""
    needs = [(sweep_bytes(n, processes=processes, dense=dense),
              f"a sweep of {n} x {n} dense matrices{where}" if dense
              else f"a sweep's points of {n} unknowns")]
    if spectra:
        at_once = f" in {spectra} processes" if spectra > 1 else ""
        needs.append((spectrum_bytes(n, spectra), f"the dense {n} x {n} spectrum at a run's start{at_once}"))
    nbytes, what = max(needs)
    try:
        require_memory(nbytes, f"N = {scene.N}: {what}")
    except NotEnoughMemory as error:
        raise CommandError(f"{command} error: {scene.source}: {error}") from None


def run_command(args: argparse.Namespace) -> int:
    """Run the chosen subcommand. A SceneError, CommandError or OneLineError (no equilibrium,
    not enough memory, ...) becomes one line on stderr and its exit code; Ctrl-C one line
    (interrupted_line) and 130, also where it surfaces as another exception raised from it or
    while handling it (interrupted); a MemoryError one line and exit 1."""
    command = getattr(args, "command", "diskfriction")
    try:
        with ctrl_c_noted() as noted:
            try:
                return args.run(args)
            except Exception as error:
                if noted.seen or interrupted(error):
                    raise KeyboardInterrupt from error
                raise
    except SceneError as error:
        print(error, file=sys.stderr)
        return EXIT_BAD_INPUT
    except CommandError as error:
        print(error, file=sys.stderr)
        return error.code
    except OneLineError as error:
        print(f"{command} error: {error}", file=sys.stderr)
        return error.exit_code
    except MemoryError as error:
        print(f"{command} error: out of memory ({error})", file=sys.stderr)
        return EXIT_FAILED
    except KeyboardInterrupt:
        print(interrupted_line(args), file=sys.stderr)
        return EXIT_INTERRUPTED


RESUMES = "interrupted: the finished {what} are kept in {where}; rerun the same command to resume"
STARTS_OVER = "interrupted: {command} does not resume; run it again to get its results"
NONE_KEPT = ("interrupted before any of the {what} was finished: nothing is kept; rerun the same "
             "command to start again")


class CtrlC:
    """Whether Ctrl-C (SIGINT) arrived during a command (ctrl_c_noted)."""

    seen = False


@contextlib.contextmanager
def ctrl_c_noted():
    """Note every SIGINT while the block runs, then raise KeyboardInterrupt as Python's own
    handler does. Library code may swallow that KeyboardInterrupt and fail later with an error
    that does not chain to it (numba saving a compiled function to its cache, interrupted,
    then 'no compiled object yet'): run_command still reads that as Ctrl-C. Where SIGINT is not
    Python's default handler, or off the main thread, nothing is installed."""
    noted = CtrlC()

    def note(signum, frame):
        noted.seen = True
        raise KeyboardInterrupt

    installed = (threading.current_thread() is threading.main_thread()
                 and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
    if installed:
        signal.signal(signal.SIGINT, note)
    try:
        yield noted
    finally:
        if installed:
            signal.signal(signal.SIGINT, signal.default_int_handler)


def interrupted(error: BaseException) -> bool:
    """Whether a KeyboardInterrupt caused `error` (its __cause__ or __context__ chain): Ctrl-C
    landing in a compiled function's first call (numba unpickling its constants) comes out as
    a SystemError raised from the KeyboardInterrupt, and a wrapper may turn that into its own
    error (continuation.api: "dG/du raised SystemError")."""
    seen = set()
    while error is not None and id(error) not in seen:
        if isinstance(error, KeyboardInterrupt):
            return True
        seen.add(id(error))
        error = error.__cause__ or error.__context__
    return False


def interrupted_line(args: argparse.Namespace) -> str:
    """What Ctrl-C leaves: a command that resumes says what it keeps and where (args.keeps,
    set by the command once it knows: ("realizations", DIR)), or that it had finished none of
    them yet (DIR None); any other that it starts over."""
    keeps = getattr(args, "keeps", None)
    if keeps is not None:
        what, where = keeps
        return (NONE_KEPT.format(what=what) if where is None
                else RESUMES.format(what=what, where=where))
    return STARTS_OVER.format(command=getattr(args, "command", "the command"))
