"""Where a shear's state loses or regains damped stability with dashpots on its contacts (issue 63;
models/packing/contact_damping.py): the modes of

    M q'' + C q' + J q = 0,   q = r e^(s t),   det(s^2 M + s C + J) = 0,

with C the contact dashpots' matrix, no longer follow from the eigenvalues of M^-1 J (C does not
commute with it), so no tracked eigenvalue of the branch maps to an exponent s, and the drag's
per-pair analysis (models/packing/damped.py) has nothing to follow. What is followed instead is
the state's largest growth rate

    g(gamma) = max Re s  [1 / time]

of the quadratic eigenproblem at the equilibrium at strain gamma (contact_damping.damped_spectrum:
the tracked spectrum's coordinates, the translations and loose disks left out). g is computed at
every accepted state k (its own committed contacts, damped.problem_at; contact_growth, which
bifurcate --dashpots also reads for the fraction of the strain with g > 0 and for g at each
plastic event). Where it changes sign clearly (clear_signs: |g| > rel_tol times the state's
frequency scale max|s|, as bifurcations.crossing_steps asks of a pair's growth rate in units of
sqrt(max|lambda|); undamped, a stable state's g is 0 to rounding, so that at the rate 0 no state
is clearly stable and no point is found) from one state to the next state clearly on the other
side, the step over which it changes is refined to
|d gamma| <= damped.TOL_GAMMA by segment.refine_sign_change on g(gamma) at the equilibria solved at
fixed strain with the step's committed contacts (newton.fixed_p_newton, from the equilibria
interpolated between the bracket's ends, as sampled.py solves a grid strain): an "onset" where g
turns positive, an "end" where it turns negative. The marginal exponent s = +-i w there gives the
point's frequency w and its mode: the null vector of s^2 + s C_red + K_red at s = -i w (the
conjugate of +i w's: the same plane of real motions; -i w so that with the drag it is the
eigenvector of the pair's member lambda = w^2 + i eta w, damped.py's) in the tracked
coordinates, mapped back to the disks' translations with the network's centre of mass at rest and
the loose disks at rest, as in the mode of the full system (mode_translations).

This is the state's damped stability, not each pair's: an onset is where the first mode becomes
unstable (no mode grew before it), an end where the last one recovers. While one mode grows,
another's onset or end changes no sign of g and is not seen, and two changes within one step (one
mode recovering as another takes over, g dipping below zero in between) leave g of one sign at both
states and are not seen either: seeing them would need each exponent tracked from state to state,
and the quadratic eigenvalues have no tracking here (no continuation of the eigenvalues of a
quadratic pencil, no collision detection for them). With the drag eta M in place of C
(stability_changes) the points are damped_hopfs' changes between no damped-unstable pair and one,
in each step whose two states differ in having one (tests/models/packing/test_contact_onsets.py).
On the 24-disk test branch at eta = 0.002 omega_0 damped_hopfs also has an end and an onset within
one step, which g cannot see; and g finds an onset 1.3e-5 of strain before damped_hopfs' first in
its step: a pair born, unstable and dead within that step, which no state holds, so that
damped_hopfs (following the states' tracked pairs) does not see it.

The dashpots switch at a commit: a contact's normal dashpot acts while it overlaps, its tangential
one while it is not sliding at the committed state. g is continuous within a step, and may jump at
a state where a contact opens or starts or stops to slide. The sign change is refined on the first
step of its span over which g, evaluated with that step's contacts at both ends, changes sign; a
change made by the jump alone is no Hopf point (no exponent crosses the imaginary axis) and is left
out, as is a real exponent through zero (a fold: a plastic event, where the segment ends).

Cost: one dense eigenvalue problem of size 2k (k ~ 3 N tracked coordinates) per accepted state,
plus 7 to 12 equilibria at fixed strain, each with its eigenvalue problem, per point located. On
the 24-disk test branch (27 states, 2k = 122, one BLAS thread on a shared 2-core machine): 7 to 9
ms per state, 0.04 to 0.12 s per point, 0.3 to 0.5 s for the branch at each rate.
"""
from __future__ import annotations

import bisect
from functools import partial
from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.linalg.solves import blas_threads
from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL
from diskfriction.continuation.stepping.newton import fixed_p_newton
from diskfriction.continuation.stepping.segment import refine_sign_change
from diskfriction.dynamics.quadratic_modes import largest_growth, quadratic_exponents
from diskfriction.models.packing.contact_damping import (ContactDamping, problem_damping, reduced_exponents,
                                                         reduced_pencil)
from diskfriction.models.packing.damped import NEWTON_TOL, TOL_GAMMA, DampedHopf, problem_at
from diskfriction.models.packing.equilibria import LINEAR_SOLVER, PackingEquilibria
from diskfriction.models.packing.network import Network

Dashpots = Callable[[PackingEquilibria, np.ndarray, float], object]
"""C (3N x 3N, dense or sparse) [mass / time] of a problem at (q, gamma): the damping of M q'' + C
q' + J q = 0 (contact_damping.problem_damping with its rates, or a drag eta M)."""


def contact_hopfs(network: Network, mass: np.ndarray, branch: Branch, damping: ContactDamping,
                  rel_tol: float = DEFAULT_REL_TOL,
                  growth: Optional[tuple[np.ndarray, np.ndarray]] = None) -> tuple[DampedHopf, ...]:
    """Every onset and end of the states' damped stability with the dashpots `damping` on the
    contacts along a shear's branch (any spectra: only its states are read), in strain order within
    each segment, segments in order (module docstring). eta of each point: damping.rate. growth:
    the branch's contact_growth at `damping` where already computed."""
    return stability_changes(network, mass, branch, damping.rate,
                             partial(problem_damping, damping=damping), rel_tol, growth)


def contact_growth(network: Network, mass: np.ndarray, branch: Branch, damping: ContactDamping
                   ) -> tuple[np.ndarray, np.ndarray]:
    """(g, max|s|), (m,) each [1 / time]: the largest growth rate max Re s and the frequency
    scale max|s| of M q'' + C q' + J q = 0 at each of the branch's m accepted states, with the
    dashpots `damping` on its committed contacts (contact_damping.damped_spectrum; g > 0: a mode
    grows)."""
    return state_growth(network, mass, branch, partial(problem_damping, damping=damping))


def state_growth(network: Network, mass: np.ndarray, branch: Branch, dashpots: Dashpots
                 ) -> tuple[np.ndarray, np.ndarray]:
    """contact_growth with the damping C = dashpots(problem, q, gamma): state k's with its own
    committed contacts (damped.problem_at), on one BLAS thread."""
    with blas_threads():  # as the continuation's spectra: one BLAS thread (solves.blas_threads)
        g, scale = np.array([_growth(problem_at(network, mass, branch, k), branch.u[k],
                                     float(branch.p[k]), dashpots)
                             for k in range(len(branch))]).reshape(-1, 2).T
    return g, scale


def stability_changes(network: Network, mass: np.ndarray, branch: Branch, eta: float,
                      dashpots: Dashpots, rel_tol: float = DEFAULT_REL_TOL,
                      growth: Optional[tuple[np.ndarray, np.ndarray]] = None
                      ) -> tuple[DampedHopf, ...]:
    """contact_hopfs with the damping C = dashpots(problem, q, gamma), its points labelled with
    the rate eta [1 / time]; growth: the branch's state_growth with it where already computed."""
    g, scale = state_growth(network, mass, branch, dashpots) if growth is None else growth
    with blas_threads():
        return tuple(_changes(network, mass, branch, eta, dashpots, rel_tol, g, scale))


def clear_signs(g: np.ndarray, scale: np.ndarray, rel_tol: float = DEFAULT_REL_TOL) -> np.ndarray:
    """(m,): +1 where the growth rate g is clearly positive (g > rel_tol max|s|, scale = max|s|:
    a mode grows), -1 where clearly negative, 0 in between (rounding: undamped, every stable
    state's exponents lie on the imaginary axis)."""
    return np.where(np.abs(g) > rel_tol * scale, np.sign(g), 0.0)


def _changes(network, mass, branch, eta, dashpots, rel_tol, g, scale):
    """stability_changes' points, one after another, from the states' (g, max|s|)."""
    for piece in branch.of_kind("segment"):
        growth = g[piece.start:piece.stop]
        signs = clear_signs(growth, scale[piece.start:piece.stop], rel_tol)
        last = None  # the last state clearly on one side
        for k in np.flatnonzero(signs):
            if last is not None and signs[last] != signs[k]:
                point = _within(network, mass, branch, piece.start + last, growth[last:k + 1],
                                eta, dashpots, rel_tol)
                if point is not None:
                    yield point
            last = k


def _growth(problem: PackingEquilibria, q: np.ndarray, gamma: float, dashpots: Dashpots
            ) -> tuple[float, float]:
    """(g, max|s|) at (q, gamma) [1 / time]: the largest growth rate and the frequency scale."""
    s = reduced_exponents(problem, q, gamma, dashpots(problem, q, gamma))
    return largest_growth(s), float(np.abs(s).max())


def _within(network, mass, branch, first: int, growth: np.ndarray, eta: float,
            dashpots: Dashpots, rel_tol: float) -> Optional[DampedHopf]:
    """The point of a sign change of g over the states first, first + 1, ... (their g: growth):
    located on the first step over which g, with the step's contacts at both ends, changes sign;
    None where none does (the jumps at the commits made it) or where the exponent through zero
    is real."""
    for j in range(growth.size - 1):
        k = first + j
        step = _StepGrowth(problem_at(network, mass, branch, k), branch, k, dashpots)
        g_b = step(float(branch.p[k + 1]))
        if g_b is not None and growth[j] * g_b < 0:
            step.values[float(branch.p[k])] = growth[j]
            return _located(step, eta, rel_tol)
    return None


class _StepGrowth:
    """g(gamma) within the step from state k to k + 1 (with state k's contacts): the equilibrium
    solved at fixed gamma from the one interpolated between the solved strains nearest it on
    either side (the states at first), and its largest growth rate; None where Newton fails."""

    def __init__(self, problem: PackingEquilibria, branch: Branch, k: int, dashpots: Dashpots):
        self.problem, self.dashpots, self.k = problem, dashpots, k
        self.solved = {float(branch.p[k]): branch.u[k], float(branch.p[k + 1]): branch.u[k + 1]}
        self.values: dict[float, float] = {}

    def __call__(self, gamma: float) -> Optional[float]:
        strains = sorted(self.solved)
        i = min(max(bisect.bisect_left(strains, gamma), 1), len(strains) - 1)
        lo, hi = strains[i - 1], strains[i]
        share = (gamma - lo) / (hi - lo)
        guess = (1.0 - share) * self.solved[lo] + share * self.solved[hi]
        result = fixed_p_newton(self.problem, guess, gamma, NEWTON_TOL, 20, LINEAR_SOLVER)
        if not result.converged:
            return None
        self.solved[gamma] = result.x[:-1]
        self.values[gamma] = _growth(self.problem, self.solved[gamma], gamma, self.dashpots)[0]
        return self.values[gamma]


def _located(step: _StepGrowth, eta: float, rel_tol: float) -> Optional[DampedHopf]:
    """The sign change of g over the step refined to TOL_GAMMA, the point at the bracket's
    interpolated root (gamma and q linear in between), its marginal exponent and mode there; None
    where that exponent is real."""
    a, b = sorted(step.values)
    kind = "onset" if step.values[b] > 0 else "end"
    a, b = refine_sign_change(step, a, step.values[a], b, step.values[b],
                              lambda lo, hi: hi - lo <= TOL_GAMMA, tol=0.5 * TOL_GAMMA)
    t = 0.0 if a == b else step.values[a] / (step.values[a] - step.values[b])
    gamma = a + t * (b - a)
    q = step.solved[a] + t * (step.solved[b] - step.solved[a])
    problem = step.problem
    C_red, K_red = reduced_pencil(problem, q, gamma, step.dashpots(problem, q, gamma))
    s = quadratic_exponents(np.ones(K_red.shape[0]), C_red, K_red)
    marginal = s[np.argmax(s.real)]
    if abs(marginal.imag) <= rel_tol * np.abs(s).max():
        return None
    marginal = complex(marginal.real, -abs(marginal.imag))
    return DampedHopf(eta, float(gamma), kind, None,
                      float(abs(marginal.imag)), step.k, (float(a), float(b)), q,
                      mode_translations(problem, null_vector(marginal, C_red, K_red)))


def null_vector(s: complex, C_red: np.ndarray, K_red: np.ndarray) -> np.ndarray:
    """z (k,) complex, |z| = 1: the right singular vector of s^2 + s C_red + K_red with the least
    singular value, the mode of an exponent s of the pencil."""
    Q = s * s * np.eye(K_red.shape[0]) + s * C_red + K_red
    return np.linalg.svd(Q)[2][-1].conj()


def mode_translations(problem: PackingEquilibria, z: np.ndarray) -> np.ndarray:
    """(N, 2) complex: the disks' (x, y) in the mode of the full system whose tracked coordinates
    are z (an exponent s != 0): E z with the network's centre of mass at rest and the loose disks
    at rest. (The translations T and the loose disks' dofs L feel no force nor dashpot, so the
    mode is E z + T a + L b with s^2 M (E z + T a + L b) summing to zero over each axis and b = 0:
    a = -(the mass-weighted mean of E z over the disks that are not loose).)"""
    N = problem.network.N
    q = np.zeros(problem.network.ndof, complex)
    q[problem.gauge.kept] = z
    moved = np.stack([q[:N], q[N:2 * N]], axis=1)
    held, m = ~problem.gauge.loose, problem.mass[:N]
    moved[held] -= (m[held, None] * moved[held]).sum(axis=0) / m[held].sum()
    return moved
