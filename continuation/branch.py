"""The result of a continuation run: one object of arrays (one row per accepted point)."""
from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.detection.detectors import Collision
from diskfriction.continuation.stepping.newton import NewtonResult
from diskfriction.continuation.detection.samples import Sample, continued_labels
from diskfriction.continuation.spectra.tracking import condition_numbers, count_complex_pairs

Array = np.ndarray


class StopCode(StrEnum):
    """Why a run stopped (arclength.py): it reached the end of the span it heads for, the
    branch folded and left the span on its starting side, the step limit, a step that had to
    shrink below ds_min, a commit (Problem.commit) after which no equilibrium was found,
    (with stop_at_fold) a step that would have turned p back, or a spectral window that no
    longer holds every eigenvalue its guard bands reach (spectral_window.WindowCrowded: the
    branch ends at the last point whose step was certified; a caller may size the window
    anew there and go on)."""

    REACHED = "p_end"
    TURNED_BACK = "turned back"
    MAX_STEPS = "max_steps"
    DS_MIN = "ds_min"
    COMMIT = "commit"
    FOLD = "fold"
    WINDOW = "window"


MESSAGES = {
    StopCode.REACHED: "p_end",
    StopCode.MAX_STEPS: "max_steps",
    StopCode.DS_MIN: "ds_min: {reason} at p={p:.12g}",
    StopCode.COMMIT: "commit: {reason} at p={p:.12g}",
    StopCode.TURNED_BACK: "turned back: {reason} at p={p:.12g}",
    StopCode.FOLD: "fold: {reason} at p={p:.12g}",
    StopCode.WINDOW: "window: {reason} at p={p:.12g}",
}
"""The status line of each code (str(Stop)): the text Branch.status had before it was a Stop."""


@dataclass(frozen=True)
class Stop:
    """Why a run stopped: code; reason, what failed or happened, as words (e.g. "corrector
    failed (residual 1.6e-11)"; empty for REACHED and MAX_STEPS); p, where (None for REACHED
    and MAX_STEPS). str() is its status line (MESSAGES)."""

    code: StopCode
    reason: str = ""
    p: Optional[float] = None

    def __str__(self) -> str:
        return MESSAGES[self.code].format(reason=self.reason, p=self.p)

    @property
    def reached(self) -> bool:
        """Whether the run reached the end of the span it heads for."""
        return self.code is StopCode.REACHED

    def sentence(self, points: int) -> str:
        """The stop for a sentence, without its location: "reached", "the run stopped after
        {points} points" (points: the run's accepted points), else the reason."""
        if self.code is StopCode.REACHED:
            return "reached"
        if self.code is StopCode.MAX_STEPS:
            return f"the run stopped after {points} points"
        return self.reason


@dataclass(frozen=True)
class Branch:
    """Accepted points k = 0..m-1 of a branch G(u, p) = 0.

    p (m,); u (m, n); eigenvalues (m, n) complex, tracked: column i is one eigenvalue followed
    along the branch; n_complex (m,): number of complex pairs (spectra.count_complex_pairs);
    ds (m,): arclength step that reached the point (0 for the first); newton_iterations (m,):
    corrector updates; residual (m,): max|G| at the stored point; tangent (m, n+1): unit
    tangent in x = (u, p); detection_solves (m,): corrector solves spent on collision detection
    in the step ending at the point; collisions: located births and deaths in branch order;
    status: why the run stopped (a Stop: its code, reason and p);
    warnings; events: steps cut at an event (problem.event_functions); continued (m, n) bool,
    with a spectral window only (else None): label i at point k is certified to hold the
    eigenvalue it held at point k - 1 (False at k = 0): it stayed in the tracked set throughout
    the step (the detection certified it), or samples.certified_labels certifies the step;
    condition (m, n): each tracked eigenvalue's condition number |l| |r| / |l^H r|
    (spectra.condition_numbers; nan where the point's sample holds no vectors: exhaustive
    detection, or no spectra).
    """

    p: Array
    u: Array
    eigenvalues: Array
    n_complex: Array
    ds: Array
    newton_iterations: Array
    residual: Array
    tangent: Array
    detection_solves: Array
    collisions: tuple[Collision, ...]
    status: Stop
    warnings: tuple[str, ...] = ()
    events: int = 0
    continued: Optional[Array] = None
    condition: Optional[Array] = None

    def __len__(self) -> int:
        return self.p.size

    @property
    def x(self) -> Array:
        """Rows (u, p), shape (m, n+1)."""
        return np.column_stack([self.u, self.p])


class BranchRecorder:
    """Accumulates the accepted points of a run (arclength.continuation) and builds the Branch:
    rel_tol, the complex-pair threshold (spectra.count_complex_pairs); rho, the certification
    margin of a spectral window's label continuity (samples.continued_labels); callback(k, p,
    u, eigenvalues), called for every point recorded."""

    def __init__(self, rel_tol: float, rho: float, callback: Optional[Callable]):
        self.rel_tol, self.rho, self.callback = rel_tol, rho, callback
        self.rows: list[tuple] = []
        self.collisions: list = []
        self.warnings: list = []
        self.events = 0
        self.continued: list[Array] = []
        self.last: Optional[Sample] = None

    @property
    def steps(self) -> int:
        return len(self.rows) - 1

    def add(self, sample: Sample, ds: float, newton: NewtonResult, t: Array, solves: int,
            tracked: Optional[Array] = None) -> None:
        """Record an accepted point (with a spectral window, Branch.continued too)."""
        u, p = sample.x[:-1].copy(), float(sample.x[-1])
        kappa = (np.full(sample.eigvals.size, np.nan) if sample.system is None
                 else condition_numbers(sample.system))
        self.rows.append((p, u, sample.eigvals, count_complex_pairs(sample.eigvals, self.rel_tol),
                          ds, newton.iterations, newton.residual, t, solves, kappa))
        if sample.disc is not None:
            self.continued.append(continued_labels(self.last, sample, tracked, self.rho))
            self.last = sample.without_vectors()
        if self.callback is not None:
            self.callback(len(self.rows) - 1, p, u, sample.eigvals)

    def branch(self, status: Stop) -> Branch:
        cols = list(zip(*self.rows))
        return Branch(p=np.array(cols[0]), u=np.array(cols[1]), eigenvalues=np.array(cols[2]),
                      n_complex=np.array(cols[3]), ds=np.array(cols[4]),
                      newton_iterations=np.array(cols[5]), residual=np.array(cols[6]),
                      tangent=np.array(cols[7]), detection_solves=np.array(cols[8]),
                      collisions=tuple(self.collisions), status=status, warnings=tuple(self.warnings),
                      events=self.events, continued=np.array(self.continued) if self.continued else None,
                      condition=np.array(cols[9]))
