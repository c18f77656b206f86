"""Equilibria of frictional disks as a continuation problem: what the chain's
(models/chain/equilibria.py, DiskEquilibria) and the packing's (models/packing/equilibria.py,
PackingEquilibria) share.

u = q, the disks' coordinates [length, and rad for the angles]; p the load (the chain's force
F_x, the packing's Lees-Edwards strain gamma). The committed state (q_c, xi_c, p_c) is the last
accepted point; the residual of a trial (q, p) is the quasistatic step from it,

    G(q, p) = F(q, xi(q, p); p),   xi = the history rule from (q_c, xi_c) to (q, p), the
                                   Coulomb cap included (trial),

F the disks' generalized forces [force, and force x length for the torques], dG/dq = -J the
total stiffness with the history following q. The equations of exact zero modes (a disk that
may roll freely, a packing's translations, a loose disk) are replaced by gauge rows

    kappa m^T (q - q_c) = 0,   m a null direction, kappa a stiffness scale [force / length],

which hold those modes at their committed values (GaugeRows). The stability matrix's spectrum
(J or M^-1 J) is the coupled disks' and those modes': the problem declares which in its
StructuredMatrix (continuation/spectra/structure.py: decoupled blocks, or the zero modes of the
gauge), and the eigensolvers embed the coupled part's eigensystem and exclude the others from
collision detection. The finite-difference length along the branch is 0.1 of the smallest
acting overlap, within DERIVATIVE_STEP.
"""
from __future__ import annotations

from abc import abstractmethod
from dataclasses import dataclass
from typing import Callable

import numpy as np

from diskfriction.continuation.problem import Problem

Array = np.ndarray

DERIVATIVE_STEP = (1e-11, 1e-7)
"""Range of the finite-difference length along the branch (samples.matrix_derivative,
locate.py): 0.1 of the smallest acting overlap, within these bounds [length]."""


@dataclass(frozen=True)
class GaugeRows:
    """Gauge rows kappa m^T (q - q_c) = 0 (module docstring) in place of equation rows: for f
    groups of d coordinates (dofs (f, d)), k null directions each, the rows they replace (rows
    (f, k)) and their coefficients kappa m^T (weights (f, k, d)) [force / length]."""

    dofs: Array
    rows: Array
    weights: Array

    @classmethod
    def diagonal(cls, rows: Array, kappa: float) -> "GaugeRows":
        """The rows kappa (q_i - q_c,i) = 0 for each coordinate i in rows (f,)."""
        rows = np.asarray(rows)[:, None]
        return cls(rows, rows, np.full((rows.shape[0], 1, 1), kappa))

    def values(self, q: Array, q_c: Array) -> Array:
        """kappa m^T (q - q_c) of every gauge row, (f, k) [force]."""
        return np.einsum("fkd,fd->fk", self.weights, q[self.dofs] - q_c[self.dofs])


class Equilibria(Problem):
    """The continuation problem of disks with a tangential history (module docstring). A
    subclass sets the committed state (q_c, xi_c, p_c) and its gauge rows (gauge_rows, None:
    none) and gives the history rule (trial) and the overlaps of the contacts that act
    (acting_overlaps)."""

    q_c: Array
    xi_c: Array
    p_c: float
    gauge_rows = None
    _trial_key = None

    def committed(self) -> tuple[Array, float]:
        """(q_c, p_c): the point of the committed state (where api.solve_in_runs sizes a crowded
        window anew)."""
        return self.q_c, self.p_c

    @abstractmethod
    def trial(self, q: Array, p: float, cap: bool = True) -> tuple[Array, Array]:
        """(xi, slid): the history of every contact at (q, p) reached by a straight step from the
        committed state (capped at the Coulomb limit if `cap`), and the contacts the cap acted
        on."""

    @abstractmethod
    def acting_overlaps(self, x: Array) -> Array:
        """The overlaps delta of the contacts that act at x = (q, p) [length] (negative: open)."""

    def _at_trial(self, q: Array, p: float, part: str, compute: Callable[[], object]):
        """compute(), kept for the last trial point (q, p) under `part`: Newton asks the residual,
        then the Jacobian, at one point, and both need the history there."""
        key = (q.tobytes(), p)
        if self._trial_key != key:
            self._trial_key, self._trial = key, {}
        if part not in self._trial:
            self._trial[part] = compute()
        return self._trial[part]

    def _forget_trial(self) -> None:
        """Drop what _at_trial kept (the committed state changed)."""
        self._trial_key = None

    def _gauged(self, G: Array, q: Array) -> Array:
        """G with its gauge rows' equations replaced by kappa m^T (q - q_c) (in place)."""
        if self.gauge_rows is not None:
            G[self.gauge_rows.rows] = self.gauge_rows.values(q, self.q_c)
        return G

    def derivative_step(self, x: Array) -> float:
        """0.1 of the smallest acting overlap at x, within DERIVATIVE_STEP [length]."""
        delta = self.acting_overlaps(x)
        active = delta[delta > 0]
        h = 0.1 * float(active.min()) if active.size else DERIVATIVE_STEP[1]
        return min(max(h, DERIVATIVE_STEP[0]), DERIVATIVE_STEP[1])
