"""Pseudo-arclength continuation with adaptive steps and inline collision detection.

Each step is a predictor-corrector step from the last accepted point (step.py: the corrector on
the hyperplane normal to the tangent, the tangent by a bordered solve, so that folds pass).
Step control (arclength ds in the Euclidean norm of x):
  * corrector failure (no convergence in max_newton updates)   -> ds / 2, retry;
  * angle(t_k, t_(k+1)) > max_angle                             -> ds / 2, retry;
  * ds would drop below ds_min                                  -> stop, Stop DS_MIN;
  * with stop_at_fold, a corrected step past a fold (p falls      -> cut just before the fold,
    back, the tangent there points back in p)                          located on the step
                                                                       (before_fold), taken
                                                                       as the last step: Stop
                                                                       FOLD; where it cannot be
                                                                       located, as below
  * with stop_at_fold, a step whose first event lies past a fold, -> ds / 2, retry; below
    or across which a real tracked eigenvalue changed sign (a          ds_min: stop at x_k,
    step that jumped the fold)                                         Stop FOLD
  * accepted with <= fast_newton updates                        -> ds = min(growth ds, ds_max).
End: when the corrected p leaves [p_min, p_max] the step is clipped: x is re-solved at the end
value p_end (fixed-p Newton from the secant point at p_end), stored, and the run stops: REACHED
at the end the run heads for (p_max for direction +1, p_min for -1), TURNED_BACK at the
other (the branch passed a fold and came back, short of its goal); otherwise after max_steps
accepted steps (MAX_STEPS). The status is a branch.Stop (code, reason, p).
Events (problem.event_functions): if a component changes sign over the step, the step is cut at
the first such change, located on the branch (the step's segment) by segment.refine_sign_change to
|dp| <= event_tol max(1, |p|) (a relative tolerance: it terminates at any p), and ends on the
far side of it; the next step starts there. No step and no collision scan straddles an event.
Each accepted step is scanned for eigenvalue collisions (collisions.scan_step) in the state
committed at x_k: inline, before problem.commit is called, or on a worker process restored to
that state while the continuation goes on (scans.py; _follow says how the labels and a failed
scan are handled then).
"""
from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, replace
from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.branch import Branch, BranchRecorder, Stop, StopCode
from diskfriction.continuation.detection.collisions import DetectionParams
from diskfriction.continuation.linalg.solves import DIRECT, LinearSolver, SingularMatrix, blas_threads, heap_kept, same_matrix
from diskfriction.continuation.stepping.newton import factored_fixed_p, fixed_p_newton, tangent
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.detection.samples import Sample, make_sample, matrix_derivative, sample_at
from diskfriction.continuation.detection.scans import ScanJob, default_workers, pending_full, scans_for
from diskfriction.continuation.stepping.segment import SegmentSolveError
from diskfriction.continuation.stepping.step import (Step, StepRejected, attempt, before_fold, cut_at_event,
                                                     runs_back)
from diskfriction.continuation.spectra.eigensolvers import DEFAULT, Eigensolver
from diskfriction.continuation.spectra.tracking import Eigensystem, eigenvalue_slopes
from diskfriction.continuation.detection.spill import files_kept
from diskfriction.continuation.spectra.window import WindowCrowded

Array = np.ndarray


class ContinuationError(RuntimeError):
    """The starting point could not be converged or the tangent is undefined there."""


@dataclass(frozen=True)
class ContinuationParams:
    """Algorithm parameters (see the module docstring). Arclength in the norm of x = (u, p);
    max_angle in radians; direction +1 follows increasing p at the start, -1 decreasing;
    linear_solver: how the bordered systems are solved (linalg.solves.LinearSolver);
    eigensolver: how the spectra are computed (spectra/eigensolvers.py)."""

    ds: float = 1e-2
    ds_min: float = 1e-8
    ds_max: float = 1e-1
    newton_tol: float = 1e-10
    max_newton: int = 8
    max_angle: float = 0.3
    p_min: float = -math.inf
    p_max: float = math.inf
    max_steps: int = 10_000
    direction: int = 1
    growth: float = 1.5
    fast_newton: int = 3
    event_tol: float = 1e-13
    stop_at_fold: bool = False
    linear_solver: LinearSolver = DIRECT
    eigensolver: Eigensolver = DEFAULT

    def __post_init__(self):
        if not 0.0 < self.ds_min <= self.ds <= self.ds_max:
            raise ValueError(f"need 0 < ds_min <= ds <= ds_max, got {self.ds_min}, {self.ds}, {self.ds_max}")
        if not self.newton_tol > 0.0 or self.max_newton < 1:
            raise ValueError("need newton_tol > 0 and max_newton >= 1")
        if not 0.0 < self.max_angle < math.pi / 2:
            raise ValueError(f"max_angle must be in (0, pi/2), got {self.max_angle}")
        if not self.p_min < self.p_max:
            raise ValueError(f"need p_min < p_max, got {self.p_min}, {self.p_max}")
        if self.max_steps < 1 or self.direction not in (1, -1) or self.growth < 1.0:
            raise ValueError("need max_steps >= 1, direction in (+1, -1), growth >= 1")


Callback = Callable[[int, float, Array, Array], None]


def _validate_start(p0: float, par: ContinuationParams) -> None:
    if not par.p_min <= p0 <= par.p_max:
        raise ValueError(f"p0={p0} outside [{par.p_min}, {par.p_max}]")
    if (par.direction > 0 and p0 >= par.p_max) or (par.direction < 0 and p0 <= par.p_min):
        raise ValueError(f"direction {par.direction} leaves [{par.p_min}, {par.p_max}] at p0={p0}")


def continuation(problem: Problem, u0: Array, p0: float,
                 params: ContinuationParams = ContinuationParams(),
                 detection: DetectionParams = DetectionParams(), *,
                 workers: Optional[int] = None, callback: Optional[Callback] = None) -> Branch:
    """Follow G(u, p) = 0 from (u0, p0) (u0 is first corrected at fixed p0).

    Stores at every accepted point the tracked spectrum of problem.stability_matrix (by
    params.eigensolver, prepared at (u0, p0): a spectral window is sized there) and locates
    every birth/death of a complex pair (collisions.py). workers: processes that scan steps
    while the continuation goes on (scans.py; 0: every scan inline; None: automatic,
    scans.planned_workers). callback(k, p, u, eigenvalues) is called for every accepted point
    k. Returns a Branch.
    """
    _validate_start(p0, params)
    u0, p0 = np.asarray(u0, dtype=float), float(p0)
    if detection.spectra:
        params = replace(params, eigensolver=params.eigensolver.prepared(problem, u0, p0))
    workers = default_workers(problem, u0.size, detection, workers, params.eigensolver)
    with blas_threads(), heap_kept(), files_kept():
        return _continuation(problem, u0, p0, params, detection, workers, callback)


def _continuation(problem, u0, p0, params, detection, workers, callback) -> Branch:
    start = fixed_p_newton(problem, u0, p0, params.newton_tol, params.max_newton, params.linear_solver)
    if not start.converged:
        raise ContinuationError(f"no equilibrium found at the start of the branch, parameter = "
                                f"{p0:.12g} (Newton's residual stayed at {start.residual:.3g})")
    x = start.x
    e_p = np.zeros_like(x)
    e_p[-1] = params.direction
    try:
        t = tangent(problem, x, e_p, linear_solver=params.linear_solver)
    except np.linalg.LinAlgError as err:
        raise ContinuationError(f"the branch has no tangent at its start, parameter = {p0:.12g} "
                                f"(a fold or a singular point there)") from err
    sample = _sorted(_sample(problem, 0.0, x, t, params, detection, None, side=+1))
    rec = BranchRecorder(detection.rel_tol, detection.rho, callback)
    rec.add(sample, 0.0, start, t, 0)
    with scans_for(problem, workers) as scans:
        status = _follow(problem, scans, workers, _Start(x, t, sample, 0.0), rec, params, detection)
    return rec.branch(status)


@dataclass(frozen=True)
class _Start:
    """Where a step starts: point, unit tangent, sample (labels tracked), event functions
    there (None: no events), and ds, the arclength tried from it."""

    x: Array
    t: Array
    sample: Sample
    ds: float
    g: Optional[Array] = None


@dataclass(frozen=True)
class _Pending:
    """A committed step whose scan (scans.py) is not yet recorded: its start, the problem's
    state committed there (to return to if the scan fails; the next pending step's is the one
    committed at this step's end), the step and its end sample after the commit (None: the
    commit found no equilibrium)."""

    ticket: int
    start: _Start
    state: object
    step: Step
    end: Optional[Sample]


def _follow(problem: Problem, scans, workers: int, here: _Start, rec: "BranchRecorder",
            params: ContinuationParams, detection: DetectionParams) -> Stop:
    """Steps from `here` until the run ends; returns its status. Each accepted step is
    committed and its scan submitted; the scans are recorded in order as they come back (at
    once inline; with `workers`, the continuation goes on while the pending steps' end samples
    stay within scans.pending_full). The labels of points tracked from a step's unscanned end
    follow the scan's end_perm: recorded = tracked[labels]. A failed scan rejects its step as
    a failed corrector does: the problem returns to the state committed at the step's start
    and later scans are dropped."""
    here = replace(here, ds=params.ds, g=problem.event_functions(here.x[:-1], here.x[-1]))
    labels = np.arange(here.sample.eigvals.size)
    pending: deque[_Pending] = deque()
    previous: Optional[Sample] = None  # a stencil for the next scan (Detector.stencil_from_previous)
    status, stopped = Stop(StopCode.MAX_STEPS), False
    while True:
        while pending and (stopped or pending_full(workers, [item.end for item in pending])
                           or scans.ready(pending[0].ticket)):
            item = pending.popleft()
            outcome = scans.result(item.ticket)
            if outcome.failure is not None:
                scans.discard([later.ticket for later in pending])
                pending.clear()
                problem.restore(item.state)
                here, stopped = replace(item.start, ds=0.5 * item.start.ds), False
                if outcome.crowded:
                    status, stopped = Stop(StopCode.WINDOW, outcome.failure, float(here.x[-1])), True
                elif here.ds < params.ds_min:
                    status, stopped = Stop(StopCode.DS_MIN, outcome.failure, float(here.x[-1])), True
                break
            scan = outcome.result
            ahead = bool(pending)  # later points were tracked from this step's unscanned end
            of_label = np.argsort(labels)  # a label at the step's start -> its recorded label
            rec.collisions += [replace(c, pair=(int(of_label[c.pair[0]]), int(of_label[c.pair[1]])))
                               for c in scan.collisions]
            rec.warnings += scan.warnings
            rec.events += item.step.event
            previous = item.start.sample if detection.detector.stencil_from_previous and not scan.collisions else None
            if item.end is None:
                continue
            tracked = None if scan.tracked is None else scan.tracked[labels]
            if ahead:
                end, labels = item.end, scan.end_perm[labels]
            else:
                end = item.end.relabel(scan.end_perm)
                here = replace(here, sample=end)
            _record(problem, rec, item, end.relabel(labels), scan.solves, pending[0].state if ahead else None,
                    tracked)
        if stopped and not pending:
            return status
        if stopped:
            continue
        if rec.steps + len(pending) >= params.max_steps:
            status, stopped = Stop(StopCode.MAX_STEPS), True
            continue
        here, stop = _advance(problem, scans, here, rec.steps + len(pending), pending, previous, params,
                              detection)
        if stop is not None:
            status, stopped = stop, True


def _advance(problem, scans, here: _Start, index: int, pending: deque, previous, params, detection):
    """Step `index` from `here`: accepted, committed and its scan submitted (appended to
    pending), or rejected (ds halved). Returns (where the next step starts, the run's status if
    it stops there, else None)."""
    try:
        step = attempt(problem, here.x, here.t, here.ds, params)
        if params.stop_at_fold and runs_back(here, step, params):
            step = before_fold(problem, here, step, params)
            if step is None:
                return _towards_fold(here, "the next step passed a fold in p", params)
        if here.g is not None:
            step = cut_at_event(problem, here.x, here.t, step, here.g, params)
            if params.stop_at_fold and step.event and runs_back(here, step, params):
                # the step went round two folds (an S in p, parity unchanged at its ends) and
                # its first event lies on the branch between them
                return _towards_fold(here, "the step's first contact event lies past a fold in p", params)
        end = _sample(problem, 1.0, step.x, step.tangent, params, detection, here.sample, side=-1)
        if params.stop_at_fold and negative_parity(end) != negative_parity(here.sample):
            return _towards_fold(here, "the next step crossed a fold: a real eigenvalue of the "
                                       "tracked matrix changed sign", params)
    except StepRejected as err:
        return _rejected(here, str(err), params)
    except SegmentSolveError as err:
        return _rejected(here, f"locating the step's first event: {err}", params)
    except SingularMatrix as err:
        return _rejected(here, f"singular matrix: {err}", params)
    except WindowCrowded as err:
        return here, Stop(StopCode.WINDOW, str(err), float(here.x[-1]))
    state = problem.state()
    ticket = scans.submit(ScanJob(state, here.x, step.x, params.newton_tol, params.max_newton, here.sample,
                                  end, detection, index, previous, step.event, params.linear_solver,
                                  params.eigensolver))
    try:
        committed, end = _commit(problem, here.x, step, end, params, detection)
    except WindowCrowded as err:  # the spectrum after a commit's change: the step is not taken
        scans.discard([ticket])
        problem.restore(state)
        return here, Stop(StopCode.WINDOW, str(err), float(here.x[-1]))
    pending.append(_Pending(ticket, here, state, step if committed is None else committed,
                            None if committed is None else end))
    if committed is None:
        return here, Stop(StopCode.COMMIT, "no equilibrium after the commit", float(end.p))
    ds = here.ds
    if committed.newton.iterations <= params.fast_newton:
        ds = min(ds * params.growth, params.ds_max)
    g = problem.event_functions(committed.x[:-1], committed.x[-1]) if here.g is not None else None
    if committed.fold and not committed.event:
        status = Stop(StopCode.FOLD, "the branch reached a fold in p (located on the step)",
                      float(committed.x[-1]))
    else:
        status = _end_status(committed.x[-1], params) if committed.last else None
    return _Start(committed.x, committed.tangent, end, ds, g), status


def _towards_fold(here: _Start, reason: str, params: ContinuationParams):
    """A step past a fold with stop_at_fold: rejected with ds halved, so that the run closes in
    on the fold, until the step would drop below ds_min; then the run ends at `here`, within
    about ds_min (arclength) of the fold, with Stop FOLD."""
    if 0.5 * here.ds >= params.ds_min:
        return replace(here, ds=0.5 * here.ds), None
    return here, Stop(StopCode.FOLD, reason, float(here.x[-1]))


def negative_parity(sample: Sample) -> int:
    """The parity of the number of real tracked eigenvalues below 0 (excluded and unknown ones
    left out): the sign of the tracked matrix's determinant, which changes where a real
    eigenvalue passes through 0, at a fold (or a branch point) of a branch whose tracked matrix
    is dG/du up to a definite factor (M^-1 J of the disk problems)."""
    ev, real = sample.eigvals, sample.status == 0
    counted = real & ~sample.excluded & np.isfinite(ev)
    return int(np.count_nonzero(ev[counted].real < 0)) % 2


def _rejected(here: _Start, reason: str, params: ContinuationParams):
    """(here with ds halved, the run's Stop if that is below ds_min, else None)."""
    here = replace(here, ds=0.5 * here.ds)
    return here, Stop(StopCode.DS_MIN, reason, float(here.x[-1])) if here.ds < params.ds_min else None


def _end_status(p: float, params: ContinuationParams) -> Stop:
    """The status of a run whose step landed on an end of [p_min, p_max]: REACHED at the end
    it heads for (p_max going up, p_min going down); at the other end the branch turned back
    (a fold) and left the span on the side it started from, short of its goal."""
    if p == (params.p_max if params.direction > 0 else params.p_min):
        return Stop(StopCode.REACHED)
    return Stop(StopCode.TURNED_BACK, "the branch folded and left the span on its starting side", float(p))


def _record(problem: Problem, rec: "BranchRecorder", item: _Pending, end: Sample, solves: int,
            after: Optional[object], tracked: Optional[Array]) -> None:
    """rec.add for a scanned step; the callback sees the problem in the state committed at the
    step's end: `after`, restored for it while the continuation is ahead (else None: the
    problem is in that state). tracked: ScanResult.tracked in the labels of `end`."""
    now = problem.state() if after is not None and rec.callback is not None else None
    if now is not None:
        problem.restore(after)
    rec.add(end, item.start.ds, item.step.newton, item.step.tangent, solves, tracked, item.step.event)
    if now is not None:
        problem.restore(now)


def _sample(problem: Problem, s: float, x: Array, t: Array, params: ContinuationParams,
            detection: DetectionParams, reference: Optional[Sample], side: int) -> Sample:
    """The sample of an accepted point by params.eigensolver: with slopes along t (one-sided
    towards `side`, the inside of the step) when the detection needs them; no eigenvalue at all
    without spectra."""
    if not detection.spectra:
        return make_sample(s, x, Eigensystem(np.zeros(0, complex)), detection.rel_tol)
    return sample_at(problem, s, x, detection.rel_tol, reference,
                     t if detection.slopes else None, side, params.eigensolver)


def _sorted(sample: Sample) -> Sample:
    """Labels ordered by (Re, Im): a reproducible order for the first point of a branch."""
    return sample.relabel(np.lexsort((sample.eigvals.imag, sample.eigvals.real)))


def _commit(problem: Problem, x: Array, step: Step, end: Sample, par: ContinuationParams,
            detection: DetectionParams):
    """Call problem.commit; if it reports a change, re-solve at fixed p (from
    problem.resolve_start) and refresh tangent and spectrum (the jump is not scanned for
    collisions; the stored residual is the re-solve's, the iterations add up). Where the
    matrix the spectrum is computed from (the problem's StructuredMatrix.spectrum_matrix) came
    out the same, the end sample's spectrum is kept (_moved). After an event the slopes are
    refreshed on the side of the next step. Returns (step, end sample) or (None, end)."""
    u, p = step.x[:-1].copy(), float(step.x[-1])
    before = problem.stability_structure(u, p).spectrum_matrix if detection.spectra else None
    changed = problem.commit(x[:-1], float(x[-1]), u, p)
    if not changed:
        if step.event and detection.slopes:
            end = _moved(problem, end, step.x, step.tangent)
        return step, end
    res, near = factored_fixed_p(problem, problem.resolve_start(u), p, par.newton_tol, par.max_newton,
                                 par.linear_solver)
    if not res.converged:
        return None, end
    try:
        t_new = tangent(problem, res.x, step.tangent, near, par.linear_solver)
    except SingularMatrix:
        return None, end
    if before is not None and same_matrix(before, problem.stability_structure(res.x[:-1], p).spectrum_matrix):
        end = _moved(problem, end, res.x, t_new if detection.slopes else None)
    else:
        end = _sample(problem, 0.0, res.x, t_new, par, detection, end, side=+1)
    newton = replace(res, iterations=step.newton.iterations + res.iterations)
    return Step(res.x, t_new, newton, step.last, step.event, step.fold), end


def _moved(problem: Problem, end: Sample, x: Array, t: Optional[Array]) -> Sample:
    """The end sample at x, where the matrix its spectrum is computed from is the same (a
    commit that changed the state but not that matrix: a packing's loose disks giving way, a
    capped history): its spectrum kept, with the slopes along t (None: a sample without
    slopes) on the side of the next step (docs/continuation.md, Stepping;
    docs/notes/core-stepping.md, "Re-solving after a commit only where the matrix changed")."""
    if t is None:
        return end.moved(x)
    dA = matrix_derivative(problem, x, t, +1)
    return end.moved(x, t, eigenvalue_slopes(end.system, dA), dA)
