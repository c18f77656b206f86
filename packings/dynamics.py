"""Newtonian dynamics of a packing from a state of its shear branch (issue 25,
docs/packings.md#dynamics): velocity Verlet with the Coulomb cap, the contact rows found again
every few steps (the history carried by row), the strain held fixed.

M q'' = F(q, xi; gamma), M = diag(m_i, m_i, I_i) (packings/equilibria.mass_diagonal). The
history follows the motion by the chain's rule; sliding (the cap) is the only dissipation. The
energy budget E_k + U_n - W_t, W_t the work of the tangential forces on the disks, is conserved
by the exact dynamics whether or not contacts slide; its drift measures the integration error.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.packings.equilibria import REACH, carried
from diskfriction.packings.network import Network

STABLE_FRACTION = 0.05
"""The default time step is this fraction of velocity Verlet's limit 2 / omega_max (the
chain's default: docs/dynamics.md)."""


@dataclass(frozen=True)
class PackingRun:
    """Frames of a run: t (f,) [time], q (f, 3N), the energy budget E_k + U_n - W_t (f,)
    [energy], the kinetic energy (f,), sliding updates (f,) since the start, the step dt, and
    the histories xi of the contact rows at the end."""

    t: np.ndarray
    q: np.ndarray
    budget: np.ndarray
    kinetic: np.ndarray
    capped: np.ndarray
    dt: float
    xi: np.ndarray
    rows: np.ndarray


def time_step(eigenvalues: np.ndarray) -> float:
    """STABLE_FRACTION of 2 / omega_max, omega_max^2 = max |lambda| of M^-1 J [time]."""
    return STABLE_FRACTION * 2.0 / float(np.sqrt(np.abs(eigenvalues).max()))


def simulate(network: Network, q: np.ndarray, v: np.ndarray, xi: np.ndarray, rows: np.ndarray,
             gamma: float, mass: np.ndarray, dt: float, t_end: float, frames: int = 200
             ) -> PackingRun:
    """Run from (q, v, xi) over the contact rows `rows` to t_end with steps dt, `frames` frames
    evenly spaced (whole numbers of steps); the rows found again whenever the disks may have
    moved half the reach since the last search."""
    q, v, xi = q.copy(), v.copy(), xi.copy()
    params, inv_mass = network.params(gamma), 1.0 / mass
    reach = REACH * network.constants[0]
    steps = max(1, int(round(t_end / dt)))
    every = max(1, steps // frames)
    F, work, capped = np.empty(q.size), np.zeros(1), 0
    network.kernels.forces(q, xi, network.radii, rows, params, F)
    out = []

    def frame(t):
        kinetic = 0.5 * float(np.sum(mass * v * v))
        U = network.kernels.normal_energy_sum(q, network.radii, rows, params)
        out.append((t, q.copy(), kinetic + U - work[0], kinetic, capped))

    frame(0.0)
    done = 0
    while done < steps:
        speed = float(np.abs(v).max())
        between = max(1, min(every - done % every, int(0.5 * reach / (speed * dt + 1e-300))))
        capped += network.kernels.advance(q, v, xi, network.radii, rows, params, inv_mass, dt,
                                          between, F, work, 0.0)
        done += between
        new_rows = network.contacts(q, gamma, reach)
        xi = carried(rows, xi, new_rows)
        rows = new_rows
        network.kernels.forces(q, xi, network.radii, rows, params, F)
        if done % every == 0:
            frame(done * dt)
    t, qs, budget, kinetic, slid = (np.array(c) for c in zip(*out))
    return PackingRun(t, qs, budget, kinetic, slid, dt, xi, rows)


def distance(run: PackingRun, q_eq: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """The mass-weighted distance from the equilibrium, sqrt(sum m (q - q_eq)^2), per frame."""
    return np.sqrt(np.sum(mass * (run.q - q_eq) ** 2, axis=1))


def growth_rate(t: np.ndarray, d: np.ndarray, lo: float, hi: float) -> tuple[float, int]:
    """(sigma, maxima used): the slope of log d over the local maxima of d(t) with lo < d < hi
    (the oscillation of a complex pair's mode rides on e^(sigma t)); nan with fewer than 5."""
    peaks = [f for f in range(1, len(d) - 1) if d[f - 1] <= d[f] >= d[f + 1]]
    t, d = t[peaks], d[peaks]
    window = (d > lo) & (d < hi)
    if window.sum() < 5:
        return float("nan"), int(window.sum())
    return float(np.polyfit(t[window], np.log(d[window]), 1)[0]), int(window.sum())


def fastest_pair(eigenvalues: np.ndarray, rel_tol: float = 1e-9) -> tuple[int, float]:
    """(index, sigma) of the complex eigenvalue of M^-1 J with the largest growth rate sigma =
    |Im sqrt(lambda)|; (-1, 0) when every eigenvalue is real."""
    lam = eigenvalues.astype(complex)
    sigma = np.where(np.abs(lam.imag) > rel_tol * np.abs(lam).max(), np.abs(np.sqrt(lam).imag), 0.0)
    i = int(np.argmax(sigma))
    return (i, float(sigma[i])) if sigma[i] > 0 else (-1, 0.0)


def mean_squared_displacement(run: PackingRun, N: int, disks: np.ndarray) -> np.ndarray:
    """MSD(t) = mean over the chosen disks (bool (N,)) of |r_i(t) - r_i(0)|^2, per frame
    [length^2]."""
    dx = run.q[:, :N] - run.q[:1, :N]
    dy = run.q[:, N:2 * N] - run.q[:1, N:2 * N]
    return np.mean((dx * dx + dy * dy)[:, disks], axis=1)
