"""The result of a continuation run: one object of arrays (one row per accepted point)."""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Optional

import numpy as np

from .collisions import Collision

Array = np.ndarray


@dataclass(frozen=True)
class Branch:
    """Accepted points k = 0..m-1 of a branch G(u, p) = 0.

    p (m,); u (m, n); eigenvalues (m, n) complex, tracked: column i is one eigenvalue followed
    along the branch; n_complex (m,): number of complex pairs (spectra.count_complex_pairs);
    ds (m,): arclength step that reached the point (0 for the first); newton_iterations (m,):
    corrector updates; residual (m,): max|G| at the stored point; tangent (m, n+1): unit
    tangent in x = (u, p); detection_solves (m,): corrector solves spent on collision detection
    in the step ending at the point; collisions: located births and deaths in branch order;
    status: why the run stopped ("p_end", "turned back: ...", "max_steps", "ds_min: ...");
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
    status: str
    warnings: tuple[str, ...] = ()
    events: int = 0
    continued: Optional[Array] = None

    def __len__(self) -> int:
        return self.p.size

    @property
    def x(self) -> Array:
        """Rows (u, p), shape (m, n+1)."""
        return np.column_stack([self.u, self.p])


def stop_reason(status: str, points: int) -> str:
    """A run's status for a sentence, without its location: "p_end" -> "reached",
    "ds_min: corrector failed (...) at p=5.1" -> "corrector failed (...)", "turned back: the
    branch folded ... at p=1" -> "the branch folded ..."; points: the run's accepted points."""
    if status == "p_end":
        return "reached"
    if status == "max_steps":
        return f"the run stopped after {points} points"
    reason = re.sub(r"\s*at p=\S+$", "", status)
    return re.sub(r"^(ds_min|commit|turned back):\s*", "", reason)
