"""The continuation problem: what the core needs to know about G(u, p) = 0.

A problem is a smooth map G: R^n x R -> R^n of a state u and one parameter p. The core
follows the curve {(u, p): G(u, p) = 0} and watches the spectrum of a stability matrix
A(u, p) along it. It knows nothing else about the problem (units, meaning of u, ...).

Required:
    residual(u, p)  -> G(u, p),        shape (n,)
    jacobian(u, p)  -> dG/du (u, p),   shape (n, n), a dense ndarray or a scipy.sparse matrix
                                       (the core factorizes it with LAPACK or SuperLU, as the
                                       run's linalg.solves.LinearSolver says)
    dG_dp(u, p)     -> dG/dp (u, p),   shape (n,)
Optional hooks (defaults below):
    commit(u_old, p_old, u_new, p_new) -> None | bool
        Called once when the step (u_old, p_old) -> (u_new, p_new) is accepted, after collision
        detection on that step. A problem that carries state alongside u (e.g. the tangential
        history of contacts) updates it here; until then residual/jacobian must describe a step
        taken from the last committed point. Return True if the commit changed the problem so
        that (u_new, p_new) must be corrected again (the core then re-solves at fixed p_new).
    state() -> a picklable snapshot of that state (default None: stateless);
    restore(snapshot) -> None: return to a snapshot taken by state() (default: nothing).
        The core scans a step on a worker process in the state committed at its start, and
        returns to an earlier state when a scan fails (scans.py): both need the pair.
    event_functions(u, p) -> array g or None (default None: no events)
        Discrete changes of the problem (a contact opening, closing, sliding). An event on a
        step is a component with g != 0 at the committed point whose sign changes (g = 0 at the
        end counts as a change from g > 0): the core ends the step on the first event (located
        on the branch), scans it for collisions, and commits there, so no step and no collision
        scan straddles a discrete change.
    root_events() -> bool mask over the event functions, or None (default: none): the
        components at whose zero the stability matrix goes as the square root of g on the
        side g > 0 (a Hertz contact opening or forming, stiffness ~ delta^(1/2)); a scan of a
        step ending on one treats that end apart (root_ends.py).
    stability_matrix(u, p) -> A(u, p), shape (n, n), dense or sparse; default dG/du.
    stability_structure(u, p) -> spectra.structure.StructuredMatrix: A(u, p) with what the
        eigensolvers may use of its structure (modes decoupled or gauged out of A, a matrix to
        shift-invert in its place, a symmetric form, a periodic block-tridiagonal layout);
        default StructuredMatrix(stability_matrix(u, p)): A alone, every eigenvalue tracked.
    derivative_step(x) -> h: length in x = (u, p) of the finite differences of A along a
        direction (eigenvalue slopes, the collision locator); default 1e-6 (1 + max|x|).
"""
from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Callable, ClassVar, Optional

import numpy as np
import scipy.sparse as sp

from diskfriction.continuation.spectra.structure import StructuredMatrix

Array = np.ndarray

ROUNDING = 16 * np.finfo(float).eps
"""A user's G rounds to about this times the size of its terms (a few roundings per term of a
sum; 3.6e-15): FunctionProblem's rounding."""


class Problem(ABC):
    """Base class of a one-parameter problem G(u, p) = 0 (see the module docstring): its
    equations, the state it carries along the branch and its events. How its linear systems
    and spectra are solved is the run's choice, not the problem's (Options.linear_solver,
    Options.eigensolver).

    rounding: 0, or the relative rounding of G's evaluation: a Newton iterate with max|G| <=
    rounding * max_i sum_j |dG_i/dx_j| |x_j| (the size of the terms that cancel in G,
    newton.term_size) is converged whatever newton_tol asks (newton.bordered_newton)."""

    rounding: float = 0.0

    @abstractmethod
    def residual(self, u: Array, p: float) -> Array:
        """G(u, p), shape (n,)."""

    @abstractmethod
    def jacobian(self, u: Array, p: float):
        """dG/du at (u, p), (n, n): dense ndarray or scipy.sparse."""

    @abstractmethod
    def dG_dp(self, u: Array, p: float) -> Array:
        """dG/dp at (u, p), shape (n,)."""

    def commit(self, u_old: Array, p_old: float, u_new: Array, p_new: float) -> Optional[bool]:
        """Accept the step (u_old, p_old) -> (u_new, p_new); stateless problems do nothing.
        True asks the core to solve again at p_new, from resolve_start(u_new)."""
        return None

    def resolve_start(self, u_new: Array) -> Array:
        """Where the core solves again after a commit that asked for it: u_new, the accepted
        point, unless the commit moved part of the state (a packing's loose disks giving way)."""
        return u_new

    def state(self) -> object:
        """A picklable snapshot of the committed state; stateless problems have none."""
        return None

    def restore(self, snapshot: object) -> None:
        """Return to a snapshot taken by state(); stateless problems have nothing to restore."""

    def event_functions(self, u: Array, p: float) -> Optional[Array]:
        """Event functions (see the module docstring); None: the problem has no events."""
        return None

    def root_events(self) -> Optional[Array]:
        """Mask of the event functions whose zero is a square-root point of the stability
        matrix (see the module docstring); None: none."""
        return None

    def stability_matrix(self, u: Array, p: float):
        """The matrix A(u, p) whose eigenvalues are tracked; default dG/du."""
        return self.jacobian(u, p)

    def stability_structure(self, u: Array, p: float) -> StructuredMatrix:
        """A(u, p) with its structure (spectra/structure.py); default: A alone."""
        return StructuredMatrix(self.stability_matrix(u, p))

    def derivative_step(self, x: Array) -> float:
        """Finite-difference length along a unit direction in x = (u, p)."""
        return 1e-6 * (1.0 + float(np.max(np.abs(x))))


@dataclass(frozen=True)
class FunctionProblem(Problem):
    """A stateless problem given by plain functions: G(u, p), G_u(u, p), G_p(u, p) and
    optionally the stability matrix A(u, p) (default G_u). Its rounding is ROUNDING: an
    absolute newton_tol below what G can be computed to (a discretised u'' with entries 1/h^2)
    does not stop the run."""

    G: Callable[[Array, float], Array]
    G_u: Callable[[Array, float], Array]
    G_p: Callable[[Array, float], Array]
    A: Optional[Callable[[Array, float], Array]] = None

    rounding: ClassVar[float] = ROUNDING

    def residual(self, u, p):
        return np.asarray(self.G(u, p), dtype=float)

    def jacobian(self, u, p):
        return matrix(self.G_u(u, p))

    def dG_dp(self, u, p):
        return np.asarray(self.G_p(u, p), dtype=float).reshape(-1)

    def stability_matrix(self, u, p):
        if self.A is None:
            return self.jacobian(u, p)
        return matrix(self.A(u, p))


def matrix(M):
    """A user's matrix as the core takes it: a scipy.sparse one as a float CSR matrix (SuperLU
    factorizes it, spectra take it dense), anything else as a 2-D float ndarray."""
    if sp.issparse(M):
        return sp.csr_array(M, dtype=float)
    return np.atleast_2d(np.asarray(M, dtype=float))
