"""Causality by dynamics (issue 63, item 4): from a state of the shear branch where a complex
pair of M^-1 J is damped-unstable at the drag eta, does the perturbation grow into a
rearrangement before the quasistatic branch reaches its fold, or does it stop growing?

The damped dynamics M q'' = F(q, xi; gamma) - eta M q' at fixed strain (dynamics.simulate with
the drag) starts at q_eq + a delta_0 Re V (V the pair's right eigenvector of M^-1 J in every
coordinate, |Re V|_M = 1), with the velocity of the growing solution or at rest. In the linear
dynamics the pair's part grows as e^(s t), s the root of s^2 + eta s + lambda = 0 with the
larger real part (dynamics/damped_modes.py); its complex amplitude

    c = (W q' - s' W dq) / (s - s'),    s' the other root, W the left eigenvector (W V = 1),

is c_0 e^(s t) exactly (y = W dq obeys y'' + eta y' + lambda y = 0), so |c| grows at Re s
without the oscillation and the other modes do not enter it. The run ends at rest, once the
largest kinetic energy over its last stretch (a period of the pair) fell below REST times the
largest of the run (or, given time to settle, below the FLOOR the state's residual forces
set), or at t_end; its end is then relaxed at fixed strain by FIRE (plastic.relax: at rest a
polish, its motion within REST^(1/2) of its largest).

The dynamics runs its course, however far the disks go: relaxed by FIRE once 1 delta_0 away
(mass-weighted), the growing oscillations of 32 disks (seed 1, eta = 0.01 omega_0, from the
onsets at gamma = 0.00084, 0.00260, 0.00785 and 0.00893) fell back near their start (0.02 to
0.46 delta_0, the same contacts), while the damped dynamics took them into rearrangements
(3.8 to 144 delta_0 away, sigma_xy down 6 to 59 %).

The relaxed end against the start gives the verdict: "rearranged" where its holding contacts
(overlap above HOLDING times the start's median overlap: a loose disk's grazing touch is no
contact) changed or it lies REARRANGING delta_0 or farther from the start (a rearrangement need
not change a holding contact: on 32 disks, seed 1, at eta = 0.05 omega_0, a run from gamma =
0.00170 came to rest 2.8 delta_0 away with the same contacts, sigma_xy 7.5 % lower, at 0.98
overlap with the displacement of the plastic event at the fold, gamma = 0.00260, which changed
two); otherwise, for a run that never came to rest, "saturated" (the motion neither grows nor
decays near the start: a limit cycle, which only the non-conservative tangential forces can keep
up against the drag), and for one that did, "returned" where it lies no farther from the start
than the start did from it, "slipped" where farther (the same contacts, histories reset by
sliding: the growth stopped at the Coulomb limit and the packing came to rest at a nearby
equilibrium). The displacement field is compared with the next plastic event's, q_after -
q_before, by their mass-weighted overlap, each without its centre-of-mass translation (a uniform
shift changes no force).

Masses in units of m (scenes.packing.PackingScene.m), so that mass-weighted distances are
compared with delta_0 [length], as dynamics.LINEAR_RANGE is.
"""
from __future__ import annotations

import math
from collections import Counter
from dataclasses import dataclass
from typing import Optional

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.dynamics.damped_modes import damped_exponents
from diskfriction.matrices import Matrix
from diskfriction.models.packing.damped import damped_rates
from diskfriction.models.packing.dynamics import STABLE_FRACTION, simulate
from diskfriction.models.packing.equilibria import LOOSE_OVERLAP, PackingEquilibria, row_keys
from diskfriction.models.packing.network import Network
from diskfriction.models.packing.plastic import RelaxationFailed, omega_bound, relax

VERDICTS = ("returned", "slipped", "rearranged", "saturated")
"""A run's verdicts (module docstring)."""

AMPLITUDE = 1e-6
"""The start's mass-weighted distance from the state, in delta_0, by default [1]: inside the
linear range (dynamics.LINEAR_RANGE, 1e-5), so that the growth starts at the damped rate, and
far above the drift the state's residual forces drive (FLOOR)."""

REARRANGING = 1.0
"""A run that comes to rest this many delta_0 or farther from the state (mass-weighted)
rearranged, whether or not a holding contact changed [1]. A slip at eta = 0.1 [1 / time] stayed
far below it (24 disks, seed 3, from gamma = 0.00109: 0.015 delta_0); the plastic events of 32
disks (seed 1, to gamma = 0.02) moved them 4.0 to 38 delta_0."""

REST = 1e-8
"""A run is at rest once its kinetic energy over its last stretch stays below this fraction of
the largest of the run [1]: its motion is then within 1e-4 of its largest."""

FLOOR = 100.0
"""A run is at rest also once its kinetic energy stays below this many times sum F^2 / (2 m
eta^2), F the residual forces of the state it started from [force], a settling_time after its
largest: the residual forces drive a creep against the drag (contacts at their Coulomb limit
give way to them), which keeps the kinetic energy from falling further (24 disks, seed 3, at
gamma = 0.00109, eta = 2 [1 / time]: 4.4e-26 [energy], 4.4 times the sum, 3e-4 of the start's
from 1e-8 delta_0; at gamma = 0.00106 and eta = 0.0105 the sum is above the start's from 1e-6
delta_0)."""

HOLDING = LOOSE_OVERLAP
"""A contact holds where its overlap exceeds this fraction of the start's median overlap [1]
(the shear's delta_hold: models/packing/equilibria.py)."""

FRAMES = 20
"""Frames per stretch of a run, at which its distance and kinetic energy are read."""

MARGIN = 4.0
"""The default t_end is this many times the time a run needs to grow from its start to
REARRANGING delta_0 at Re s and to come to rest at the drag's rate (run_length): the state a run
slips to can have slower modes (24 disks, seed 3, at gamma = 0.00109, eta = 1 [1 / time]: its
kinetic energy fell by 1e-8 in 2.4 times the estimate)."""


@dataclass(frozen=True)
class DampedMode:
    """An eigenpair of M^-1 J with lambda complex [1 / time^2]: right (n,), V with M^-1 J V =
    lambda V in every coordinate (the translations included), at the phase of its largest
    mass-weighted displacement (Re V and Im V M-orthogonal, |Re V|_M >= |Im V|_M) and scaled to
    |Re V|_M = 1; left (n,), W with W M^-1 J = lambda W and W V = 1."""

    lam: complex
    right: np.ndarray
    left: np.ndarray

    def exponents(self, eta: float) -> tuple[complex, complex]:
        """(s, s'): the roots of s^2 + eta s + lambda = 0 at the drag eta [1 / time], s the one
        with the larger real part (the pair grows where Re s > 0)."""
        s, other = damped_exponents(np.array([self.lam]), eta)[0]
        return complex(s), complex(other)

    def growth_rate(self, eta: float) -> float:
        """Re s [1 / time]."""
        return self.exponents(eta)[0].real

    def amplitude(self, eta: float, dq: np.ndarray, v: np.ndarray) -> np.ndarray:
        """c = (W v - s' W dq) / (s - s') of displacements dq and velocities v (each (n,) or (f,
        n)): c_0 e^(s t) in the linear dynamics (module docstring) [length x mass^(1/2)]."""
        s, other = self.exponents(eta)
        return (v @ self.left - other * (dq @ self.left)) / (s - other)


def damped_modes(network: Network, mass: np.ndarray, q: np.ndarray, xi: np.ndarray,
                 rows: np.ndarray, gamma: float) -> tuple[np.ndarray, list[DampedMode]]:
    """The eigenvalues of M^-1 J at the state (q, xi, rows, gamma) [1 / time^2] (dense; the
    translations' and loose disks' zeros included) and the modes of its complex ones, one per
    pair (Im lambda > 0). The reduced eigensystem (models/packing/equilibria.py) gives r, A_red r
    = lambda r at the kept dofs, and w, w A_red = lambda w; in every coordinate V = A r /
    lambda (A = M^-1 J kills the translations) and W = w P (runs.linearized)."""
    problem = PackingEquilibria(network, q, xi, rows, gamma, mass, "M^-1 J")
    system = DenseSpectra().eigensystem(problem, q, gamma, vectors=True)
    lam = system.values
    paired = np.abs(lam.imag) > 1e-9 * np.abs(lam).max()
    A, modes = problem.physical(q, gamma), []
    for i in np.flatnonzero(paired & (lam.imag > 0)):
        r, w = system.vectors(i)
        V = A @ r / lam[i]
        V = V * np.exp(-0.5j * np.angle(np.sum(mass * V * V)))  # the largest excursion's phase
        V = V / np.sqrt(np.sum(mass * V.real ** 2))
        W = w[problem.gauge.kept] @ problem.gauge.P
        modes.append(DampedMode(complex(lam[i]), V, W / (W @ V)))
    return lam, modes


def fastest(modes: list[DampedMode], eta: float) -> Optional[DampedMode]:
    """The mode with the largest damped growth rate Re s at the drag eta (None without any)."""
    return max(modes, key=lambda mode: mode.growth_rate(eta), default=None)


@dataclass(frozen=True)
class Outcome:
    """A damped run from an equilibrium along a mode (run_mode): the verdict (VERDICTS), the time
    it was reached [time] (the rest's, or t_end), the largest
    mass-weighted distance from the equilibrium reached [length x mass^(1/2)], the displacement
    (3N,) of the relaxed end from it, the holding contacts gained
    and lost there, the sliding updates of the run, the start's distance [length x
    mass^(1/2)], the relative change of sigma_xy there [1], and overlap: |<u, w>_M| / (|u|_M
    |w|_M) of the displacement u with the given field w, both without their centre-of-mass
    translations (None without w)."""

    verdict: str
    time: float
    distance: float
    displacement: np.ndarray
    gained: int
    lost: int
    slides: int
    start: float
    stress_change: float
    overlap: Optional[float]


def settling_time(rate: float, eta: float) -> float:
    """The time the kinetic energy takes to fall by REST at the rate eta, or 2 |Re s| where
    that is slower (rate = Re s <= 0: the mode decays) [time]; inf at eta = 0."""
    decay = eta if rate > 0 else min(eta, -2.0 * rate)
    return math.log(1.0 / REST) / decay if decay > 0 else math.inf


def run_length(rate: float, eta: float, amplitude: float) -> float:
    """MARGIN times the time to grow from amplitude to REARRANGING delta_0 at the damped rate
    Re s = rate [1 / time] (none where it is <= 0) and then to come to rest (settling_time)
    [time]."""
    grow = math.log(REARRANGING / amplitude) / rate if rate > 0 else 0.0
    return MARGIN * (grow + settling_time(rate, eta))


def run_mode(network: Network, mass: np.ndarray, q: np.ndarray, xi: np.ndarray, rows: np.ndarray,
             gamma: float, mode: DampedMode, eta: float, delta_0: float,
             amplitude: float = AMPLITUDE, moving: bool = True, t_end: Optional[float] = None,
             w: Optional[np.ndarray] = None, f_tol: float = 1e-11,
             dt: Optional[float] = None) -> Outcome:
    """The damped run at the drag eta [1 / time] from the equilibrium (q, xi, rows, gamma) along
    `mode` (module docstring): the start q + a Re V at the mass-weighted distance a = amplitude
    delta_0 [length], with the growing solution's velocity a Re(s V) (moving) or at rest, the
    histories charged by the displacement (Network.history_step from the state); in steps of at
    most dt (default STABLE_FRACTION of 2 / omega, omega bounded by plastic.omega_bound), in
    stretches of one period 2 pi / |Im s| of the pair, to at most t_end (default run_length).
    w: a displacement field (3N,) to compare with (the next plastic event's); f_tol: the end's
    relaxation's force tolerance [force] (plastic.RelaxationFailed where FIRE does not reach
    it). At eta = 0 only sliding dissipates: t_end is then needed (ValueError without)."""
    if eta <= 0 and t_end is None:
        raise ValueError("an undamped run comes to rest only by sliding: give its t_end")
    s = mode.exponents(eta)[0]
    a = amplitude * delta_0
    dq, v = a * mode.right.real, (a * s * mode.right).real if moving else np.zeros(q.size)
    x, x_xi, x_rows = q + dq, network.history_step(q, q + dq, gamma, gamma, xi, rows)[0], rows
    dt = dt or STABLE_FRACTION * 2.0 / omega_bound(network, q, xi, rows, gamma, mass)
    t_end = t_end or run_length(s.real, eta, amplitude)
    stretch = min(2.0 * math.pi / abs(s.imag), t_end)
    F = network.forces(q, xi, rows, gamma)
    floor = FLOOR * float(np.sum(F * F / (2.0 * mass))) / eta ** 2 if eta > 0 else 0.0
    settle = settling_time(s.real, eta)
    t, largest, kinetic, peak, slides, at_rest = 0.0, a, 0.0, 0.0, 0, False
    while not at_rest and t < t_end * (1 - 1e-12):
        run = simulate(network, x, v, x_xi, x_rows, gamma, mass, dt, min(stretch, t_end - t),
                       FRAMES, eta)
        x, v, x_xi, x_rows = run.q[-1], run.v[-1], run.xi, run.rows
        t, slides = t + float(run.t[-1]), slides + int(run.capped[-1])
        largest = max(largest, float(np.sqrt(np.sum(mass * (run.q - q) ** 2, axis=1)).max()))
        now = float(run.kinetic.max())
        if now > kinetic:
            kinetic, peak = now, t - run.t[-1] + float(run.t[np.argmax(run.kinetic)])
        at_rest = now <= REST * kinetic or (now <= floor and t - peak >= settle)
    x, x_xi, x_rows, _ = relax(network, x, x_xi, x_rows, gamma, f_tol)
    u = x - q
    moved = float(np.sqrt(np.sum(mass * u * u)))
    start, end = holding(network, q, rows, gamma), holding(network, x, x_rows, gamma, q, rows)
    gained, lost = len(end - start), len(start - end)
    verdict = ("rearranged" if gained + lost or moved >= REARRANGING * delta_0 else
               "saturated" if not at_rest else "returned" if moved <= a else "slipped")
    stress = (network.stress(x, x_xi, x_rows, gamma)[2] / network.stress(q, xi, rows, gamma)[2]
              - 1.0)
    overlap = None if w is None else mass_overlap(u, w, mass)
    return Outcome(verdict, t, largest, u, gained, lost, slides, a, float(stress), overlap)


def holding(network: Network, q: np.ndarray, rows: np.ndarray, gamma: float,
            q_ref: Optional[np.ndarray] = None, rows_ref: Optional[np.ndarray] = None) -> set:
    """Keys (equilibria.row_keys) of the rows whose overlap at (q, gamma) exceeds HOLDING times
    the median positive overlap at (q_ref, rows_ref) (default: this state's)."""
    ref = network.overlaps(q if q_ref is None else q_ref, rows if rows_ref is None else rows_ref,
                           gamma)
    delta = network.overlaps(q, rows, gamma)
    return set(row_keys(rows[delta > HOLDING * np.median(ref[ref > 0])]).tolist())


def mass_overlap(u: np.ndarray, w: np.ndarray, mass: np.ndarray) -> float:
    """|<u, w>_M| / (|u|_M |w|_M), <u, w>_M = sum m u w, of two displacement fields (3N,) each
    without its centre-of-mass translation (x and y) [1]."""
    u, w = centred(u, mass), centred(w, mass)
    return float(abs(np.sum(mass * u * w)) / np.sqrt(np.sum(mass * u * u) * np.sum(mass * w * w)))


def centred(u: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """u (3N,) less its centre-of-mass translation: the mass-weighted mean of its x and of its y
    parts subtracted from each."""
    N = u.size // 3
    out = u.copy()
    for part in (slice(0, N), slice(N, 2 * N)):
        out[part] -= np.sum(mass[part] * u[part]) / np.sum(mass[part])
    return out


@dataclass(frozen=True)
class Causality:
    """The runs from a shear branch at the drag eta [1 / time] (causality): per run the state k,
    its strain, the damped growth rate Re s of the mode run along [1 / time], the strain of the
    next plastic event (nan where the segment ends without one) and the Outcome (its overlap
    with that event's displacement)."""

    eta: float
    states: np.ndarray
    gamma: np.ndarray
    rates: np.ndarray
    folds: np.ndarray
    outcomes: tuple[Outcome, ...]
    failed: tuple[tuple[float, str], ...] = ()

    @property
    def counts(self) -> dict[str, int]:
        """The runs per verdict (every one of VERDICTS, 0 where none), and "failed": the runs
        whose end FIRE could not relax (failed: their strain and why)."""
        found = Counter(outcome.verdict for outcome in self.outcomes)
        return {verdict: found[verdict] for verdict in VERDICTS} | {"failed": len(self.failed)}


def onsets(branch: Branch, eta: float) -> np.ndarray:
    """The states where a damped-unstable mode appears along each segment: Re s > 0 there
    (damped.damped_rates) and not at the segment's state before (or it is the segment's first)."""
    rates = damped_rates(branch.eigenvalues, eta)
    unstable = rates > 0
    first = np.zeros(len(branch), bool)
    for piece in branch.of_kind("segment"):
        first[piece.start] = True
    return np.flatnonzero(unstable & (first | ~np.roll(unstable, 1)))


def causality(branch: Branch, network: Network, mass: np.ndarray, eta: float, delta_0: float,
              amplitude: float = AMPLITUDE, moving: bool = True, f_tol: float = 1e-11
              ) -> Causality:
    """run_mode from every onset of a damped-unstable pair on a shear branch with spectra "full"
    of M^-1 J (models/packing/shear.py; onsets), along the state's fastest damped mode
    (damped_modes, fastest), compared with the displacement q_after - q_before of the plastic
    event ending the state's segment, where there is one (and its relaxed state is known:
    PlasticEvent.after). ValueError for a branch without those spectra."""
    if (branch.matrix is not Matrix.M_INV_J or branch.eigenvalues.shape[1] == 0
            or branch.window is not None):
        raise ValueError("the onsets are found in the whole spectrum of M^-1 J at every state: a "
                         "shear with spectra \"full\", no window and matrix \"M^-1 J\"")
    ends = {piece.label: piece.stop - 1 for piece in branch.of_kind("segment")}
    segment = branch.labels("segment")
    states, gamma, rates, folds, outcomes, failed = [], [], [], [], [], []
    for k in onsets(branch, eta):
        q, xi, rows, g = branch.q[k], branch.xi[k], branch.rows[k], float(branch.gamma[k])
        mode = fastest(damped_modes(network, mass, q, xi, rows, g)[1], eta)
        label = int(segment[k])
        event = branch.plastic[label] if label < len(branch.plastic) else None
        known = event is not None and event.after is not None
        w = event.after[0] - branch.q[ends[label]] if known else None
        try:
            outcomes.append(run_mode(network, mass, q, xi, rows, g, mode, eta, delta_0, amplitude,
                                     moving, w=w, f_tol=f_tol))
        except RelaxationFailed as error:  # counted apart: no verdict without a relaxed end
            failed.append((g, str(error)))
            continue
        states.append(int(k))
        gamma.append(g)
        rates.append(mode.growth_rate(eta))
        folds.append(np.nan if event is None else event.gamma)
    return Causality(eta, np.array(states, int), np.array(gamma), np.array(rates),
                     np.array(folds), tuple(outcomes), tuple(failed))
