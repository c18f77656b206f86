"""The arclength metric of solve_branch: |dx|^2 = p_scale^2 w |du|^2 + dp^2 [units of p],
w = theta / n (AUTO's and BifurcationKit's theta), so that the step count does not grow like
sqrt(n) with the mesh of a discretised problem (docs/api.md, Step length), and p_scale the
unit of p that u is weighed against, so that p in other units takes the same steps.

The core measures steps in the Euclidean length of its unknowns. Continuing the problem in
y = (s u, p), s = p_scale sqrt(w), makes that length the weighted one: Weighted is the problem
in y, and unweighted() maps what the core found back to u. The tracked matrix, its spectrum and
eigenvectors are the problem's own (A(u, p) at u = y_u / s): nothing about them is scaled.
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.problem import Problem

Array = np.ndarray


@dataclass(frozen=True)
class Weighted(Problem):
    """`inner` continued in y = (s u, p): G(y_u / s, p), dG/dy_u = G_u / s; every hook is the
    inner problem's at u = y_u / s. p_scale: the unit of p in s (derivative_step)."""

    inner: Problem
    s: float
    p_scale: float = 1.0

    def u(self, y: Array) -> Array:
        return np.asarray(y) / self.s

    @property
    def rounding(self) -> float:  # term_size is the same in y: |G_u / s| |s u| = |G_u| |u|
        return self.inner.rounding

    def residual(self, y, p):
        return self.inner.residual(self.u(y), p)

    def jacobian(self, y, p):
        return self.inner.jacobian(self.u(y), p) * (1.0 / self.s)

    def dG_dp(self, y, p):
        return self.inner.dG_dp(self.u(y), p)

    def commit(self, y_old, p_old, y_new, p_new):
        return self.inner.commit(self.u(y_old), p_old, self.u(y_new), p_new)

    def state(self):
        return self.inner.state()

    def restore(self, snapshot) -> None:
        self.inner.restore(snapshot)

    def event_functions(self, y, p):
        return self.inner.event_functions(self.u(y), p)

    def stability_matrix(self, y, p):
        return self.inner.stability_matrix(self.u(y), p)

    def stability_structure(self, y, p):
        return self.inner.stability_structure(self.u(y), p)

    def derivative_step(self, x: Array) -> float:
        """The inner step at (u, p / p_scale), times s: a unit direction in y moves u by up to
        1 / s; p is passed in units of p_scale, so that the step in y scales with the units of
        p (with p_scale = 1 it is the inner step at (u, p))."""
        return self.inner.derivative_step(np.append(self.u(x[:-1]), x[-1] / self.p_scale)) * self.s


def scale_of(theta: float | None, n: int) -> float:
    """sqrt(theta / n), 1 for theta None (plain Euclidean arclength): s for p_scale = 1."""
    return 1.0 if theta is None else float(np.sqrt(theta / n))


def unweighted(branch: Branch, s: float) -> Branch:
    """The branch the core found in y, in u: u = y_u / s, the tangent as the unit tangent in
    x = (u, p), the collisions' states divided by s."""
    t = np.column_stack([branch.tangent[:, :-1] / s, branch.tangent[:, -1]])
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    return replace(branch, u=branch.u / s, tangent=t,
                   collisions=tuple(replace(c, u=np.asarray(c.u) / s) for c in branch.collisions))
