"""The result of a continuation run: one object of arrays (one row per accepted point)."""
from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum
from typing import Optional

import numpy as np

from .collisions import Collision

Array = np.ndarray


class StopCode(StrEnum):
    """Why a run stopped (arclength.py): it reached the end of the span it heads for, the
    branch folded and left the span on its starting side, the step limit, a step that had to
    shrink below ds_min, or a commit (Problem.commit) after which no equilibrium was found."""

    REACHED = "p_end"
    TURNED_BACK = "turned back"
    MAX_STEPS = "max_steps"
    DS_MIN = "ds_min"
    COMMIT = "commit"


MESSAGES = {
    StopCode.REACHED: "p_end",
    StopCode.MAX_STEPS: "max_steps",
    StopCode.DS_MIN: "ds_min: {reason} at p={p:.12g}",
    StopCode.COMMIT: "commit: {reason} at p={p:.12g}",
    StopCode.TURNED_BACK: "turned back: {reason} at p={p:.12g}",
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
    the step (the detection certified it), or samples.certified_labels certifies the step.
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

    def __len__(self) -> int:
        return self.p.size

    @property
    def x(self) -> Array:
        """Rows (u, p), shape (m, n+1)."""
        return np.column_stack([self.u, self.p])
