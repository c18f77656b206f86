"""A damping that acts on relative contact velocities only, as DEM codes apply it, and the
damped modes of a packing's state with it (issue 63; dynamics/quadratic_modes.py).

On every contact row (i, j, cx, cy) that overlaps (delta > 0), with n = r_ij / |r_ij| (r_ij =
r_i - r_j - (cx L + cy gamma L, cy L), models/packing/network.py) and s = (-n_y, n_x), the
relative velocity of the contact points at distance R_i and R_j from the centres has the normal
and tangential components

    v_n = n . (v_i - v_j),    v_t = s . (v_i - v_j) - (R_i omega_i + R_j omega_j)   [length / time]

(v_t = d xi / dt: the history increment's coefficients w, symbolic/contacts.py, so with its lever
arms R_i, R_j in both conventions), and a dashpot acts on each:

    F_t = -c_t v_t,   F_i = -c_n v_n n + F_t s = -F_j,   T_i = -R_i F_t,   T_j = -R_j F_t

[force; torque], the torques by the kernels' rule for a tangential force F_t. On the contact's
dofs u = (n, 0, -n, 0) and w = (s, -R_i, -s, -R_j) (disk i's x, y, theta, then j's) this is the
generalized force -C q' with

    C = sum over contacts of c_n u u^T + c_t w w^T    [mass / time; mass length / time for theta],

symmetric and positive semidefinite by construction, and zero on every velocity that moves no
contact point relative to its partner: a rigid translation of the packing (u and w sum to 0 over
x, and over y), and two disks rolling on each other (v_i = v_j, R_i omega_i = -R_j omega_j).
The image shift enters only through n: the perturbation's velocities carry no shear rate, and C
does not depend on the strain otherwise.

Rates (ContactDamping). As LAMMPS's pair gran/hooke (Silbert et al., PRE 64, 051302, 2001), a
dashpot's coefficient is a rate times the contact's reduced mass m_ij = m_i m_j / (m_i + m_j):

    c_n = eta m_ij,   c_t = ratio eta m_ij,   eta [1 / time], ratio [1],

so that the normal relative velocity of an isolated pair decays at the rate eta, and a small disk
of mass m on one contact with an immobile disk (m_j -> inf: m_ij = m) is damped along the normal
at eta, as the drag eta M damps it (models/packing/plastic.py drag_rate; the study gives eta as
damping omega_0). The ratio's default 1/2 is LAMMPS's (gamma_t = gamma_n / 2 when gamma_t is
NULL). The tangential relative velocity of an isolated pair of uniform disks (I = c m R^2)
decays at ratio eta (1 + 1 / c), 3 ratio eta for c = 1/2: its effective mass m_ij / (1 + 1 / c)
counts the rotations.

Which contacts carry a tangential dashpot: without tangential forces (Network.frictional false)
none, as DEM codes have no tangential force there; on a contact sliding at the committed state
(PackingEquilibria.sliding) none either: DEM codes cap the total tangential force, spring plus
dashpot, at mu F_n, so a sliding contact's dashpot changes no force to first order (the
smoothed law's stiffness there is about zero too).

The damped modes of a PackingEquilibria state (reduced_exponents, damped_spectrum) are those of
M q'' + C q' + J q = 0 in the coordinates of its tracked spectrum: z = P q (relative to the
reference disk, without the loose disks' dofs, nor the rotations without tangential forces;
equilibria.py), q' = E z' + T a' with T the translations. As J T = 0 and P T = 0,

    z'' + C_red z' + K_red z = 0,   K_red = P M^-1 J E (A_red for M^-1 J),   C_red = P M^-1 C E,

closed in z whatever C does to T (the drag eta M too: C_red = eta I, and the exponents are
dynamics/damped_modes.py's for A_red's eigenvalues); the translations' four zero exponents and the
loose disks' are left out, so the largest growth needs no zero told apart.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from diskfriction.dynamics.quadratic_modes import largest_growth, quadratic_exponents
from diskfriction.matrices import Matrix
from diskfriction.models.packing.network import D, Network

TANGENTIAL_RATIO = 0.5
"""The tangential dashpot's rate over the normal one's by default (LAMMPS's pair gran/hooke:
gamma_t = gamma_n / 2 when gamma_t is NULL) [1]."""


@dataclass(frozen=True)
class ContactDamping:
    """Dashpots on the contacts: c_n = rate m_ij, c_t = tangential_ratio rate m_ij with m_ij the
    pair's reduced mass (module docstring). rate [1 / time], tangential_ratio [1]."""

    rate: float
    tangential_ratio: float = TANGENTIAL_RATIO

    def coefficients(self, m_i: np.ndarray, m_j: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(c_n, c_t) of pairs of masses m_i, m_j [mass / time]."""
        reduced = m_i * m_j / (m_i + m_j)
        return self.rate * reduced, self.tangential_ratio * self.rate * reduced


@dataclass(frozen=True)
class DampedSpectrum:
    """The damped modes of a state: the 2k exponents s of det(s^2 + s C_red + K_red) = 0 on the
    k coordinates of its tracked spectrum, in decreasing real part [1 / time], and the largest
    growth rate max Re s [1 / time] (positive: a mode grows)."""

    exponents: np.ndarray
    growth: float


def contact_normals(network: Network, q: np.ndarray, rows: np.ndarray, gamma: float
                    ) -> tuple[np.ndarray, np.ndarray]:
    """(n (m, 2), delta (m,)): the unit normal r_ij / |r_ij| [1] from the image of j to i and the
    overlap R_i + R_j - |r_ij| [length] of every contact row at (q, gamma)."""
    N, L = network.N, network.L
    i, j, cx, cy = rows.T
    dx = q[i] - q[j] - (cx + cy * gamma) * L
    dy = q[N + i] - q[N + j] - cy * L
    rho = np.hypot(dx, dy)
    return np.stack([dx, dy], axis=1) / rho[:, None], network.radii[i] + network.radii[j] - rho


def damping_matrix(network: Network, q: np.ndarray, rows: np.ndarray, gamma: float,
                   mass: np.ndarray, damping: ContactDamping, tangential: np.ndarray
                   ) -> sp.csr_array:
    """C (3N x 3N, sparse) of the dashpots on the contact rows (i, j, cx, cy) that overlap at (q,
    gamma) (module docstring), the tangential one only where `tangential` (bool per row); mass:
    diag(M) (models/packing/equilibria.mass_diagonal)."""
    N = network.N
    n, delta = contact_normals(network, q, rows, gamma)
    touching = delta > 0
    rows, n, tangential = rows[touching], n[touching], np.asarray(tangential, bool)[touching]
    i, j = rows[:, 0], rows[:, 1]
    c_n, c_t = damping.coefficients(mass[i], mass[j])
    c_t = np.where(tangential, c_t, 0.0)
    s = np.stack([-n[:, 1], n[:, 0]], axis=1)
    zero = np.zeros(i.size)
    u = np.stack([n[:, 0], n[:, 1], zero, -n[:, 0], -n[:, 1], zero], axis=1)
    w = np.stack([s[:, 0], s[:, 1], -network.radii[i], -s[:, 0], -s[:, 1], -network.radii[j]],
                 axis=1)
    blocks = (c_n[:, None, None] * u[:, :, None] * u[:, None, :]
              + c_t[:, None, None] * w[:, :, None] * w[:, None, :])
    dofs = np.concatenate([np.arange(D)[None, :] * N + i[:, None],
                           np.arange(D)[None, :] * N + j[:, None]], axis=1)
    size = D * N
    return sp.csr_array(sp.coo_array(
        (blocks.ravel(), (np.repeat(dofs, 2 * D, axis=1).ravel(), np.tile(dofs, 2 * D).ravel())),
        shape=(size, size)))


def problem_damping(problem, q: np.ndarray, gamma: float, damping: ContactDamping
                    ) -> sp.csr_array:
    """C of a PackingEquilibria's active rows at (q, gamma): the rows whose forces act (none with
    a loose disk), tangential dashpots where the network is frictional and the row is not
    sliding at the committed state (module docstring)."""
    active = problem.active
    tangential = problem.network.frictional & ~problem.sliding[active]
    return damping_matrix(problem.network, q, problem.rows_c[active], gamma, problem.mass,
                          damping, tangential)


def reduced_pencil(problem, q: np.ndarray, gamma: float, C) -> tuple[np.ndarray, np.ndarray]:
    """(C_red, K_red), dense (k x k): P M^-1 C E [1 / time] and P M^-1 J E [1 / time^2] on the k
    coordinates of a PackingEquilibria's tracked spectrum at (q, gamma) (module docstring; M^-1
    J whatever the problem's matrix is); C (3N x 3N, dense or sparse) [mass / time]."""
    g = problem.gauge
    inverse_mass = sp.diags_array(1.0 / problem.mass)
    A = problem.physical(q, gamma)
    if problem.matrix is Matrix.J:
        A = inverse_mass @ A
    K_red = (g.P @ A).tocsc()[:, g.kept].toarray()
    C_red = (g.P @ (inverse_mass @ sp.csr_array(C))).tocsc()[:, g.kept].toarray()
    return C_red, K_red


def reduced_exponents(problem, q: np.ndarray, gamma: float, C) -> np.ndarray:
    """(2k,): the exponents of z'' + C_red z' + K_red z = 0 (reduced_pencil) [1 / time]."""
    C_red, K_red = reduced_pencil(problem, q, gamma, C)
    return quadratic_exponents(np.ones(K_red.shape[0]), C_red, K_red)


def damped_spectrum(problem, q: np.ndarray, gamma: float, damping: ContactDamping
                    ) -> DampedSpectrum:
    """The damped modes of a PackingEquilibria at (q, gamma) with the dashpots `damping` on its
    contacts (problem_damping, reduced_exponents): one dense eigendecomposition of size 2k."""
    exponents = reduced_exponents(problem, q, gamma, problem_damping(problem, q, gamma, damping))
    return DampedSpectrum(exponents, largest_growth(exponents))
