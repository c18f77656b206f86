"""Damped stability along a shear (docs/packings.md#damped-stability): with a viscous drag
-eta M q' on every degree of freedom, the modes of M q'' + eta M q' + J q = 0 grow as e^(s t),

    s^2 + eta s + lambda = 0   for every eigenvalue lambda of M^-1 J

(dynamics/damped_modes.py), and a complex pair lambda = a +- i b is damped-unstable exactly
while b^2 > eta^2 a. Where a pair crosses into ("onset") or out of ("end") damped instability
is a Hopf point of the damped linearization: there s = i w with w^2 = a and eta w = |b|. This
module gives every accepted state's damped growth rate and locates those points along a shear's
branch with spectra "full" (models/packing/shear.py), each to |d gamma| <= TOL_GAMMA by the
core's locate_crossing over the step that holds it (the step's equilibria solved at fixed
contacts, as the shear's own corrector does: within a step no contact event happens).

eta = 0 is the undamped analysis: every complex pair grows from its birth to its death, so
the onsets and ends are the located collisions themselves (births and deaths) and the damped
growth rate is |Im sqrt(lambda)|, the same numbers the undamped analysis gives. A real
eigenvalue through zero is a fold (a plastic event, where the segment ends), not a damped Hopf
point, and is left out.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import partial

import numpy as np
import scipy.sparse.linalg as spla

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.detection.bifurcations import crossing_steps, locate_crossing
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.continuation.spectra.nearest import start_vector
from diskfriction.continuation.linalg.solves import SingularMatrix
from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL
from diskfriction.continuation.stepping.segment import SegmentSolveError
from diskfriction.dynamics.damped_modes import damped_exponents, damped_growth_rates
from diskfriction.matrices import Matrix
from diskfriction.models.packing.equilibria import LINEAR_SOLVER, PackingEquilibria
from diskfriction.models.packing.network import Network

TOL_GAMMA = 1e-10
"""The strain bracket every damped Hopf point is refined to [1] (the core's Hopf tolerance)."""

NEWTON_TOL = 1e-10
"""The equilibria's force tolerance in the refinement [force], ten times the shear's
(ShearParams): each equilibrium inside a step is solved from the step's secant, and at the
shear's 1e-11 such solves stalled at max |F| = 1.3e-11 (32 disks, seed 2, mu = 1e6, to gamma =
0.004; the shear's own states there: 8.8e-12). A force error of 1e-10 moves the disks by about
1e-10 / k_n delta_0^(1/2) ~ 1e-12 and the eigenvalues far less than the strain's tolerance
resolves."""


@dataclass(frozen=True)
class DampedHopf:
    """A point of a shear's branch where a mode crosses into (kind "onset") or out of ("end")
    damped instability at the damping rate eta [1 / time]: its strain gamma; the eigenvalue
    lambda of M^-1 J there with the viscous drag (the member with Im >= 0: Re lambda = w^2,
    Im lambda = eta w; at eta = 0 the double real eigenvalue of the collision), None with
    contact dashpots (models/packing/contact_onsets.py); the marginal mode's angular
    frequency w [1 / time]; the branch step holding it; the strain bracket it was refined to;
    the equilibrium q there; and the mode's translations, (N, 2) complex (pair_translations; at
    eta = 0 the collision's Jordan chain, _collision)."""

    eta: float
    gamma: float
    kind: str
    eigenvalue: complex | None
    frequency: float
    step: int
    bracket: tuple[float, float]
    q: np.ndarray | None = field(default=None, compare=False, repr=False)
    mode: np.ndarray | None = field(default=None, compare=False, repr=False)
    jump: bool = False
    resolved: bool = True


def pair_translations(problem: PackingEquilibria, q: np.ndarray, gamma: float, near: complex) -> np.ndarray:
    """(N, 2) complex: the disks' translations in the right eigenvector of the physical M^-1 J
    at (q, gamma) (PackingEquilibria.physical: every disk's dofs) whose eigenvalue is the upper
    member nearest `near` (shift_inverted; the dense eigendecomposition where ARPACK fails)."""
    N = problem.network.N
    A = problem.physical(q, gamma)
    target = complex(near.real, abs(near.imag))
    found = shift_inverted(A, target, vectors=True)
    if found is None:
        values, vectors = np.linalg.eig(A.toarray())
        upper = np.flatnonzero(values.imag > 0)
        vector = vectors[:, upper[np.argmin(np.abs(values[upper] - target))]]
    else:
        vector = found[1][:, 0]
    return np.stack([vector[:N], vector[N:2 * N]], axis=1)


def shift_inverted(A, target: complex, vectors: bool = False):
    """The eigenvalue of the sparse A nearest the complex target (and its right eigenvector,
    (n, 1), with `vectors`), by ARPACK on (A - target I)^-1 in complex arithmetic (scipy takes a
    real A with a complex shift apart); None where ARPACK fails."""
    try:
        return spla.eigs(A.astype(complex), k=1, sigma=target, v0=start_vector(A.shape[0]).astype(complex),
                         return_eigenvectors=vectors)
    except (spla.ArpackNoConvergence, RuntimeError):
        return None


def problem_at(network: Network, mass: np.ndarray, branch: Branch, k: int) -> PackingEquilibria:
    """The equilibrium problem with state k's committed contacts and histories (within the step
    from k to k + 1 no contact event happens)."""
    return PackingEquilibria(network, branch.u[k], branch.xi[k], branch.rows[k], float(branch.p[k]),
                             mass, str(branch.matrix), NEWTON_TOL)


def fastest_damped(eigenvalues: np.ndarray, eta: float, rel_tol: float = DEFAULT_REL_TOL) -> float:
    """The largest damped growth rate max Re s [1 / time] of s^2 + eta s + lambda = 0 over the
    eigenvalues lambda of M^-1 J at one state (nan ones, outside a window, left out), eta >= 0
    [1 / time]: positive where a mode is damped-unstable (a complex pair with (Im lambda)^2 >
    eta^2 Re lambda, or a real lambda < 0, which grows at any drag). An eigenvalue with
    |Im lambda| within rel_tol max|lambda| is taken as real, as the pair count does, and one
    with |lambda| within it (the translations' zeros, and their rounding) as no mode, so that
    rounding grows none; -inf without any."""
    lam = np.asarray(eigenvalues, dtype=complex)
    lam = lam[np.isfinite(lam)]
    floor = rel_tol * float(np.abs(lam).max(initial=0.0))
    lam = np.where(np.abs(lam.imag) > floor, lam, lam.real)
    lam = lam[np.abs(lam) > floor]
    return float(damped_growth_rates(lam, eta).max(initial=-np.inf))


def damped_rates(eigenvalues: np.ndarray, eta: float, rel_tol: float = DEFAULT_REL_TOL) -> np.ndarray:
    """fastest_damped of every row (state) of an (m, n) eigenvalue array [1 / time]."""
    return np.array([fastest_damped(row, eta, rel_tol) for row in eigenvalues])


def damped_hopfs(network: Network, mass: np.ndarray, branch: Branch, eta: float,
                 rel_tol: float = DEFAULT_REL_TOL) -> tuple[DampedHopf, ...]:
    """Every onset and end of damped instability at the drag eta [1 / time] along a shear's
    branch (models/packing/shear.py) with spectra "full" of M^-1 J (every eigenvalue, or a
    window's tracked columns), in strain order within each segment, segments in order (module
    docstring; eta = 0: its collisions). ValueError for another matrix or a branch without
    spectra at its states."""
    if branch.matrix != Matrix.M_INV_J:
        raise ValueError(f"damped stability needs the matrix M^-1 J (the modes of M q'' + eta M q' "
                         f"+ J q = 0), not {branch.matrix}")
    if branch.eigenvalues.shape[1] == 0:
        raise ValueError('damped Hopf points are located on a branch with spectra "full", not one '
                         'without spectra at its states ("none" or "sample")')
    if eta == 0.0:
        return tuple(_collision(c, network.N) for c in branch.collisions)
    growth = partial(damped_growth_rates, eta=eta)
    found = []
    for piece in branch.of_kind("segment"):
        ev = branch.eigenvalues[piece.start:piece.stop]
        for k, i, rising in crossing_steps(ev, growth, rel_tol):
            step = piece.start + k
            problem = problem_at(network, mass, branch, step)
            try:
                point = _located(problem, branch, step, ev[k, i], ev[k + 1, i], eta)
            except (SegmentSolveError, SingularMatrix):  # an equilibrium inside the step not found
                found.append(_unresolved(branch, step, complex(ev[k, i]), complex(ev[k + 1, i]), eta, rising))
                continue
            if point is None:  # the sign changed at the contact event ending the step
                unstable = complex(ev[k + 1, i] if rising else ev[k, i])
                if abs(unstable.imag) > rel_tol * abs(unstable):  # a real one: static, left out
                    found.append(_at_event(network, mass, branch, step, unstable, eta, rising))
                continue
            lam = complex(point.value)
            if abs(lam.imag) > rel_tol * abs(lam):  # a real one: a fold, left out
                found.append(DampedHopf(eta, point.p, "onset" if rising else "end", lam,
                                        float(np.sqrt(max(lam.real, 0.0))), point.step, point.bracket,
                                        point.u, pair_translations(problem, point.u, point.p, lam)))
    return tuple(sorted(found, key=lambda h: (h.step, h.gamma)))


def _unresolved(branch: Branch, k: int, lam_a: complex, lam_b: complex, eta: float,
                rising: bool) -> DampedHopf:
    """A crossing in step k whose refinement found no equilibrium inside the step (a disk
    turning loose at the contact event ending it makes the Jacobian there nearly singular, and
    Newton stalls): the whole step as its bracket (`resolved` False), gamma where the damped
    growth rates at its ends, linear in the strain, cross zero, the eigenvalue and frequency of
    its unstable end, no state and no mode."""
    g_a, g_b = damped_growth_rates(np.array([lam_a, lam_b]), eta)
    gamma_a, gamma_b = float(branch.p[k]), float(branch.p[k + 1])
    gamma = gamma_a + (gamma_b - gamma_a) * g_a / (g_a - g_b)
    lam = lam_b if rising else lam_a
    return DampedHopf(eta, gamma, "onset" if rising else "end", lam, marginal_frequency(lam, eta), k,
                      (gamma_a, gamma_b), resolved=False)


def _at_event(network: Network, mass: np.ndarray, branch: Branch, k: int, lam: complex, eta: float,
              rising: bool) -> DampedHopf:
    """A crossing at the contact event that ends step k: with the step's contacts the growth
    rate keeps its sign up to state k + 1, where a contact opens or closes and the spectrum
    jumps across zero growth (locate_crossing's None). The point is state k + 1 (a bracket of
    width 0, `jump`); lam is the tracked eigenvalue on its unstable side (state k + 1 for an
    onset, k for an end), whose damped root gives the frequency and whose right eigenvector
    there the mode."""
    gamma = float(branch.p[k + 1])
    j = k + 1 if rising else k
    problem = problem_at(network, mass, branch, j)
    return DampedHopf(eta, gamma, "onset" if rising else "end", lam, marginal_frequency(lam, eta), k,
                      (gamma, gamma),
                      branch.u[k + 1], pair_translations(problem, branch.u[j], float(branch.p[j]), lam),
                      jump=True)


def _collision(c, N: int) -> DampedHopf:
    """A located collision as the damped Hopf point at eta = 0: a birth an onset, a death an end.
    Its mode spans the plane of the Jordan chain (v, w) there (eigenvector, generalized
    eigenvector: the pair's eigenvectors next to it are v +- i epsilon w to first order), in
    coordinates relative to the reference disk (a uniform translation apart from the physical
    ones: precursors.plane_overlap removes it)."""
    chain = c.eigenvector + 1j * c.generalized_eigenvector
    return DampedHopf(0.0, float(c.p), "onset" if c.kind == "birth" else "end", complex(c.eigenvalue),
                      float(np.sqrt(max(c.eigenvalue, 0.0))), int(c.step), (float(c.p), float(c.p)),
                      c.u, np.stack([chain[:N], chain[N:2 * N]], axis=1))


def in_gauge(problem: PackingEquilibria, q: np.ndarray, gamma: float) -> np.ndarray:
    """x = (q', gamma): a later state q of the step (at gamma) in the gauge of `problem`
    (problem_at the step's start). The gauge pins the reference disk and the loose disks to the
    committed state, while the branch lets them move from state to state; q' is q translated
    as a whole so that the reference disk is back (a symmetry of the sheared periodic box:
    every separation and image is kept) and the gauge rows' dofs back at the committed state
    (the loose disks carry no force), so that the secant between the step's ends stays in one
    gauge. Where a disk turns loose at q (a contact event ending the step) q' is no equilibrium
    of `problem` by that disk's force, which its last contact no longer balances."""
    N, committed, shifted = problem.network.N, problem.q_c, np.array(q, dtype=float)
    ref = problem.gauge.ref
    for c in (0, 1):
        shifted[c * N:(c + 1) * N] -= q[c * N + ref] - committed[c * N + ref]
    shifted[problem.gauge.rows] = committed[problem.gauge.rows]
    return np.append(shifted, gamma)


def nearest_eigenvalue(problem: PackingEquilibria, x: np.ndarray, target: complex) -> complex:
    """The eigenvalue of the problem's stability matrix at x = (q, gamma) nearest target
    (shift_inverted: its gauge rows' parked diagonal lies far from any target here, Re lambda =
    w^2 > 0); the whole dense spectrum where ARPACK fails. 64 disks: 7 ms against a dense
    spectrum's 15-96 ms; 256 disks: 53 against 719 ms (2026-12-02, two other jobs on the
    machine)."""
    values = shift_inverted(problem.stability_matrix(x[:-1], x[-1]), target)
    if values is None:
        values = DenseSpectra().eigensystem(problem, x[:-1], x[-1]).values
    return complex(values[np.argmin(np.abs(values - target))])


def marginal_frequency(lam: complex, eta: float) -> float:
    """|Im s| of the damped root with the larger real part for the eigenvalue lam at the drag eta
    [1 / time]: the marginal mode's frequency w where Re s = 0 (w^2 = Re lambda there)."""
    return float(np.abs(damped_exponents(np.array([lam]), eta)[0, 0].imag))


def _located(problem: PackingEquilibria, branch: Branch, k: int, lam_a: complex, lam_b: complex,
             eta: float):
    """The sign change of the damped growth rate of the eigenvalue tracked from lam_a at state k
    to lam_b at k + 1, located (bifurcations.locate_crossing) on `problem` (problem_at k)."""
    x_a = np.append(branch.u[k], branch.p[k])
    x_b = in_gauge(problem, branch.u[k + 1], float(branch.p[k + 1]))
    return locate_crossing(problem, x_a, x_b, lam_a, lam_b,
                           lambda lam: float(damped_growth_rates(np.array([lam]), eta)[0]), k,
                           TOL_GAMMA, NEWTON_TOL, 20, LINEAR_SOLVER, DenseSpectra(), upper=False,
                           kind="damped-hopf", nearest=nearest_eigenvalue)
