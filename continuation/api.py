"""The public front end: any one-parameter problem G(u, p) = 0 continued over a span of p, with
every eigenvalue collision, fold and Hopf point on the branch located.

    from diskfriction.continuation import Options, problem_from_functions, solve_branch

    problem = problem_from_functions(G, A=A)   # dG/du, dG/dp by differences (one warning)
    result = solve_branch(problem, u0, (0.0, 6.0), Options(ds_max=0.05))
    result.collisions, result.folds, result.hopf, result.branch.eigenvalues

scipy.integrate.solve_ivp's conventions: one front-end function (solve_branch), an options
object checked at the door (Options), one result object of arrays and located points
(BranchResult). Problems come from plain callables (problem_from_functions), from sympy
expressions compiled to cached numba kernels (problem_from_sympy), or from any subclass of
the core's Problem (problem.py: a history carried alongside u, events, a sparse Jacobian);
the builders and the checks at the door are builders.py's.
A problem file for `diskfriction bifurcate --problem` exports a BifurcationProblem: the
problem with its starting guess, its parameter's name and units and its matrix's name.
The reference with a worked example is docs/api.md.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable, Optional, Sequence, Union

import numpy as np

from diskfriction.continuation.branch import Branch, Record, StopCode, recorded
from diskfriction.continuation.builders import (ProblemError, check_problem, evaluated, problem_from_functions,
                                                problem_from_sympy, span_of)
from diskfriction.continuation.detection.bifurcations import (CONSERVATIVE, SpecialPoint, branch_point_brackets, conservative,
                                                              locate_branch_points, locate_folds, locate_hopf,
                                                              other_direction)
from diskfriction.continuation.detection.collisions import Collision, DetectionParams
from diskfriction.continuation.linalg.solves import DIRECT, LinearSolver
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.spectra.eigensolvers import DEFAULT, Eigensolver
from diskfriction.continuation.spectra.window import WIDENINGS, WindowCrowded
from diskfriction.continuation.stepping.arclength import Callback, ContinuationError, ContinuationParams, continuation
from diskfriction.continuation.stepping.newton import bordered_matrix, bordered_newton, term_size
from diskfriction.continuation.stepping.segment import SegmentSolveError
from diskfriction.continuation.stepping.weighting import Weighted, scale_of, unweighted

__all__ = ["BifurcationProblem", "BranchResult", "Options", "ProblemError", "check_problem",
           "problem_from_functions", "problem_from_sympy", "solve_branch", "solve_in_runs", "switch_branch"]

Array = np.ndarray

STEPS_PER_SPAN = 50
"""Default largest step: the span of p over this many steps (arclength in x = (u, p))."""
LOCATOR_TOL = 1e-2
"""Folds and Hopf points are refined on points solved to this fraction of newton_tol."""
FOLD_TOL = 1e-9
"""Folds are refined to |dx| <= FOLD_TOL in the run's metric (|dp| ~ p'' |dx|^2 / 2), times
min(1, p_scale)."""
BRANCH_POINT_TOL = 1e-12
"""Branch points are refined to |dx| <= BRANCH_POINT_TOL in the run's metric, times
min(1, p_scale)."""
P_RESOLUTION = 1000 * np.finfo(float).eps
"""The detection's tol_p is at least P_RESOLUTION max(|p_start|, |p_stop|) (2.2e-13 of it): the
collision locator stops at |dp| <= tol_p / 100, which p resolves (it rounds to eps |p|) only
above that; with p in units where it is 1e6, tol_p = 1e-10 ended a run ("the branch jumps")."""


SPECIAL_POINTS = ("fold", "branch", "hopf")
"""What solve_branch can locate after the run (Options.special_points)."""


@dataclass(frozen=True)
class Options:
    """Options of solve_branch (steps in the arclength |dx|^2 = p_scale^2 (theta / n) |du|^2 +
    dp^2 of x = (u, p), n = u.size, in units of p; theta None: p_scale^2 |du|^2 + dp^2,
    weighting.py).

    ds_max: largest step (None: |p_stop - p_start| / 50); ds: first step (None: ds_max / 4);
    ds_min: the run stops when the step must shrink below it (None: 1e-8 ds_max) [units of p];
    p_scale: the unit of p that u is weighed against in the arclength [units of p] (None: the
    span |p_stop - p_start|, so that p in other units takes the same steps; 1: the problem's
    own units, as the disk sweeps and packing shears take them); the tolerances in p (the
    detection's tol_p for collisions and Hopf points, 1e-9 in x for folds, 1e-12 for branch
    points) are taken times min(1, p_scale): absolute in units of p where p_scale >= 1,
    relative to p_scale where it is smaller, so that p in small units is located as finely,
    and tol_p at least P_RESOLUTION max|p|, what p in large units resolves;
    residual_scale: the size of G that newton_tol is relative to [units of G] (None: the size
    of G at the start, residual_scale_at, but at most 1: newton_tol tightens with G in small
    units and is never looser than in the units of G; 1: newton_tol in the units of G, the
    disk sweeps' and packing shears');
    newton_tol: max|G| / residual_scale at every stored point; max_newton: corrector
    iterations; max_steps: accepted points at most; detection: the collision detector's
    parameters (collisions.DetectionParams: collisions located to |dp| <= tol_p = 1e-10, as
    above); workers:
    processes scanning steps while the branch goes on (None: automatic; 0: inline;
    arclength.continuation);
    special_points: what to locate after the run (bifurcations.py): "fold", "branch" (simple
    branch points, where a second branch crosses: switch_branch follows it) and/or "hopf";
    a Hopf point is where a complex pair of the tracked matrix crosses Re = 0, a Hopf
    bifurcation when that matrix is the Jacobian of u' = G(u, p): leave "hopf" out for any
    other (e.g. M^-1 K, whose eigenvalues are omega^2). Nothing is located for a problem with a
    commit hook (its state is gone after the run). stop_at_fold: end the run at the last point
    before a step that turns p back (Stop code "fold"), for a problem whose branch beyond a
    fold is not physical (a loaded state that carries history jumps there).
    eigensolver: how the tracked spectra are computed (spectra/eigensolvers.py): DenseSpectra
    (every eigenvalue, LAPACK or a GPU: device), RefinedSpectra (the default: dense, full
    spectra refined from the previous sample's where the problem's stability matrix is
    periodic block-tridiagonal) or SpectralWindow(lo, hi) (the eigenvalues near a band of real
    parts, by sparse shift-invert); linear_solver: how the bordered systems are solved
    (linalg.solves.LinearSolver: LAPACK for a dense Jacobian, SuperLU with its column ordering
    for a sparse one)."""

    ds_max: Optional[float] = None
    ds: Optional[float] = None
    ds_min: Optional[float] = None
    newton_tol: float = ContinuationParams.newton_tol  # the core's defaults, not copies of them
    max_newton: int = ContinuationParams.max_newton
    max_steps: int = ContinuationParams.max_steps
    detection: DetectionParams = DetectionParams()
    workers: Optional[int] = None
    special_points: tuple[str, ...] = ("fold", "branch", "hopf")
    stop_at_fold: bool = False
    theta: Optional[float] = 1.0
    p_scale: Optional[float] = None
    residual_scale: Optional[float] = None
    eigensolver: Eigensolver = DEFAULT
    linear_solver: LinearSolver = DIRECT

    def __post_init__(self):
        for name in ("ds_max", "ds", "ds_min", "newton_tol", "p_scale", "residual_scale"):
            value = getattr(self, name)
            if value is not None and not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        if self.theta is not None and not (math.isfinite(self.theta) and self.theta > 0):
            raise ValueError(f"theta must be a finite number > 0 or None, got {self.theta!r}")
        if self.max_newton < 1 or self.max_steps < 1:
            raise ValueError("max_newton and max_steps must be >= 1")
        if not set(self.special_points) <= set(SPECIAL_POINTS):
            raise ValueError(f"special_points may hold {', '.join(map(repr, SPECIAL_POINTS))}, "
                             f"got {self.special_points!r}")

    def params(self, p_start: float, p_stop: float, residual_scale: float) -> ContinuationParams:
        """The core's ContinuationParams for the span p_start -> p_stop, its newton_tol
        absolute: newton_tol times residual_scale [units of G]."""
        ds_max = self.ds_max or abs(p_stop - p_start) / STEPS_PER_SPAN
        ds = self.ds or ds_max / 4
        ds_min = self.ds_min or min(1e-8 * ds_max, ds)
        return ContinuationParams(ds=ds, ds_min=ds_min, ds_max=ds_max,
                                  newton_tol=self.newton_tol * residual_scale,
                                  max_newton=self.max_newton, p_min=min(p_start, p_stop),
                                  p_max=max(p_start, p_stop), max_steps=self.max_steps,
                                  direction=1 if p_stop > p_start else -1,
                                  stop_at_fold=self.stop_at_fold, linear_solver=self.linear_solver,
                                  eigensolver=self.eigensolver)


@dataclass(frozen=True)
class BranchResult:
    """What solve_branch returns.

    branch: the core's Branch (branch.py): one row per accepted point, p (m,), u (m, n),
    eigenvalues (m, n_A) tracked (column i is one eigenvalue followed along the branch),
    n_complex (m,), residual (m,), tangent, status (branch.Stop), and the located collisions;
    folds, hopf, branch_points: bifurcations.SpecialPoint (p, u, bracket, step, value) in
    branch order;
    warnings: the detector's and the locators';
    p_scale [units of p], residual_scale [units of G]: those the run took (Options).
    Shortcuts: p, u, eigenvalues, collisions (collisions.Collision: p, kind Kind.BIRTH | Kind.DEATH,
    the double eigenvalue, its Jordan chain, bracket), success (the branch reached the end
    of the span) and message (why it stopped)."""

    branch: Branch
    folds: tuple[SpecialPoint, ...] = ()
    hopf: tuple[SpecialPoint, ...] = ()
    warnings: tuple[str, ...] = ()
    branch_points: tuple[SpecialPoint, ...] = ()
    p_scale: float = 1.0
    residual_scale: float = 1.0

    @property
    def p(self) -> Array:
        return self.branch.p

    @property
    def u(self) -> Array:
        return self.branch.u

    @property
    def eigenvalues(self) -> Array:
        return self.branch.eigenvalues

    @property
    def collisions(self) -> tuple[Collision, ...]:
        return self.branch.collisions

    @property
    def success(self) -> bool:
        return self.branch.status.reached

    @property
    def message(self) -> str:
        """The run's status line (str of branch.Stop)."""
        return str(self.branch.status)


def _stateless(problem: Problem) -> bool:
    """The problem carries no state alongside u (its commit hook is the base class's)."""
    return type(problem).commit is Problem.commit


def special_points(problem: Problem, branch: Branch, asked: tuple[str, ...],
                   params: ContinuationParams, detection: DetectionParams, in_p: float):
    """(folds, hopf, warnings, branch_points) of a finished branch, the kinds `asked`
    (bifurcations.py): folds to |dx| <= FOLD_TOL in_p and branch points to BRANCH_POINT_TOL
    in_p in the run's metric (in_p = min(1, p_scale); a step over a branch point is none of
    its folds), Hopf points to |dp| <= detection.tol_p (the run's, already times in_p), their
    points solved to max|G| <= params.newton_tol / 100 (with the branch's own tolerance a
    fold's p would be off by up to ~newton_tol / |dG/dp|); where no Hopf point was found on a
    conservative spectrum, a warning says why."""
    tol, solver = LOCATOR_TOL * params.newton_tol, params.linear_solver
    crossings = branch_point_brackets(problem, branch, tol, rel_tol=detection.rel_tol,
                                      linear_solver=solver) if "branch" in asked else []
    steps = tuple(sorted({k for k, _, _ in crossings}))
    locators = {"fold": lambda: locate_folds(problem, branch, tol_x=FOLD_TOL * in_p,
                                             newton_tol=tol, skip=steps, linear_solver=solver),
                "branch": lambda: locate_branch_points(problem, branch, crossings,
                                                       tol_x=BRANCH_POINT_TOL * in_p,
                                                       newton_tol=tol, linear_solver=solver),
                "hopf": lambda: locate_hopf(problem, branch, tol_p=detection.tol_p,
                                            rel_tol=detection.rel_tol, newton_tol=tol,
                                            linear_solver=solver, eigensolver=params.eigensolver)}
    found, warnings = dict.fromkeys(SPECIAL_POINTS, ()), []
    for kind in asked:
        try:
            found[kind] = tuple(locators[kind]())
        except SegmentSolveError as error:
            warnings.append(f"{kind} points not located: {error}")
    if "hopf" in asked and not found["hopf"] and conservative(branch.eigenvalues):
        warnings.append(CONSERVATIVE)
    return found["fold"], found["hopf"], tuple(warnings), found["branch"]


def residual_scale_at(problem: Problem, u: Array, p: float) -> float:
    """The size of G at (u, p), that newton_tol is relative to [units of G]: the size of the
    terms that cancel in G, max_i sum_j |dG_i/dx_j| |x_j| over x = (u, p) (newton.term_size);
    where those are all 0 (u = 0 and p = 0, or a trivial branch u = 0 of a G linear in u), the
    size of its change with a unit change of each, max_i sum_j |dG_i/dx_j|. Either scales with
    G and neither changes with the units of p. A ProblemError (one line, naming the option to
    set) where both are 0: dG/du and dG/dp vanish there."""
    x = np.append(u, p)
    M = bordered_matrix(problem, x, np.zeros_like(x))
    scale = term_size(M, x) or term_size(M, np.ones_like(x))
    if not (math.isfinite(scale) and scale > 0):
        raise ProblemError(f"G has no size to measure newton_tol against at p = {p:g} (dG/du and "
                           f"dG/dp are 0 there): give its size as Options(residual_scale=...)")
    return scale


def _units(options: Options, problem: Problem, u0: Array, p_start: float, p_stop: float):
    """(p_scale, residual_scale) of a run: the options', or their defaults (Options)."""
    p_scale = options.p_scale or abs(p_stop - p_start)
    return p_scale, options.residual_scale or min(1.0, residual_scale_at(problem, u0, p_start))


def _tol_p(tol_p: float, in_p: float, p_start: float, p_stop: float) -> float:
    """The detection's tol_p in units of p: times in_p = min(1, p_scale), and at least
    P_RESOLUTION max(|p_start|, |p_stop|)."""
    return max(tol_p * in_p, P_RESOLUTION * max(abs(p_start), abs(p_stop)))


def solve_branch(problem: Problem, u0, p_span, options: Options = Options(), *,
                 callback: Optional[Callback] = None, record: Optional[Record] = None) -> BranchResult:
    """Continue G(u, p) = 0 from p_span[0] to p_span[1] and locate what happens on the way.

    u0 is a guess of the state at p_span[0], corrected there by Newton (ContinuationError if it
    does not converge). The branch is followed by pseudo-arclength continuation through folds
    (arclength.py) until p leaves the span; at every accepted point the spectrum of the
    tracked matrix is stored, and every birth and death of a complex pair is located to
    |dp| <= the detection's tol_p (in units of p as Options says: _tol_p) (collisions.py);
    folds and Hopf points are located after the run (bifurcations.py). The core runs in y = (p_scale sqrt(theta / n) u,
    p), whose Euclidean length is the Options' arclength (weighting.py), with newton_tol times
    residual_scale: the same problem with G or p in other units takes the same steps.
    callback(k, p, u, eigenvalues) is called at every accepted point; record(p, u), a record
    hook (branch.Record), gives each accepted point's columns of the branch (Branch.columns;
    its "residual", the point's residual).
    Bad input (span, options, a problem whose functions fail or return wrong shapes at the
    start) raises ValueError or ProblemError before anything is computed."""
    p_start, p_stop = span_of(p_span)
    u0 = check_problem(problem, u0, p_start)
    p_scale, residual_scale = _units(options, problem, u0, p_start, p_stop)
    params = options.params(p_start, p_stop, residual_scale)
    if options.detection.spectra:  # a spectral window sized at the start (Eigensolver.prepared)
        params = replace(params, eigensolver=params.eigensolver.prepared(problem, u0, p_start))
    in_p = min(1.0, p_scale)  # the tolerances in p: absolute, or relative to a smaller p_scale
    tol_p = _tol_p(options.detection.tol_p, in_p, p_start, p_stop)
    detection = options.detection if tol_p == options.detection.tol_p else \
        replace(options.detection, tol_p=tol_p)
    s = scale_of(options.theta, u0.size) * p_scale
    core = problem if s == 1.0 else Weighted(problem, s, p_scale)  # the metric of the Options
    records = []

    def told(k, p, y, ev):
        if record is not None:
            records.append(record(p, y / s))
        if callback is not None:
            callback(k, p, y / s, ev)
    branch = continuation(core, u0 * s, p_start, params, detection, workers=options.workers,
                          callback=None if callback is None and record is None else told)
    asked = options.special_points if _stateless(problem) else ()
    folds, hopf, warnings, branch_points = special_points(core, branch, asked, params, detection,
                                                          in_p)
    folds, hopf, branch_points = ([replace(point, u=point.u / s) for point in points]
                                  for points in (folds, hopf, branch_points))
    return BranchResult(recorded(unweighted(branch, s), records),
                        tuple(folds), tuple(hopf),
                        branch.warnings + warnings, tuple(branch_points), p_scale, residual_scale)


def solve_in_runs(problem: Problem, u0, p_span, options: Options,
                  callback_of: Callable[[int], Optional[Callback]],
                  record: Optional[Record] = None,
                  committed: Optional[Callable[[], tuple[Array, float]]] = None
                  ) -> tuple[list[Branch], int, Eigensolver]:
    """solve_branch, where a crowded spectral window does not end the work. The eigensolver
    (options.eigensolver) is prepared at the start (Eigensolver.prepared: a window sized
    there); where a run ends crowded (StopCode.WINDOW) it is sized anew, wider, at the point of
    the problem's committed state, committed() (None: the last point of the run), and a new run
    goes on from the last certified point, or the run starts again (its first point crowded:
    WindowCrowded before any point, as at the start of a packing's segment after a plastic
    event), until a run ends otherwise or WIDENINGS widenings in a row reach no further point.
    callback_of(r) is run r's callback (None: none); a run after the first starts at the last
    point of the one before, which its callback does not get again (record, solve_branch's,
    gets every point of every run, that one too). Returns (the runs' branches in order, their
    eigenvalues under each run's own labels: a widened window holds more of them; how often
    the window was widened; the eigensolver as the last run took it, for a run that goes on
    from there)."""
    runs, stuck, widenings, (p_start, p_stop) = [], 0, 0, p_span
    eigensolver = options.eigensolver
    if options.detection.spectra:
        eigensolver = eigensolver.prepared(problem, u0, p_start)

    def wider(u, p) -> Optional[Eigensolver]:
        """The eigensolver widened at the committed point (or at (u, p)), None: none, or stuck."""
        if stuck > WIDENINGS:
            return None
        return eigensolver.widened(problem, *(committed() if committed is not None else (u, p)))

    while True:
        callback = callback_of(len(runs))
        if runs and callback is not None:
            callback = _after_start(callback)
        try:
            branch = solve_branch(problem, u0, (p_start, p_stop), replace(options, eigensolver=eigensolver),
                                  callback=callback, record=record).branch
        except WindowCrowded:
            stuck += 1
            widened = wider(u0, p_start)
            if widened is None:
                raise
            eigensolver, widenings = widened, widenings + 1
            continue
        runs.append(branch)
        stuck = stuck + 1 if len(branch) == 1 else 0
        widened = None if branch.status.code is not StopCode.WINDOW else wider(branch.u[-1], float(branch.p[-1]))
        if widened is None:
            return runs, widenings, eigensolver
        eigensolver, widenings = widened, widenings + 1
        u0, p_start = branch.u[-1], float(branch.p[-1])


def _after_start(callback: Callback) -> Callback:
    """callback for every point but a run's first (k = 0)."""
    def call(k, p, u, eigenvalues):
        if k:
            callback(k, p, u, eigenvalues)
    return call


def switch_branch(problem: Problem, result: BranchResult, k: int, p_stop: float,
                  options: Options = Options(), *, side: int = 1,
                  callback: Optional[Callback] = None) -> BranchResult:
    """Follow the second branch through result.branch_points[k] from there to p_stop.

    Its direction at the point is the null direction of [G_u, G_p] orthogonal to the found
    branch (bifurcations.other_direction). A first point one step (options' ds) along it is
    solved with the arclength constraint normal to that direction, on the half of the second
    branch that moves p toward p_stop; where neither half does (a pitchfork: the second branch
    leaves with dp = 0 and both halves bend the same way), the half toward the direction's
    largest component, and with `side` = -1 the other. The branch is continued from that
    point by solve_branch (the same options; p_scale and residual_scale, where they leave
    them None, the first run's: result.p_scale, result.residual_scale). ValueError for a k
    that names no branch point or a side other than +-1; ContinuationError if no first point
    converges."""
    if not 0 <= k < len(result.branch_points):
        raise ValueError(f"branch point {k} asked for; the branch has "
                         f"{len(result.branch_points)} (numbered from 0)")
    if side not in (1, -1):
        raise ValueError(f"side must be 1 or -1, got {side!r}")
    point = result.branch_points[k]
    x = result.branch.x
    along = x[point.step + 1] - x[point.step]
    phi = other_direction(problem, point, along / np.linalg.norm(along))
    phi = side * (phi if phi[np.argmax(np.abs(phi))] > 0 else -phi)
    options = replace(options, p_scale=options.p_scale or result.p_scale,
                      residual_scale=options.residual_scale or result.residual_scale)
    params = options.params(point.p, p_stop, options.residual_scale)
    x_star = np.append(point.u, point.p)
    halves = [bordered_newton(problem, x_star + params.ds * d, d, params.newton_tol,
                              params.max_newton, linear_solver=params.linear_solver) for d in (phi, -phi)]
    ahead = [h for h in halves if h.converged and (h.x[-1] - point.p) * (p_stop - point.p)
             > FLAT_IN_P * params.ds]
    first = ahead[0] if ahead else halves[0]
    if not first.converged:
        raise ContinuationError(f"no point of the second branch one step (ds = {params.ds:g}) "
                                f"from the branch point at p = {point.p:.12g}: the corrector "
                                f"failed ({first.failure()})")
    return solve_branch(problem, first.x[:-1], (float(first.x[-1]), p_stop), options,
                        callback=callback)


FLAT_IN_P = 1e-6
"""A first point whose p moved by less than this times the step toward p_stop does not move p
(a pitchfork's, which moves p by O(ds^2)): switch_branch then keeps the half `side` names."""


Start = Union[Sequence[float], Array, Callable[[float], Array]]


@dataclass(frozen=True)
class BifurcationProblem:
    """A problem with what a problem file gives besides its equations (`diskfriction
    bifurcate --problem FILE.py[:NAME]` imports FILE.py and takes NAME, default `problem`).

    problem: the equations (problem_from_functions, problem_from_sympy or a Problem subclass);
    u0: a guess of the state at the start of the span, an array or a function of p;
    p_span: the span the command runs without --p (None: --p is required);
    parameter: the name of p, a Python identifier (axis labels, the keys of branch.npz and
    collisions.json); units: its units ("" for none);
    matrix: the name of the tracked matrix, e.g. "M^-1 K"; eigenvalue_units: its eigenvalues'
    units; options: the Options the command uses for this problem (its --ds-max overrides
    ds_max)."""

    problem: Problem
    u0: Start
    p_span: Optional[tuple[float, float]] = None
    parameter: str = "p"
    units: str = ""
    matrix: str = "A"
    eigenvalue_units: str = ""
    options: Options = Options()

    def __post_init__(self):
        if not isinstance(self.problem, Problem):
            raise TypeError(f"problem must be a continuation Problem (problem_from_functions, "
                            f"problem_from_sympy or a subclass), got {type(self.problem).__name__}")
        if not self.parameter.isidentifier():
            raise ValueError(f"parameter must be a name such as P, F_x or I (it keys the output "
                             f"files), got {self.parameter!r}")
        if self.p_span is not None:
            span_of(self.p_span)

    def start(self, p: float):
        """The guess of the state at p (checked by solve_branch); a ProblemError if u0(p) fails."""
        return evaluated("u0(p)", lambda: self.u0(p), p) if callable(self.u0) else self.u0

    def solve(self, p_span=None, options: Optional[Options] = None, *,
              callback: Optional[Callback] = None) -> BranchResult:
        """solve_branch over p_span (default self.p_span) with options (default self.options)."""
        span = span_of(p_span if p_span is not None else self.p_span)
        return solve_branch(self.problem, self.start(span[0]), span, options or self.options,
                            callback=callback)
