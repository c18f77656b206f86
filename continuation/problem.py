"""The continuation problem: what the core needs to know about G(u, p) = 0.

A problem is a smooth map G: R^n x R -> R^n of a state u and one parameter p. The core
follows the curve {(u, p): G(u, p) = 0} and watches the spectrum of a stability matrix
A(u, p) along it. It knows nothing else about the problem (units, meaning of u, ...).

Required:
    residual(u, p)  -> G(u, p),        shape (n,)
    jacobian(u, p)  -> dG/du (u, p),   dense, shape (n, n)
    dG_dp(u, p)     -> dG/dp (u, p),   shape (n,)
Optional hooks (defaults below):
    commit(u_old, p_old, u_new, p_new) -> None | bool
        Called once when the step (u_old, p_old) -> (u_new, p_new) is accepted, after event
        detection on that step. A problem that carries state alongside u (e.g. the tangential
        history of contacts) updates it here; until then residual/jacobian must describe a step
        taken from the last committed point. Return True if the commit changed the problem so
        that (u_new, p_new) must be corrected again (the core then re-solves at fixed p_new).
    stability_matrix(u, p) -> A(u, p), shape (n, n); default dG/du.
    spectrum(u, p) -> eigenvalues of A(u, p) (complex, any order); default numpy.linalg.eigvals.
        Override only to use a faster solver for the same matrix: collision eigenvectors are
        computed from stability_matrix.
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Callable, Optional

import numpy as np

Array = np.ndarray


class Problem(ABC):
    """Base class of a one-parameter problem G(u, p) = 0 (see the module docstring)."""

    @abstractmethod
    def residual(self, u: Array, p: float) -> Array:
        """G(u, p), shape (n,)."""

    @abstractmethod
    def jacobian(self, u: Array, p: float) -> Array:
        """dG/du at (u, p), dense (n, n)."""

    @abstractmethod
    def dG_dp(self, u: Array, p: float) -> Array:
        """dG/dp at (u, p), shape (n,)."""

    def commit(self, u_old: Array, p_old: float, u_new: Array, p_new: float) -> Optional[bool]:
        """Accept the step (u_old, p_old) -> (u_new, p_new); stateless problems do nothing."""
        return None

    def stability_matrix(self, u: Array, p: float) -> Array:
        """The matrix A(u, p) whose eigenvalues are tracked; default dG/du."""
        return self.jacobian(u, p)

    def spectrum(self, u: Array, p: float) -> Array:
        """All eigenvalues of A(u, p) (complex array, any order)."""
        return np.linalg.eigvals(self.stability_matrix(u, p))


@dataclass(frozen=True)
class FunctionProblem(Problem):
    """A stateless problem given by plain functions: G(u, p), G_u(u, p), G_p(u, p) and
    optionally the stability matrix A(u, p) (default G_u)."""

    G: Callable[[Array, float], Array]
    G_u: Callable[[Array, float], Array]
    G_p: Callable[[Array, float], Array]
    A: Optional[Callable[[Array, float], Array]] = None

    def residual(self, u, p):
        return np.asarray(self.G(u, p), dtype=float)

    def jacobian(self, u, p):
        return np.atleast_2d(np.asarray(self.G_u(u, p), dtype=float))

    def dG_dp(self, u, p):
        return np.asarray(self.G_p(u, p), dtype=float).reshape(-1)

    def stability_matrix(self, u, p):
        if self.A is None:
            return self.jacobian(u, p)
        return np.atleast_2d(np.asarray(self.A(u, p), dtype=float))
