"""The result of a run: one object of arrays, frames every `stride` steps (raw units).

Observables (docs/model.md#targets):
  M(t)      = (1/N) sum_i |r_i(t) - r_i(0)|^2, disk centres only (no angles) [length^2];
  C(t)      = (1/N) sum_i r_i(t), the centre of mass (equal masses) [length];
  budget(t) = E_kin + U_n + U_load - W_t, constant up to O(dt^2) [energy], with
              E_kin = 1/2 v.M.v, U_n = sum over active contacts 2/5 k_n delta^(5/2) (Hertz),
              U_load = -F_x x_1 + F_y sum_i y_i (the dead loads), and W_t the work of the
              tangential (Mindlin) forces along the path, W_t = W_stick + W_slip, W_slip the part
              done at capped contacts on the distance they slid (<= 0: dissipated). The
              Mindlin force depends on delta, so F_n d delta + F_t d xi is not exact and W_t is
              not a function of the state: there is no tangential potential energy to add.

The budget's closure is the run's accuracy test (summarize: `accurate`): its error, relative to
the energy the run exchanged between the terms,
  E_x = max_t (|E_kin - E_kin(0)| + |U_n - U_n(0)| + |U_load - U_load(0)| + |W_t|) [energy],
must not exceed BUDGET_BOUND. A run whose dt resolves its fastest mode closes to ~1e-4 of E_x
(paper scene, F_x = 0.03 and 0.09, dt = 0.05 x 2 / omega_max, 1000 time units); one that goes
unstable, where a contact stiffens past the step's reach, exchanges energies of 1e6 and more
and closes only to 5-25 % of them.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.dynamics.start import Perturbation

Array = np.ndarray

BUDGET_BOUND = 1e-2
"""The largest budget error, as a fraction of the energy exchanged E_x, of a run whose results
are reported (module docstring): at 1 % the run resolves its dynamics; velocity Verlet at the
default step closes to ~1e-4, the error grows as dt^2, and an unstable run closes to no better
than ~5 %."""

ROUNDING_FLOOR = 1e-12
"""E_x is taken no smaller than this fraction of the terms' size |E_kin| + |U_n| + |U_load| at
t = 0, so that a run in which (almost) nothing moves is judged against rounding, not against
an exchange of 1e-20."""


def _column(k: int, doc: str) -> property:
    """Read-only view of column k of Trajectory.energy."""
    return property(lambda self: self.energy[:, k], doc=doc)


@dataclass(frozen=True)
class Trajectory:
    """One run from an equilibrium at load F_x plus a perturbation (raw units).

    t (f,) [time]; q, v (f, ndof) positions and velocities in docs/model.md's layout; energy (f, 5)
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

    def energy_exchanged(self) -> float:
        """E_x = max_t (|dE_kin| + |dU_n| + |dU_load| + |W_t|), changes since t = 0 [energy]."""
        moved = np.abs(self.energy[:, :3] - self.energy[0, :3]).sum(axis=1) + np.abs(self.W_t)
        return float(moved.max())

    def budget_relative(self) -> float:
        """budget_error / E_x, with E_x no smaller than ROUNDING_FLOOR times the terms' size
        at t = 0 [1]; inf if the budget is not finite (the run overflowed)."""
        size = float(np.abs(self.energy[0, :3]).sum())
        scale = max(self.energy_exchanged(), ROUNDING_FLOOR * size)
        error = self.budget_error()
        return error / scale if np.isfinite(error) and scale > 0 else (0.0 if error == 0 else np.inf)

    @property
    def accurate(self) -> bool:
        """The budget closes within BUDGET_BOUND of the energy exchanged."""
        return self.budget_relative() <= BUDGET_BOUND
