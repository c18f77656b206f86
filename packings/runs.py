"""A run of the dynamics from one state of a shear branch, perturbed, with its growth measured
against the spectrum's (docs/packings.md#dynamics): what `simulate PACKING --gamma G` does at
one state and `verify PACKING` at several.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.packings.dynamics import (PackingRun, distance, fastest_pair, growth_rate,
                                            simulate, time_step)
from diskfriction.packings.equilibria import PackingEquilibria, row_keys
from diskfriction.packings.network import Network
from diskfriction.packings.plastic import RelaxationFailed, relax
from diskfriction.packings.shear import PackingBranch

KINDS = ("eigenvector", "random-position", "random-velocity", "none")


class NoComplexPair(ValueError):
    """An eigenvector perturbation asked for at a state whose eigenvalues are all real."""


@dataclass(frozen=True)
class StateRun:
    """A run from state k of a branch: its strain, the state (q0, xi0, rows0), complex pairs,
    the perturbation (kind, amplitude [length, or length / time for random-velocity], the
    displacement + velocity it added), the step dt, the fastest pair's growth rate sigma_predicted = |Im sqrt(lambda)| of
    M^-1 J (0 if none), the run, its mass-weighted distance from the state, sigma_measured (nan
    with fewer than 5 maxima to fit, `maxima`) and the energy budget's largest drift."""

    k: int
    gamma: float
    q0: np.ndarray
    xi0: np.ndarray
    rows0: np.ndarray
    pairs: int
    kind: str
    amplitude: float
    kick: np.ndarray
    dt: float
    sigma_predicted: float
    run: PackingRun
    distance: np.ndarray
    sigma_measured: float
    maxima: int
    drift: float

    def settled(self, network: Network, f_tol: float) -> "AtRest":
        """Where the run's end relaxes at rest (FIRE on the frictional forces, the history
        following: packings/plastic.relax), against the state (AtRest; NOT_RELAXED where the
        relaxation fails)."""
        try:
            q, xi, rows, _ = relax(network, self.run.q[-1], self.run.xi, self.run.rows,
                                   self.gamma, f_tol)
        except RelaxationFailed:
            return NOT_RELAXED
        before = network.stress(self.q0, self.xi0, self.rows0, self.gamma)[2]
        after = network.stress(q, xi, rows, self.gamma)[2]
        N = network.N
        moved = np.hypot(q[:N] - self.q0[:N], q[N:2 * N] - self.q0[N:2 * N])
        start = set(touching(network, self.q0, self.rows0, self.gamma))
        rest = set(touching(network, q, rows, self.gamma))
        return AtRest(float(after / before - 1.0), float(moved.max() / network.constants[0]),
                      len(start - rest), len(rest - start))

    @property
    def slid(self) -> bool:
        """A contact reached its Coulomb limit during the run."""
        return bool(self.run.capped[-1] > 0)


SLIPPED = 1e-5
"""A run that changed no contact but sigma_xy at rest by more than this fraction slipped [1]:
on 24 disks the runs that only wobbled came back within 7.4e-8, the smallest slip changed it by
2.9e-4 (docs/packings.md#verify)."""


@dataclass(frozen=True)
class AtRest:
    """A run's end relaxed at rest against the state it started from: the relative change of
    sigma_xy, the largest displacement of a disk [R], and the contacts (delta > 0) that opened
    and that formed (None, and nan before them: the relaxation failed, NOT_RELAXED)."""

    stress_change: float
    moved: float
    opened: int | None
    formed: int | None

    @property
    def outcome(self) -> str:
        """'rearranged': the contact network changed, a plastic event; 'slipped': the same
        contacts, sigma_xy changed by more than SLIPPED (histories reset by sliding); 'came
        back': a wobble; 'not relaxed'."""
        if self.opened is None:
            return "not relaxed"
        if self.opened + self.formed > 0:
            return "rearranged"
        return "slipped" if abs(self.stress_change) > SLIPPED else "came back"


NOT_RELAXED = AtRest(float("nan"), float("nan"), None, None)
"""Where a run's end did not relax at rest."""


def touching(network: Network, q: np.ndarray, rows: np.ndarray, gamma: float) -> list[int]:
    """Keys (equilibria.row_keys) of the rows in contact, delta > 0, at (q, gamma)."""
    return row_keys(rows[network.overlaps(q, rows, gamma) > 0]).tolist()


def run_from_state(branch: PackingBranch, k: int, network: Network, mass: np.ndarray,
                   matrix: str, kind: str, amplitude: float, t_end: float, delta_0: float,
                   dt: float | None = None, seed: int = 0) -> StateRun:
    """Perturb state k (eigenvector: along the real part of the fastest complex pair's right
    eigenvector, mass-normalised; random-position / random-velocity: normal deviates from
    `seed`; none: the state as it is), integrate to t_end with dt (default time_step of the state's spectrum) and fit the
    growth of the distance between 10 times its start and 1e-3 delta_0. Raises NoComplexPair."""
    lam = branch.eigenvalues[k]
    q0, xi0, rows0, gamma = branch.q[k], branch.xi[k], branch.rows[k], float(branch.gamma[k])
    i, sigma = fastest_pair(lam)
    rng = np.random.default_rng(seed)
    q, v = q0.copy(), np.zeros_like(q0)
    if kind == "eigenvector":
        if i < 0:
            raise NoComplexPair(f"an eigenvector perturbation needs a complex pair at gamma = "
                                f"{gamma:g}, and there is none")
        mode = fastest_mode(branch, k, network, mass, matrix)
        q += amplitude * mode / np.sqrt(np.sum(mass * mode * mode))
    elif kind == "random-position":
        shift = rng.normal(size=q.size)
        q += amplitude * shift / np.sqrt(np.sum(mass * shift * shift))
    elif kind == "random-velocity":
        v = amplitude * rng.normal(size=q.size)
    elif kind != "none":
        raise ValueError(f"perturbation must be one of {', '.join(KINDS)} (got {kind!r})")
    step = dt or time_step(lam)
    run = simulate(network, q, v, xi0, rows0, gamma, mass, step, t_end, frames=2000)
    d = distance(run, q0, mass)
    measured, used = (growth_rate(run.t, d, 10 * max(d[0], 1e-300), 1e-3 * delta_0)
                      if kind != "none" else (float("nan"), 0))  # nothing grows from nothing
    return StateRun(k, gamma, q0, xi0, rows0, int(branch.n_complex[k]), kind, amplitude,
                    q - q0 + v, step, sigma, run, d, measured, used,
                    float(np.abs(run.budget - run.budget[0]).max()))


def fastest_mode(branch: PackingBranch, k: int, network: Network, mass: np.ndarray,
                 matrix: str) -> np.ndarray:
    """Re of the right eigenvector of state k's fastest-growing complex pair (dense spectrum);
    zeros when every eigenvalue is real."""
    lam = branch.eigenvalues[k]
    i, _ = fastest_pair(lam)
    if i < 0:
        return np.zeros(branch.q[k].size)
    problem = PackingEquilibria(network, branch.q[k], branch.xi[k], branch.rows[k],
                                float(branch.gamma[k]), mass, matrix)
    system = problem.eigensystem(branch.q[k], float(branch.gamma[k]), vectors=True)
    return np.real(system.vectors(int(np.argmin(np.abs(system.values - lam[i]))))[0])
