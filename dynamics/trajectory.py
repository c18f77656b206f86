"""The result of a run: one object of arrays, frames every `stride` steps (raw units).

Observables (MODEL.md):
  M(t)      = (1/N) sum_i |r_i(t) - r_i(0)|^2, disk centres only (no angles) [length^2];
  C(t)      = (1/N) sum_i r_i(t), the centre of mass (equal masses) [length];
  budget(t) = E_kin + U_n + U_load - W_t, constant up to O(dt^2) [energy], with
              E_kin = 1/2 v.M.v, U_n = sum over active contacts 2/5 k_n delta^(5/2) (Hertz),
              U_load = -F_x x_1 + F_y sum_i y_i (the dead loads), and W_t the work of the
              tangential (Mindlin) forces along the path, W_t = W_stick + W_slip, W_slip the part
              done at capped contacts on the distance they slid (<= 0: dissipated). The
              Mindlin force depends on delta, so F_n d delta + F_t d xi is not exact and W_t is
              not a function of the state: there is no tangential potential energy to add.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.dynamics.start import Perturbation

Array = np.ndarray


def _column(k: int, doc: str) -> property:
    """Read-only view of column k of Trajectory.energy."""
    return property(lambda self: self.energy[:, k], doc=doc)


@dataclass(frozen=True)
class Trajectory:
    """One run from an equilibrium at load F_x plus a perturbation (raw units).

    t (f,) [time]; q, v (f, ndof) positions and velocities in MODEL.md's layout; energy (f, 5)
    columns E_kin, U_n, U_load, W_t, W_slip (see the module docstring); slip (f, N) signed
    distance each substrate contact has slid (sum over its capped steps of the excess the cap
    removed) [length]. breach_t, breach_x (N,): first time the Coulomb cap acts at the
    substrate contact of disk i and x_i then (nan, and breach_t = nan, if never).
    onset_t, onset_x (N,): onset of sliding of disk i (dynamics/onset.py; nan if never).
    eigenvalues (ndof,): spectrum of M^-1 J at the equilibrium; sigma_predicted its largest
    |Im sqrt(lambda)| (0 if all real), omega_predicted Re sqrt(lambda) of that pair (0 if none).
    overlaps0 (2N,): delta of every contact at the equilibrium (pairs, then substrate).
    """

    t: Array
    q: Array
    v: Array
    energy: Array
    slip: Array
    breach_t: Array
    breach_x: Array
    onset_t: Array
    onset_x: Array
    F_x: float
    dt: float
    stride: int
    steps: int
    N: int
    eigenvalues: Array
    sigma_predicted: float
    omega_predicted: float
    overlaps0: Array
    perturbation: Perturbation

    # -- configuration
    @property
    def x(self) -> Array:
        """x_i(t), (f, N) [length]."""
        return self.q[:, :self.N]

    @property
    def y(self) -> Array:
        """y_i(t), (f, N) [length]."""
        return self.q[:, self.N:2 * self.N]

    @property
    def theta(self) -> Array | None:
        """theta_i(t), (f, N) [rad]; None without rotation."""
        return self.q[:, 2 * self.N:] if self.q.shape[1] == 3 * self.N else None

    @property
    def M(self) -> Array:
        """M(t) = (1/N) sum_i |r_i(t) - r_i(0)|^2 [length^2]."""
        return ((self.x - self.x[0]) ** 2 + (self.y - self.y[0]) ** 2).mean(axis=1)

    @property
    def C_x(self) -> Array:
        return self.x.mean(axis=1)

    @property
    def C_y(self) -> Array:
        return self.y.mean(axis=1)

    # -- energy budget: the columns of `energy` (E_KIN.. in dynamics/stepper_src.py)
    E_kin = _column(0, "Kinetic energy 1/2 v.M.v [energy].")
    U_n = _column(1, "Hertz energy sum 2/5 k_n delta^(5/2) over active contacts [energy].")
    U_load = _column(2, "Load potential -F_x x_1 + F_y sum_i y_i [energy].")
    W_t = _column(3, "Work of the tangential forces since t = 0 [energy].")
    W_slip = _column(4, "Part of W_t done on the distance slid at capped contacts (<= 0) [energy].")

    @property
    def W_stick(self) -> Array:
        """Part of W_t done while sticking [energy]."""
        return self.W_t - self.W_slip

    @property
    def budget(self) -> Array:
        """E_kin + U_n + U_load - W_t: constant up to O(dt^2) [energy]."""
        return self.E_kin + self.U_n + self.U_load - self.W_t

    def budget_error(self) -> float:
        """max_t |budget(t) - budget(0)| [energy]."""
        return float(np.abs(self.budget - self.budget[0]).max())
