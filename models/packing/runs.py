"""A run of the dynamics from one state of a shear branch, perturbed, with its growth measured
against the spectrum's (docs/packings.md#dynamics): what `simulate PACKING --gamma G` does at
one state and `verify PACKING` at several.

Small motions about the state (q_eq, xi_eq) obey M dq'' = -J dq, J the total stiffness with the
history following q (models/packing/equilibria.py), so the spectrum that governs them is that of
M^-1 J, whatever matrix the branch tracked. A complex pair lambda with sqrt(lambda) = omega +
i sigma (sigma > 0) has the growing solution dq = Re(c_0 V e^(s t)), s = sigma - i omega, V the
right eigenvector of M^-1 J. Its complex amplitude c(t) = (s W dq + W dq') / s, W the left
eigenvector (W M^-1 J = lambda W, W V = 1), picks that solution out of any motion: in the
linear dynamics |c| = |c_0| e^(sigma t) exactly, without the oscillation, and the other modes
(the decaying partner, the other pairs, the translations) do not enter it.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.continuation.spectra.tracking import count_complex_pairs
from diskfriction.models.packing.dynamics import (LINEAR_RANGE, GrowthFit, PackingRun, distance,
                                            fastest_pair, fit_growth, no_fit, simulate, time_step)
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.models.packing.equilibria import PackingEquilibria, row_keys
from diskfriction.models.packing.network import Network
from diskfriction.models.packing.plastic import RelaxationFailed, relax
from diskfriction.continuation.branch import Branch

KINDS = ("eigenvector", "random-position", "random-velocity", "none")


class NoComplexPair(ValueError):
    """An eigenvector perturbation asked for at a state whose eigenvalues are all real."""


FRAMES = 2000
"""Frames recorded per run, evenly spaced in time."""


@dataclass(frozen=True)
class GrowingMode:
    """The growing solution of a complex pair lambda of M^-1 J [1 / time^2] (module docstring):
    right (n,), V with M^-1 J V = lambda V in every coordinate (the translations included), at
    the phase of its largest mass-weighted displacement (Re V and Im V M-orthogonal, |Re V|_M >=
    |Im V|_M) and scaled to |Re V|_M = sqrt(sum m (Re V)^2) = 1; left (n,), W with W M^-1 J =
    lambda W and W V = 1."""

    lam: complex
    right: np.ndarray
    left: np.ndarray

    @property
    def s(self) -> complex:
        """s = sigma - i omega with sqrt(lambda) = omega + i sigma: dq ~ e^(s t) grows [1 / time]."""
        root = np.sqrt(complex(self.lam))
        return complex(abs(root.imag), -root.real)

    @property
    def sigma(self) -> float:
        """The growth rate |Im sqrt(lambda)| [1 / time]."""
        return self.s.real

    def amplitude(self, dq: np.ndarray, v: np.ndarray) -> np.ndarray:
        """c = (s W dq + W v) / s of displacements dq and velocities v (each (n,) or (f, n)):
        dq = Re(c V) on the growing solution [length x mass^(1/2), as |Re V|_M = 1]."""
        return (self.s * (dq @ self.left) + v @ self.left) / self.s


@dataclass(frozen=True)
class Linearized:
    """M^-1 J at a state of the branch: its eigenvalues (n,) [1 / time^2] (the translations' and
    loose disks' zeros included), the complex pairs among them, the growing solution of the
    fastest pair (None when every eigenvalue is real) and the state's continuation problem,
    whose history rule the linear problem follows (PackingEquilibria.trial)."""

    eigenvalues: np.ndarray
    pairs: int
    mode: GrowingMode | None
    problem: PackingEquilibria


def linearized(branch: Branch, k: int, network: Network, mass: np.ndarray) -> Linearized:
    """M^-1 J at state k (dense spectrum) and its fastest pair's growing solution. The reduced
    eigensystem (models/packing/equilibria.py) gives r, A_red r = lambda r at the kept dofs, and w,
    w A_red = lambda w; in every coordinate V = A r / lambda (A = M^-1 J: A V = lambda V, since
    A kills the translations) and W = w P (P the map to coordinates relative to the reference
    disk)."""
    q, gamma = branch.q[k], float(branch.gamma[k])
    problem = PackingEquilibria(network, q, branch.xi[k], branch.rows[k], gamma, mass, "M^-1 J")
    system = DenseSpectra().eigensystem(problem, q, gamma, vectors=True)
    i, _ = fastest_pair(system.values)
    pairs = count_complex_pairs(system.values)
    if i < 0:
        return Linearized(system.values, pairs, None, problem)
    lam = complex(system.values[i])
    r, w = system.vectors(i)
    V = problem.physical(q, gamma) @ r / lam
    V = V * np.exp(-0.5j * np.angle(np.sum(mass * V * V)))  # the largest excursion's phase
    V = V / np.sqrt(np.sum(mass * V.real ** 2))
    W = w[problem.gauge.kept] @ problem.gauge.P
    return Linearized(system.values, pairs, GrowingMode(lam, V, W / (W @ V)), problem)


@dataclass(frozen=True)
class StateRun:
    """A run from state k of a branch: its strain, the state (q0, xi0, rows0), the complex pairs
    of M^-1 J there, the perturbation (kind, amplitude [length x mass^(1/2) as a mass-weighted
    distance for eigenvector and random-position, length / time for random-velocity], the
    displacement and velocity of the start), the step dt [time], the fastest pair's growth
    rate sigma_predicted = |Im sqrt(lambda)| of M^-1 J [1 / time] (0 if none), the run, its
    mass-weighted distance from the state and the modulus of the fastest pair's amplitude |c|
    per frame [length x mass^(1/2)] (nan without a pair), the fit of its growth and the energy
    budget's largest drift [energy]."""

    k: int
    gamma: float
    q0: np.ndarray
    xi0: np.ndarray
    rows0: np.ndarray
    pairs: int
    kind: str
    amplitude: float
    displacement: np.ndarray
    velocity: np.ndarray
    dt: float
    sigma_predicted: float
    run: PackingRun
    distance: np.ndarray
    mode_amplitude: np.ndarray
    fit: GrowthFit
    drift: float

    @property
    def sigma_measured(self) -> float:
        """The fitted growth rate [1 / time], nan where none was (fit.reason says why)."""
        return self.fit.sigma

    @property
    def kick(self) -> np.ndarray:
        """The start's displacement, or its velocity where it has none (random-velocity)."""
        return self.displacement if self.displacement.any() else self.velocity

    @property
    def unmeasured(self) -> bool:
        """A complex pair grows from the perturbed start, but no rate was fitted (fit.reason
        says why and what would give one)."""
        return self.sigma_predicted > 0 and self.kind != "none" and self.fit.reason != "ok"

    def settled(self, network: Network, f_tol: float) -> "AtRest":
        """Where the run's end relaxes at rest (FIRE on the frictional forces, the history
        following: models/packing/plastic.relax), against the state (AtRest; NOT_RELAXED where the
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


def run_from_state(branch: Branch, k: int, network: Network, mass: np.ndarray,
                   kind: str, amplitude: float, t_end: float, delta_0: float,
                   dt: float | None = None, seed: int = 0,
                   linear: Linearized | None = None) -> StateRun:
    """Perturb state k, integrate to exactly t_end in steps of at most dt (default time_step of
    M^-1 J's spectrum there) and fit the growth of the fastest pair's amplitude |c| over the
    linear range (the distance below LINEAR_RANGE delta_0: dynamics.fit_growth). The start:
      eigenvector      the fastest pair's growing solution in the full state: q = q_eq + a Re V,
                       v = a Re(s V) (GrowingMode: |Re V|_M = 1, so the start lies a mass-weighted
                       distance a from the state), the histories xi those the displacement
                       charges by the linear problem's rule (PackingEquilibria.trial: the
                       quasistatic history step from the state, Coulomb cap included): the run
                       follows q_eq + Re(a V e^(s t)) from t = 0;
      random-position  q = q_eq + a g / |g|_M, g ~ N(0, 1) from `seed`, the histories charged
                       likewise, v = 0;
      random-velocity  v = a g;
      none             the state as it is, nothing to fit.
    linear: linearized(branch, k, ...) if the caller has it. Raises NoComplexPair."""
    linear = linear or linearized(branch, k, network, mass)
    q0, xi0, rows0, gamma = branch.q[k], branch.xi[k], branch.rows[k], float(branch.gamma[k])
    mode = linear.mode
    rng = np.random.default_rng(seed)
    dq, v = np.zeros_like(q0), np.zeros_like(q0)
    if kind == "eigenvector":
        if mode is None:
            raise NoComplexPair(f"an eigenvector perturbation needs a complex pair of M^-1 J at "
                                f"gamma = {gamma:g}, and there is none")
        dq, v = amplitude * mode.right.real, amplitude * (mode.s * mode.right).real
    elif kind == "random-position":
        shift = rng.normal(size=q0.size)
        dq = amplitude * shift / np.sqrt(np.sum(mass * shift * shift))
    elif kind == "random-velocity":
        v = amplitude * rng.normal(size=q0.size)
    elif kind != "none":
        raise ValueError(f"perturbation must be one of {', '.join(KINDS)} (got {kind!r})")
    xi = linear.problem.trial(q0 + dq, gamma)[0] if dq.any() else xi0
    run = simulate(network, q0 + dq, v, xi, rows0, gamma, mass, dt or time_step(linear.eigenvalues),
                   t_end, frames=FRAMES)
    d = distance(run, q0, mass)
    if mode is None:
        c = np.full(run.t.size, np.nan)
        fit = no_fit(f"every eigenvalue of M^-1 J is real at gamma = {gamma:g}: nothing grows")
    else:
        c = np.abs(mode.amplitude(run.q - q0, run.v))
        fit = (fit_growth(run.t, c, d, LINEAR_RANGE * delta_0) if kind != "none" else
               no_fit("nothing was perturbed (perturbation none)"))
    return StateRun(k, gamma, q0, xi0, rows0, linear.pairs, kind, amplitude, dq, v, run.dt,
                    0.0 if mode is None else mode.sigma, run, d, c, fit,
                    float(np.abs(run.budget - run.budget[0]).max()))
