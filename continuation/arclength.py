"""Pseudo-arclength continuation with adaptive steps and inline collision detection.

From a converged point x_k = (u_k, p_k) with unit tangent t_k:
  predictor  x_pred = x_k + ds t_k
  corrector  Newton on  [G(u, p); t_k . (x - x_pred)] = 0          (newton.bordered_newton)
  tangent    [[G_u, G_p], [t_k^T]] t = e_(n+1),  t_(k+1) = t / |t|  (t_k . t_(k+1) > 0: folds pass)
Step control (arclength ds in the Euclidean norm of x):
  * corrector failure (no convergence in max_newton updates)   -> ds / 2, retry;
  * angle(t_k, t_(k+1)) > max_angle                             -> ds / 2, retry;
  * ds would drop below ds_min                                  -> stop, status "ds_min: ...";
  * accepted with <= fast_newton updates                        -> ds = min(growth ds, ds_max).
End: when the corrected p leaves [p_min, p_max] the step is clipped: x is re-solved at the end
value p_end (fixed-p Newton from the secant point at p_end), stored, and the run stops
("p_end"); otherwise after max_steps accepted steps ("max_steps").
Each accepted step is scanned for eigenvalue collisions (collisions.scan_step) BEFORE
problem.commit is called, so intermediate points see the state committed at x_k.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Callable, Optional

import numpy as np

from .branch import Branch
from .collisions import DetectionParams, Sample, make_sample, scan_step
from .newton import NewtonResult, bordered_newton, fixed_p_newton, tangent
from .problem import Problem
from .segment import Segment, SegmentSolveError
from .spectra import count_complex_pairs, sort_spectrum

Array = np.ndarray


class ContinuationError(RuntimeError):
    """The starting point could not be converged or the tangent is undefined there."""


@dataclass(frozen=True)
class ContinuationParams:
    """Algorithm parameters (see the module docstring). Arclength in the norm of x = (u, p);
    max_angle in radians; direction +1 follows increasing p at the start, -1 decreasing."""

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


@dataclass(frozen=True)
class _Step:
    """An accepted-to-be step: new point, its tangent, corrector work, whether it ends the run."""

    x: Array
    tangent: Array
    newton: NewtonResult
    last: bool


def _angle(t0: Array, t1: Array) -> float:
    return math.acos(min(1.0, max(-1.0, float(t0 @ t1))))


def _attempt(problem: Problem, x: Array, t: Array, ds: float, par: ContinuationParams):
    """One predictor-corrector step of length ds; a _Step or the reason of failure (str)."""
    res = bordered_newton(problem, x + ds * t, t, par.newton_tol, par.max_newton)
    if not res.converged:
        return f"corrector failed (residual {res.residual:.3g})"
    x_new, last = res.x, False
    try:
        t_new = tangent(problem, x_new, t)
        if _angle(t, t_new) > par.max_angle:
            return f"tangent turned by {_angle(t, t_new):.3g} rad"
        p_new = x_new[-1]
        if not par.p_min < p_new < par.p_max:  # landing exactly on an end also ends the run
            p_end = par.p_max if p_new >= par.p_max else par.p_min
            guess = x + (p_end - x[-1]) / (p_new - x[-1]) * (x_new - x)
            res = fixed_p_newton(problem, guess[:-1], p_end, par.newton_tol, par.max_newton)
            if not res.converged:
                return "landing on the end value failed"
            x_new, last = res.x, True
            t_new = tangent(problem, x_new, t)
    except np.linalg.LinAlgError:
        return "singular bordered matrix"
    return _Step(x_new, t_new, res, last)


def _validate_start(p0: float, par: ContinuationParams) -> None:
    if not par.p_min <= p0 <= par.p_max:
        raise ValueError(f"p0={p0} outside [{par.p_min}, {par.p_max}]")
    if (par.direction > 0 and p0 >= par.p_max) or (par.direction < 0 and p0 <= par.p_min):
        raise ValueError(f"direction {par.direction} leaves [{par.p_min}, {par.p_max}] at p0={p0}")


def continuation(problem: Problem, u0: Array, p0: float,
                 params: ContinuationParams = ContinuationParams(),
                 detection: DetectionParams = DetectionParams(), *,
                 callback: Optional[Callback] = None) -> Branch:
    """Follow G(u, p) = 0 from (u0, p0) (u0 is first corrected at fixed p0).

    Stores at every accepted point the tracked spectrum of problem.stability_matrix and locates
    every birth/death of a complex pair (collisions.py). callback(k, p, u, eigenvalues) is called
    for every accepted point k. Returns a Branch.
    """
    _validate_start(p0, params)
    start = fixed_p_newton(problem, np.asarray(u0, dtype=float), float(p0), params.newton_tol, params.max_newton)
    if not start.converged:
        raise ContinuationError(f"no equilibrium found at p0={p0} (residual {start.residual:.3g})")
    x = start.x
    e_p = np.zeros_like(x)
    e_p[-1] = params.direction
    try:
        t = tangent(problem, x, e_p)
    except np.linalg.LinAlgError as err:
        raise ContinuationError(f"tangent undefined at p0={p0} (fold or singular point)") from err
    sample = make_sample(0.0, x, sort_spectrum(problem.spectrum(x[:-1], x[-1])), detection.rel_tol)
    rec = _Recorder(detection.rel_tol, callback)
    rec.add(sample, 0.0, start, t, 0)
    previous: Optional[Sample] = None
    ds, status = params.ds, "max_steps"
    while rec.steps < params.max_steps:
        step = _attempt(problem, x, t, ds, params)
        if isinstance(step, _Step):
            try:
                found, end, solves, warnings = scan_step(
                    problem, Segment(problem, x, step.x, params.newton_tol, params.max_newton),
                    sample, problem.spectrum(step.x[:-1], step.x[-1]), detection, rec.steps, previous)
            except SegmentSolveError as err:
                step = f"collision scan: {err}"
        if not isinstance(step, _Step):
            ds *= 0.5
            if ds < params.ds_min:
                status = f"ds_min: {step} at p={x[-1]:.12g}"
                break
            continue
        rec.collisions += found
        rec.warnings += warnings
        step, end = _commit(problem, x, step, end, params, detection.rel_tol)
        if step is None:
            status = f"commit: no equilibrium after the commit at p={end.p:.12g}"
            break
        rec.add(end, ds, step.newton, step.tangent, solves)
        previous = None if found else sample
        x, t, sample = step.x, step.tangent, end
        if step.last:
            status = "p_end"
            break
        if step.newton.iterations <= params.fast_newton:
            ds = min(ds * params.growth, params.ds_max)
    return rec.branch(status)


def _commit(problem: Problem, x: Array, step: _Step, end: Sample, par: ContinuationParams, rel_tol: float):
    """Call problem.commit; if it reports a change, re-solve at fixed p and refresh tangent and
    spectrum (the jump is not scanned for collisions; the stored residual is the re-solve's, the
    iterations add up). Returns (step, end sample) or (None, end)."""
    changed = problem.commit(x[:-1], float(x[-1]), step.x[:-1].copy(), float(step.x[-1]))
    if not changed:
        return step, end
    res = fixed_p_newton(problem, step.x[:-1], float(step.x[-1]), par.newton_tol, par.max_newton)
    if not res.converged:
        return None, end
    t_new = tangent(problem, res.x, step.tangent)
    end = make_sample(0.0, res.x, problem.spectrum(res.x[:-1], res.x[-1]), rel_tol, reference=end)
    newton = replace(res, iterations=step.newton.iterations + res.iterations)
    return _Step(res.x, t_new, newton, step.last), end


class _Recorder:
    """Accumulates the accepted points of a run and builds the Branch."""

    def __init__(self, rel_tol: float, callback: Optional[Callback]):
        self.rel_tol, self.callback = rel_tol, callback
        self.rows: list[tuple] = []
        self.collisions: list = []
        self.warnings: list = []

    @property
    def steps(self) -> int:
        return len(self.rows) - 1

    def add(self, sample: Sample, ds: float, newton: NewtonResult, t: Array, solves: int) -> None:
        u, p = sample.x[:-1].copy(), float(sample.x[-1])
        self.rows.append((p, u, sample.eigvals, count_complex_pairs(sample.eigvals, self.rel_tol),
                          ds, newton.iterations, newton.residual, t, solves))
        if self.callback is not None:
            self.callback(len(self.rows) - 1, p, u, sample.eigvals)

    def branch(self, status: str) -> Branch:
        cols = list(zip(*self.rows))
        return Branch(p=np.array(cols[0]), u=np.array(cols[1]), eigenvalues=np.array(cols[2]),
                      n_complex=np.array(cols[3]), ds=np.array(cols[4]),
                      newton_iterations=np.array(cols[5]), residual=np.array(cols[6]),
                      tangent=np.array(cols[7]), detection_solves=np.array(cols[8]),
                      collisions=tuple(self.collisions), status=status, warnings=tuple(self.warnings))
