"""The contact network of a packing, evaluated through its generated kernels (docs/packings.md).

State: q = (x_1..x_N, y_1..y_N, theta_1..theta_N) [length, rad] in unwrapped coordinates, the
strain gamma of the Lees-Edwards box [1], and the contacts as int64 rows (i, j, cx, cy): disk i
touches the image of disk j shifted by (cx L + cy gamma L, cy L). The history xi [length] has
one entry per contact row, in the same order; a row keeps its image while it lasts, so a
contact never jumps between images along a branch.
"""
from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Optional

import numpy as np
import scipy.sparse as sp

from diskfriction.scenes import Effects
from diskfriction.symbolic.generated import Progress
from diskfriction.symbolic.kernels import load_packing_kernels

D = 3  # x, y, theta per disk: a packing's disks rotate


@dataclass(frozen=True)
class Network:
    """N disks of radii `radii` in a periodic square box of side L, bound to the kernels of
    their contact law. constants = (R, k_n, k_t, mu) in raw units (R the small radius).
    frictional: whether the contacts carry tangential forces (a tangential law and mu > 0);
    without them no torque acts on a disk and every history is 0."""

    kernels: ModuleType
    radii: np.ndarray
    L: float
    constants: tuple[float, float, float, float]
    frictional: bool = True

    @classmethod
    def build(cls, radii: np.ndarray, L: float, k_n: float, k_t: float, mu: float,
              effects: Effects = Effects(), progress: Optional[Progress] = None) -> Network:
        """Bind the disks to the kernels of `effects` (generated and compiled on a cold cache)."""
        radii = np.ascontiguousarray(radii, dtype=float)
        return cls(load_packing_kernels(effects, progress), radii, float(L),
                   (float(radii.min()), float(k_n), float(k_t), float(mu)),
                   effects.pair_law != "none" and mu > 0.0)

    @property
    def N(self) -> int:
        return self.radii.size

    @property
    def ndof(self) -> int:
        return D * self.N

    def params(self, gamma: float) -> np.ndarray:
        """The kernels' params (R, k_n, k_t, mu, 0, L, gamma) (symbolic/packing_src.py)."""
        R, k_n, k_t, mu = self.constants
        return np.array([R, k_n, k_t, mu, 0.0, self.L, gamma])

    def contacts(self, q: np.ndarray, gamma: float, reach: float = 0.0) -> np.ndarray:
        """Rows (i, j, cx, cy), i < j, of the pairs whose nearest Lees-Edwards images overlap by
        delta > -reach [length] (a cell list, O(N))."""
        return self.kernels.near_pairs(q, self.radii, self.L, gamma, reach)

    def overlaps(self, q: np.ndarray, contacts: np.ndarray, gamma: float) -> np.ndarray:
        """delta = R_i + R_j - |r_ij| of every contact row [length]; active iff delta > 0."""
        delta = np.empty(contacts.shape[0])
        self.kernels.overlaps(q, self.radii, contacts, self.params(gamma), delta)
        return delta

    def normal_forces(self, q: np.ndarray, contacts: np.ndarray, gamma: float) -> np.ndarray:
        """|F_n| = the normal law at delta of every contact row, 0 where open [force]."""
        delta = self.overlaps(q, contacts, gamma)
        return np.where(delta > 0, self.kernels.normal_force(np.maximum(delta, 0.0),
                                                             self.constants[1]), 0.0)

    def forces(self, q: np.ndarray, xi: np.ndarray, contacts: np.ndarray, gamma: float
               ) -> np.ndarray:
        """Generalized forces F(q, xi; gamma) [force; torque for the angles]."""
        F = np.empty(self.ndof)
        self.kernels.forces(q, xi, self.radii, contacts, self.params(gamma), F)
        return F

    def evaluate(self, q: np.ndarray, xi: np.ndarray, contacts: np.ndarray, gamma: float
                 ) -> tuple[np.ndarray, sp.csr_matrix, np.ndarray]:
        """F, the sparse total stiffness J = -dF/dq (history following q) [force / length] and
        dF/dgamma (history following gamma) [force]."""
        rows, cols = self.jacobian_pattern(contacts)
        F, values, F_gamma = self.evaluate_values(q, xi, contacts, gamma)
        return F, sp.csr_matrix((values, (rows, cols)), shape=(self.ndof, self.ndof)), F_gamma

    def jacobian_pattern(self, contacts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(rows, cols) of J's entries over the contact rows, one per value of evaluate_values
        (duplicates summed)."""
        return self.kernels.jacobian_pattern(self.N, contacts)

    def evaluate_values(self, q: np.ndarray, xi: np.ndarray, contacts: np.ndarray, gamma: float
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """evaluate with J as its values on jacobian_pattern(contacts)."""
        F, F_gamma = np.empty(self.ndof), np.empty(self.ndof)
        values = np.empty(contacts.shape[0] * (2 * D) ** 2)  # a (2D)^2 block per contact row
        self.kernels.evaluate(q, xi, self.radii, contacts, self.params(gamma), F, values, F_gamma)
        return F, values, F_gamma

    def history_step(self, q0: np.ndarray, q1: np.ndarray, gamma0: float, gamma1: float,
                     xi0: np.ndarray, contacts: np.ndarray, cap: bool = True
                     ) -> tuple[np.ndarray, np.ndarray]:
        """xi after the straight step (q0, gamma0) -> (q1, gamma1) over fixed contact rows: the
        midpoint increment, the chain's history rule (reset where open at the end, the part
        after first contact where closing, with `cap` the Coulomb cap |xi| <= t*). Returns
        (xi1, slid), slid True where the cap acted; without tangential forces xi1 = 0 and no
        cap acts."""
        m = contacts.shape[0]
        if not self.frictional:
            return np.zeros(m), np.zeros(m, dtype=np.bool_)
        dxi, xi1, slid = np.empty(m), np.empty(m), np.empty(m, dtype=np.bool_)
        self.kernels.history_increment(q0, q1, gamma0, gamma1, self.radii, contacts,
                                       self.params(gamma0), dxi)
        self.kernels.commit_history(xi0, dxi, self.overlaps(q0, contacts, gamma0),
                                    self.overlaps(q1, contacts, gamma1), self.params(gamma1),
                                    cap, xi1, slid)
        return xi1, slid

    def carried_forces(self, q0: np.ndarray, q1: np.ndarray, xi0: np.ndarray, delta0: np.ndarray,
                       contacts: np.ndarray, gamma: float
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(F(q1, xi1), xi1, delta1) at fixed strain: xi1 = history_step(q0, q1, gamma, gamma,
        xi0, contacts)[0] (the cap on), delta1 the overlaps at q1, given delta0 those at q0
        (one compiled call: a relaxation's force evaluation)."""
        m = contacts.shape[0]
        F, xi1, delta1 = np.empty(self.ndof), np.empty(m), np.empty(m)
        self.kernels.carried_forces(q0, q1, xi0, delta0, self.radii, contacts, self.params(gamma),
                                    F, xi1, delta1)
        return F, xi1 if self.frictional else np.zeros(m), delta1

    def stress(self, q: np.ndarray, xi: np.ndarray, contacts: np.ndarray, gamma: float
               ) -> np.ndarray:
        """The contact stress (sigma_xx, sigma_yy, sigma_xy, sigma_yx) [force / length],
        sigma_ab = -(1 / L^2) sum r_ij,a f_ij,b: compression negative; the pressure is
        P = -(sigma_xx + sigma_yy) / 2 and the shear stress under positive strain sigma_xy."""
        sigma = np.empty(4)
        self.kernels.stress(q, xi, self.radii, contacts, self.params(gamma), sigma)
        return sigma


def frictionless_forces(kernels: ModuleType, k_n: float):
    """The preparation's pair_forces (models/packing/prepare.py) from a packing's kernels:
    (positions (N, 2), radii, L) -> (F (N, 2) [force], U [energy], virial [energy]) of the
    frictionless normal forces at gamma = 0 (kernels.frictionless)."""

    def pair_forces(positions: np.ndarray, radii: np.ndarray, L: float):
        N = radii.size
        F = np.empty(2 * N)
        U, W = kernels.frictionless(np.ascontiguousarray(positions.T).ravel(), radii, L, k_n, F)
        return F.reshape(2, N).T, U, W

    return pair_forces
