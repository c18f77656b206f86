"""The disk chain of a scene, evaluated through its generated kernels, for any N.

State (docs/model.md#history): q = (x_1..x_N, y_1..y_N[, theta_1..theta_N]) [length, rad] and the history
xi = (xi_pair_1..xi_pair_N, xi_wall_1..xi_wall_N) [length]; pair k joins disk k and disk k+1,
pair N joins disk N and disk 1 across the periodic boundary (ring length L).
"""
from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Optional

import numpy as np

from diskfriction.matrices import Matrix
from diskfriction.scenes import Scene
from diskfriction.symbolic.generated import Progress
from diskfriction.symbolic.kernels import load_kernels


@dataclass(frozen=True)
class System:
    """A scene bound to the kernels its effects call for."""

    scene: Scene
    kernels: ModuleType
    params: np.ndarray  # (R, k_n, k_t, mu, F_y, L), raw units
    rows: np.ndarray  # row of each stored stiffness value
    cols: np.ndarray

    @classmethod
    def from_scene(cls, scene: Scene, progress: Optional[Progress] = None) -> System:
        """Bind `scene` to its kernels (generated and compiled on a cold cache, with
        progress(stage, fraction) as in symbolic.generated.load_generated)."""
        kernels = load_kernels(scene.resolved_effects, progress)
        params = np.array([scene.R, scene.k_n, scene.k_t, scene.mu, scene.F_y, scene.L])
        rows, cols = kernels.jacobian_pattern(scene.N)
        return cls(scene, kernels, params, rows, cols)

    @property
    def N(self) -> int:
        return self.scene.N

    @property
    def ndof(self) -> int:
        return self.kernels.D * self.scene.N

    def rest_state(self) -> tuple[np.ndarray, np.ndarray]:
        """The analytic F_x = 0 equilibrium: equal spacing L / N, every disk sunk by
        delta_w0 (F_n(delta_w0) = F_y; Hertz: (F_y / k_n)^(2/3)) into the substrate, all xi = 0
        (docs/model.md#history)."""
        s, N = self.scene, self.scene.N
        q = np.zeros(self.ndof)
        q[:N] = (np.arange(N) + 0.5) * (s.L / N)
        q[N:2 * N] = s.R - s.delta_w0
        return q, np.zeros(2 * N)

    def forces(self, q: np.ndarray, xi: np.ndarray, F_x: float) -> np.ndarray:
        """Generalized forces F(q, xi; F_x) [force; torque for angle dofs]."""
        F = np.empty(self.ndof)
        self.kernels.forces(q, xi, F_x, self.params, F)
        return F

    def forces_and_jacobian(self, q: np.ndarray, xi: np.ndarray, F_x: float
                            ) -> tuple[np.ndarray, np.ndarray]:
        """F and the dense total stiffness J = -dF/dq (history following q) [force / length]."""
        n = self.ndof
        F, J, Jvals = np.empty(n), np.empty((n, n)), np.empty(self.rows.size)
        self.kernels.evaluate_dense(q, xi, F_x, self.params, F, J, Jvals, self.rows, self.cols)
        return F, J

    def jacobian_values(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """Values of J = -dF/dq at (rows, cols) (duplicates add up) [force / length]."""
        F, Jvals = np.empty(self.ndof), np.empty(self.rows.size)
        self.kernels.evaluate(q, xi, 0.0, self.params, F, Jvals)
        return Jvals

    def jacobian(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """Dense J = -dF/dq; F_x is a dead load and does not enter it."""
        return self.forces_and_jacobian(q, xi, 0.0)[1]

    def mass_diagonal(self) -> np.ndarray:
        """diag(M): m for x and y, I = c m R^2 for theta."""
        N, s = self.N, self.scene
        M = np.full(self.ndof, s.m)
        M[2 * N:] = s.I
        return M

    def stability_matrix(self, J: np.ndarray, matrix: str | None = None) -> np.ndarray:
        """"J" (the paper's eq. 8) or "M^-1 J" (small oscillations M q'' = -J q); any other
        name is a ValueError (diskfriction.matrices.Matrix)."""
        matrix = Matrix(matrix or self.scene.matrix)
        return J if matrix is Matrix.J else J / self.mass_diagonal()[:, None]

    def overlaps(self, q: np.ndarray) -> np.ndarray:
        """delta of every contact (pairs, then substrate) [length]; active iff delta > 0."""
        delta = np.empty(2 * self.N)
        self.kernels.overlaps(q, self.params, delta)
        return delta

    def coulomb_limit(self, delta: np.ndarray) -> np.ndarray:
        """t*(delta) of every contact, the Coulomb limit of its history (kernels.coulomb_limit;
        Hertz: mu k_n delta / k_t), 0 where open (delta <= 0) [length]."""
        s = self.scene
        return self.kernels.coulomb_limit(np.maximum(delta, 0.0), s.k_n, s.k_t, s.mu)

    def history_step(self, q0: np.ndarray, q1: np.ndarray, xi0: np.ndarray, cap: bool = True
                     ) -> tuple[np.ndarray, np.ndarray]:
        """xi after the straight step q0 -> q1 (commit_history: midpoint increment, contacts
        opening reset, contacts closing charge only after first contact, and with `cap` the
        Coulomb cap |xi| <= t*). Returns (xi1, slid), slid[c] True where the cap acted.
        cap=False gives the trial history of a quasistatic step before the cap (docs/model.md#history)."""
        dxi = np.empty_like(xi0)
        self.kernels.history_increment(q0, q1, self.params, dxi)
        xi1 = np.empty_like(xi0)
        slid = np.empty(xi0.shape, dtype=np.bool_)
        self.kernels.commit_history(xi0, dxi, self.overlaps(q0), self.overlaps(q1), self.params,
                                    cap, xi1, slid)
        return xi1, slid
