"""Newtonian dynamics of a packing from a state of its shear branch (
docs/packings.md#dynamics): velocity Verlet with the Coulomb cap, the contact rows found again
every few steps (the history carried by row), the strain held fixed.

M q'' = F(q, xi; gamma) - eta M q', M = diag(m_i, m_i, I_i)
(models/packing/equilibria.mass_diagonal), eta a viscous drag rate [1 / time] (0 by default:
the model has none, and sliding, the cap, is the only dissipation; the damped linearization's
modes: dynamics/damped_modes.py). The history follows the motion by the chain's rule. The
energy budget E_k + U_n - W_t, W_t the work of the tangential forces on the disks, is conserved
by the exact undamped dynamics whether or not contacts slide; its drift measures the
integration error. With eta > 0 it decreases by the drag's work, int eta v.M v dt.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from diskfriction.files import json_values
from diskfriction.models.packing.equilibria import REACH, carried
from diskfriction.models.packing.network import Network

STABLE_FRACTION = 0.05
"""The default time step is this fraction of velocity Verlet's limit 2 / omega_max (the
chain's default: docs/dynamics.md)."""


@dataclass(frozen=True)
class PackingRun:
    """Frames of a run: t (f,) [time], q (f, 3N), v = q' (f, 3N), the energy budget
    E_k + U_n - W_t (f,) [energy] (which a drag lowers by its work), the kinetic energy (f,),
    sliding updates (f,) since the start, the step dt, and the histories xi of the contact rows
    at the end."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    budget: np.ndarray
    kinetic: np.ndarray
    capped: np.ndarray
    dt: float
    xi: np.ndarray
    rows: np.ndarray


def time_step(eigenvalues: np.ndarray) -> float:
    """STABLE_FRACTION of 2 / omega_max, omega_max^2 = max |lambda| of M^-1 J [time]."""
    return STABLE_FRACTION * 2.0 / float(np.sqrt(np.abs(eigenvalues).max()))


def run_steps(t_end: float, dt_max: float, frames: int) -> tuple[int, int]:
    """(steps, every): the fewest equal steps t_end / steps <= dt_max [time] that make a whole
    number of frames of `every` steps, about `frames` of them, so that the run ends exactly at
    t_end on its last frame (the chain's rule, dynamics/simulate.plan_run)."""
    every = max(1, int(t_end / (dt_max * frames)))
    return every * max(1, math.ceil(t_end / (every * dt_max) - 1e-9)), every


def simulate(network: Network, q: np.ndarray, v: np.ndarray, xi: np.ndarray, rows: np.ndarray,
             gamma: float, mass: np.ndarray, dt_max: float, t_end: float, frames: int = 200,
             eta: float = 0.0) -> PackingRun:
    """Run from (q, v, xi) over the contact rows `rows` to exactly t_end in equal steps of at
    most dt_max (run_steps), about `frames` frames evenly spaced, the last at t_end; the rows
    found again whenever the disks may have moved half the reach since the last search. eta:
    the drag rate [1 / time], the force -eta M q' on every dof (the kernels' advance: exact,
    v *= exp(-eta dt / 2) at either end of a step); 0, none, is the undamped run bit for bit.
    With eta > 0 the budget E_k + U_n - W_t is not conserved: it decreases by the drag's work,
    int eta v.M v dt."""
    q, v, xi = q.copy(), v.copy(), xi.copy()
    params, inv_mass = network.params(gamma), 1.0 / mass
    reach = REACH * network.constants[0]
    steps, every = run_steps(t_end, dt_max, frames)
    dt = t_end / steps
    F, work, capped = np.empty(q.size), np.zeros(1), 0
    network.kernels.forces(q, xi, network.radii, rows, params, F)
    out = []

    def frame(t):
        kinetic = 0.5 * float(np.sum(mass * v * v))
        U = network.kernels.normal_energy_sum(q, network.radii, rows, params)
        out.append((t, q.copy(), v.copy(), kinetic + U - work[0], kinetic, capped))

    frame(0.0)
    done = 0
    while done < steps:
        speed = float(np.abs(v).max())
        between = max(1, min(every - done % every, int(0.5 * reach / (speed * dt + 1e-300))))
        slides = network.kernels.advance(q, v, xi, network.radii, rows, params, inv_mass, dt,
                                         between, F, work, eta)
        if network.frictional:  # without tangential forces no contact slides: no history to cap
            capped += slides
        done += between
        new_rows = network.contacts(q, gamma, reach)
        xi = carried(rows, xi, new_rows)
        rows = new_rows
        network.kernels.forces(q, xi, network.radii, rows, params, F)
        if done % every == 0:
            frame(t_end * (done / steps))  # exactly t_end at the last step
    t, qs, vs, budget, kinetic, slid = (np.array(c) for c in zip(*out))
    return PackingRun(t, qs, vs, budget, kinetic, slid, dt, xi, rows)


def distance(run: PackingRun, q_eq: np.ndarray, mass: np.ndarray) -> np.ndarray:
    """The mass-weighted distance from the equilibrium, sqrt(sum m (q - q_eq)^2), per frame."""
    return np.sqrt(np.sum(mass * (run.q - q_eq) ** 2, axis=1))


LINEAR_RANGE = 1e-5
"""A run is taken as linear while its mass-weighted distance from the state is below this
fraction of the typical overlap delta_0 (scenes/packing.PackingScene.delta_0) [1]. Contacts
near their Coulomb limit bend the growth long before contacts open: on 24 disks (seed 3, to
gamma = 0.002, runs from 1e-10 along 12 states' fastest pairs) the rate fitted up to 1e-3
delta_0 was up to 51 % low (a state with four pairs), up to 1e-4 delta_0 1.8 % low, up to 1e-5
delta_0 within 0.3 % of |Im sqrt(lambda)| at every state, within 0.05 % at nine of them
(velocity Verlet's own error at dt = 0.05 of its limit, at gamma = 0.002: 0.033 %, 0.0084 % at
half the step)."""

MIN_FRAMES = 10
"""The fewest frames a growth rate is fitted over."""


@dataclass(frozen=True)
class GrowthFit:
    """The growth rate sigma [1 / time] of a run's linear phase and its standard error (nan
    when none was fitted), the window [t_start, t_end] [time] and its frames, and reason: "ok",
    or why no rate was fitted and what would give one."""

    sigma: float
    stderr: float
    t_start: float
    t_end: float
    frames: int
    reason: str

    def as_dict(self) -> dict:
        """The fit as JSON values (None for nan)."""
        return json_values(asdict(self))


def no_fit(reason: str, frames: int = 0) -> GrowthFit:
    """A GrowthFit without a rate, for `reason`."""
    nan = float("nan")
    return GrowthFit(nan, nan, nan, nan, frames, reason)


def fit_growth(t: np.ndarray, amplitude: np.ndarray, d: np.ndarray, d_linear: float
               ) -> GrowthFit:
    """The growth rate of a mode's amplitude |c(t)| (c its complex amplitude: |c| = |c_0|
    e^(sigma t) exactly in the linear dynamics, with no oscillation, whether sigma is above or
    below the frequency omega): sigma the slope of the least-squares line through (t, log |c|)
    over the frames before the mass-weighted distance d(t) from the state first reaches d_linear
    (the linear range), at least MIN_FRAMES of them."""
    frames = t.size - 1
    beyond = np.flatnonzero(d >= d_linear)
    n = beyond[0] if beyond.size else t.size
    if n == 0:
        return no_fit(f"the start lies beyond the linear range (distance {d[0]:.3g} >= "
                      f"{d_linear:.3g}): a smaller --amplitude")
    window = np.arange(n)[amplitude[:n] > 0]
    if window.size < MIN_FRAMES and n == t.size:
        return no_fit(f"the run has {t.size} frames, fewer than {MIN_FRAMES}: a longer --t-end",
                      int(window.size))
    if window.size < MIN_FRAMES:
        longest = t[n] * frames / (2 * MIN_FRAMES)
        return no_fit(f"the distance left the linear range ({d_linear:.3g}) at t = {t[n]:.4g}, "
                      f"within {window.size} of the run's {frames} frames: a shorter --t-end "
                      f"(at most {longest:.3g}) or a smaller --amplitude", int(window.size))
    (slope, _), cov = np.polyfit(t[window], np.log(amplitude[window]), 1, cov=True)
    return GrowthFit(float(slope), float(np.sqrt(cov[0, 0])), float(t[window[0]]),
                     float(t[window[-1]]), int(window.size), "ok")


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
