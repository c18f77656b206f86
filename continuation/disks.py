"""Equilibria of the disk chain as a continuation problem, with the tangential history carried.

u = q (MODEL.md layout), p = F_x. The committed state (q_c, xi_c) is the last accepted point.
The residual of a trial q is the quasistatic step from it:

    G(q, F_x) = F(q, xi(q); F_x),  xi(q) = history rule from (q_c, xi_c) to q, Coulomb cap included,

dG/dq = -J(q, xi(q)) (the total stiffness, history following q), dG/dF_x = e_(x_1).
MODEL.md solves with the uncapped history and caps afterwards; the smoothed law beyond t* falls
(phi(u) decreases for u > 1), so that problem has no equilibrium once a contact must slide.
Capping inside the residual (return mapping) is the limit of MODEL.md's procedure for small steps
and equal to it while nothing slides. For the smoothed law J stays exact at the cap: there
dF_t/dxi = 0 and dF_t/ddelta is the same at fixed xi and at fixed u = xi / t*. For the linear
law J is the sticking tangent at a sliding contact, and Newton converges only linearly there.
On commit the step is split at the first contact event inside it (a contact opening or closing,
or a history reaching its Coulomb limit): the event is located on the branch by secant
iteration, the state is committed exactly there (reset, first contact, cap), and the core
re-solves the end of the step from it. The committed history is therefore integrated piecewise
straight between events and accepted points, with the midpoint rule's O(|dq|^3) error per piece.
"""
from __future__ import annotations

import numpy as np

from diskfriction.continuation.problem import Problem
from diskfriction.symbolic import System

EVENT_TOL = 1e-13
"""Events are located to |dF_x| <= EVENT_TOL (raw force units)."""


class EquilibriumError(RuntimeError):
    """No equilibrium could be converged."""


class DiskEquilibria(Problem):
    """The continuation problem of one System (see the module docstring)."""

    def __init__(self, system: System, q: np.ndarray, xi: np.ndarray, F_x: float,
                 matrix: str | None = None, newton_tol: float = 1e-11):
        self.system = system
        self.matrix = matrix or system.scene.matrix
        self.newton_tol = newton_tol
        self.q_c, self.xi_c, self.F_c = q.copy(), xi.copy(), float(F_x)
        self.e_x1 = np.zeros(system.ndof)
        self.e_x1[0] = 1.0
        self.events = 0  # contact events split off so far
        self.unsplit = 0  # events that could not be located (fixed-F_x solve failed, e.g. at a fold)
        self._last = (None, None, None)  # (q bytes, xi, J or None) of the last trial q

    # -- the history and its stiffness at a trial q
    def trial(self, q: np.ndarray, cap: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """History at q reached by a straight step from the committed state, and slid flags."""
        return self.system.history_step(self.q_c, q, self.xi_c, cap=cap)

    def _xi(self, q: np.ndarray) -> np.ndarray:
        """Trial history at q, kept for the last q (Newton asks residual then jacobian)."""
        key = q.tobytes()
        if self._last[0] != key:
            self._last = (key, self.trial(q)[0], None)
        return self._last[1]

    def _J(self, q: np.ndarray) -> np.ndarray:
        xi = self._xi(q)
        if self._last[2] is None:
            self._last = (self._last[0], xi, self.system.jacobian(q, xi))
        return self._last[2]

    # -- Problem protocol
    def residual(self, q, F_x):
        return self.system.forces(q, self._xi(q), F_x)

    def jacobian(self, q, F_x):
        return -self._J(q)

    def dG_dp(self, q, F_x):
        return self.e_x1

    def stability_matrix(self, q, F_x):
        return self.system.stability_matrix(self._J(q), self.matrix)

    def commit(self, q_old, F_old, q_new, F_new) -> bool:
        """Commit the step, split at its first contact event. True asks the core to re-solve
        the step's end: after a split, or when the Coulomb cap changed a history."""
        try:
            F_e, q_e = self._first_event(q_new, F_new)
        except EquilibriumError:
            self.unsplit += 1
            F_e = None
        if F_e is None:
            return self._set_committed(q_new, F_new)
        self._set_committed(q_e, F_e)
        self.events += 1
        return True

    # -- events
    def _set_committed(self, q, F_x) -> bool:
        self.xi_c, slid = self.trial(q)
        self.q_c, self.F_c = q.copy(), float(F_x)
        self._last = (None, None, None)
        return bool(slid.any())

    def event_functions(self, q: np.ndarray) -> np.ndarray:
        """Per contact: delta, then t* - |xi| of the uncapped history of active contacts (1 for
        open ones) at q. A strict sign change of either along a step is an event."""
        delta = self.system.overlaps(q)
        xi = self.trial(q, cap=False)[0]
        s = self.system.scene
        margin = s.mu * s.k_n * delta / s.k_t - np.abs(xi)
        return np.concatenate([delta, np.where(delta > 0, margin, 1.0)])

    def _first_event(self, q_new, F_new):
        """(F_x, q) just past the first event between the committed point and (q_new, F_new),
        or (None, None). Contacts at exactly zero at the committed point (touching, or at the
        Coulomb limit) are not events: the history rule treats them exactly."""
        g0, g1 = self.event_functions(self.q_c), self.event_functions(q_new)
        crossing = ((g0 > 0) & (g1 <= 0)) | ((g0 < 0) & (g1 > 0))
        if not crossing.any():
            return None, None
        frac = np.full(g0.shape, np.inf)
        frac[crossing] = g0[crossing] / (g0[crossing] - g1[crossing])
        c = int(np.argmin(frac))
        # Illinois regula falsi in F_x on the equilibrium branch; (F_far, q_far) stays past it
        F_near, g_near, q_near = self.F_c, g0[c], self.q_c
        F_far, g_far, q_far = F_new, g1[c], q_new
        side = 0
        while abs(F_far - F_near) > EVENT_TOL:
            F = F_far - g_far * (F_far - F_near) / (g_far - g_near)
            if not min(F_near, F_far) < F < max(F_near, F_far):
                F = 0.5 * (F_near + F_far)
            q = self.solve(q_near + (q_far - q_near) * (F - F_near) / (F_far - F_near), F)
            g = self.event_functions(q)[c]
            if (g > 0) == (g0[c] > 0):
                F_near, g_near, q_near = F, g, q
                g_far *= 0.5 if side == -1 else 1.0
                side = -1
            else:
                F_far, g_far, q_far = F, g, q
                g_near *= 0.5 if side == 1 else 1.0
                side = 1
        return F_far, q_far

    def solve(self, q_guess: np.ndarray, F_x: float, max_iter: int = 30) -> np.ndarray:
        """Equilibrium at fixed F_x from the committed state by Newton's method."""
        q = q_guess.copy()
        for _ in range(max_iter):
            G = self.residual(q, F_x)
            if np.abs(G).max() <= self.newton_tol:
                return q
            try:
                q = q - np.linalg.solve(self.jacobian(q, F_x), G)
            except np.linalg.LinAlgError:
                break
        raise EquilibriumError(f"no equilibrium at F_x = {F_x:.12g} (residual {np.abs(G).max():.3g})")


def relax(system: System, q: np.ndarray, xi: np.ndarray, F_x: float, tol: float = 1e-11,
          max_iter: int = 500) -> tuple[np.ndarray, np.ndarray]:
    """Equilibrium at F_x reached in one quasistatic step from (q, xi), by pseudo-transient
    continuation: (J + M / dt^2) dq = F with dt grown by the residual ratio (switched evolution
    relaxation). It converges where Newton cannot start: at the paper's rest state the pairs
    touch at delta = 0 and J has N zero (rolling) modes. Returns (q1, xi1) with xi1 committed."""
    problem = DiskEquilibria(system, q, xi, 0.0)
    M = np.diag(system.mass_diagonal())
    q1, dt = q.copy(), 1.0
    G = problem.residual(q1, F_x)
    r0 = np.linalg.norm(G)
    for _ in range(max_iter):
        if np.abs(G).max() <= tol:
            return q1, problem.trial(q1)[0]
        try:
            q1 = q1 + np.linalg.solve(-problem.jacobian(q1, F_x) + M / dt**2, G)
        except np.linalg.LinAlgError:
            break
        G = problem.residual(q1, F_x)
        r = np.linalg.norm(G)
        dt = min(dt * max(r0 / r, 0.5), 1e12)
        r0 = r
    raise EquilibriumError(f"relaxation did not converge at F_x = {F_x:.12g} (residual {np.abs(G).max():.3g})")
