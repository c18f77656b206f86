"""Past a plastic event: where quasistatic shear reaches a fold in gamma (the saddle-node where
the branch is lost), the packing is strained a little further and relaxed with friction to the
next mechanically stable state, from which the shear goes on (docs/packings.md#plastic-events).

The relaxation (the scene's `relaxation`) is either FIRE (models/packing/fire.py, "fire", the default)
on the frictional forces, or Newtonian dynamics with a viscous drag ("damped": damped), the
history following the relaxation path by the chain's rule (the Coulomb cap included: contacts
slide during the rearrangement) either way, the contact rows found again whenever the disks may
have moved a fraction of the reach. The model has no damping (docs/model.md): FIRE's quenches
(velocities zeroed going uphill) or the drag stand for the dissipation of a real
rearrangement, and the state found is an equilibrium with the history its path charged, which
depends on that choice (docs/notes/packings-plastic-events.md compares them). Without tangential
forces (Network.frictional) the same relaxations act on the normal forces alone, and no
history is charged.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional

import numpy as np

from diskfriction.models.packing.equilibria import REACH, carried
from diskfriction.models.packing.fire import DT_MAX_RATIO, fire
from diskfriction.models.packing.network import Network
from diskfriction.scenes.packing import PackingScene

PAST_FOLD = 1e-7
"""The strain beyond a fold at which the packing is relaxed [1]: the run ends within about
ds_min of the fold, so this is past it, and small against the strain between events."""


MAX_STEPS = 200_000
"""FIRE steps a relaxation may take."""

STALLED = 1e3
"""FIRE that ends its steps with max |F| within this factor of the tolerance is taken: the
next segment starts with Newton at fixed strain from that state (arclength's first corrector
solve), which takes the last digits in an iteration or two. 256 disks (seed 1) after the
plastic event at gamma = 0.0212 stalled at 2.5e-11 against 1e-11 after 200 000 steps; without
this factor the run ended there."""


DT_MAX_STABLE = 1.5
"""omega dt_max of the relaxation's stiffest mode, at most (time_step), on the first attempt.
FIRE's step is semi-implicit Euler, stable for omega dt < 2. The preparation's dt0
(prepare.first_time_step, sized for the overlaps of a random start) made it about 0.75 after
the plastic events of 256 sheared disks (seed 1): their first 30 relaxations took 456 344
steps with it, one of them failing (stuck at max |F| = 9.8e-6), against 159 271 with this
rule, none failing (docs/notes/packings-plastic-events.md, "FIRE's time step from the state's
stiffest mode"; the two rules alone, on the same compiled step:
benchmarks/plastic_relaxations.py)."""

ATTEMPTS = 3
"""Relaxations tried from the same state, each with half the last one's time step, before
RelaxationFailed. With the Coulomb cap the forces are not a gradient, and FIRE can circle
without settling: 256 disks (seed 1) after the event at gamma = 0.0147 stayed near max |F| =
6e-4 for 200 000 steps at omega dt_max <= 1.5 and settled in 15 313 at half of it."""


class RelaxationFailed(RuntimeError):
    """FIRE did not bring the forces near the tolerance after a plastic event (STALLED)."""


@dataclass(frozen=True)
class PlasticEvent:
    """A plastic event: the strain gamma where the branch was lost, the shear stress sigma_xy
    before and after [force / length], the mass-free displacement |q_after - q_before|
    [length], the steps the relaxation took (FIRE's or the damped dynamics'), how the
    branch was lost (the segment's Stop code, models/packing/shear.py: PLASTIC), and the
    relaxed state after it, (q, xi, rows, gamma), where the shear goes on (None where not
    known)."""

    gamma: float
    stress_before: float
    stress_after: float
    displacement: float
    steps: int
    kind: str = "fold"
    after: Optional[tuple] = field(default=None, compare=False, repr=False)


def time_step(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray,
              gamma: float) -> float:
    """FIRE's dt0 for a relaxation from (q, xi, rows) [time with unit masses]: dt_max = 10 dt0
    = DT_MAX_STABLE / sqrt(||J||_inf), J = -dF/dq there. ||J||_inf (the largest absolute row
    sum) bounds every |lambda| of J, so the stiffest mode's omega dt_max <= DT_MAX_STABLE,
    inside the semi-implicit Euler step's limit 2."""
    return DT_MAX_STABLE / (DT_MAX_RATIO * omega_bound(network, q, xi, rows, gamma, 1.0))


def omega_bound(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray, gamma: float,
                mass) -> float:
    """sqrt(||M^-1 J||_inf) at (q, xi, rows) [1 / time], J = -dF/dq, M = diag(mass) (1.0: unit
    masses): the largest absolute row sum bounds every |lambda| of M^-1 J, so no mode's omega
    exceeds it."""
    J = network.evaluate(q, xi, rows, gamma)[1]
    return float(np.sqrt((abs(J).sum(axis=1).A1 / mass).max()))


def relax(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray, gamma: float,
          f_tol: float, max_steps: int = MAX_STEPS) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """FIRE on the frictional forces at fixed strain from (q, xi, rows) until max |F| <= f_tol
    [force]; returns (q, xi, rows, steps) of the relaxed state, also where FIRE ran out of
    steps within STALLED times f_tol (the caller's Newton solve finishes it). Where it stops
    farther away, FIRE starts again from (q, xi, rows) with half the time step, up to ATTEMPTS
    runs in all; then the run that ended closest (least max |F|) goes on from its end, with
    its time step, for max_steps more; RelaxationFailed after that. steps: over all the runs.
    A relaxation can still be settling when its steps run out: after the fold of 256 disks
    (seed 1, window [-3, 2]) at gamma = 0.0405607, FIRE stayed near max |F| = 4e-7 for 30 000
    steps, then went through a second rearrangement (4.7e-3 at step 61 000) and was at
    2.2e-8 at step 200 000 (the band: 1e-8); the restarts from the fold state with half the
    time step ended at 1.3e-7 and 1.4e-5, and the shear stopped there. Continued, the first
    run ends at 1.8e-9."""
    reach = REACH * network.constants[0]
    state = {}

    def forces(x: np.ndarray):
        F, xi_new, delta = network.carried_forces(state["q"], x, state["xi"], state["delta"],
                                                  state["rows"], gamma)
        state["q"], state["xi"], state["delta"] = x.copy(), xi_new, delta
        if np.abs(x - state["searched"]).max() > 0.5 * reach:
            rows_new = network.contacts(x, gamma, reach)
            state["xi"], state["rows"], state["searched"] = (carried(state["rows"], xi_new, rows_new),
                                                            rows_new, x.copy())
            state["delta"] = network.overlaps(x, rows_new, gamma)
            F = network.forces(x, state["xi"], rows_new, gamma)
        return F, 0.0

    dt0, steps, closest = time_step(network, q, xi, rows, gamma), 0, None
    for attempt in range(ATTEMPTS):
        state.update(q=q.copy(), xi=xi.copy(), delta=network.overlaps(q, rows, gamma), rows=rows,
                     searched=q.copy())
        result = fire(forces, q, dt0 / 2 ** attempt, f_tol, max_steps)
        steps += result.steps
        if result.max_force <= STALLED * f_tol:
            return result.x, state["xi"], state["rows"], steps
        if closest is None or result.max_force < closest[0].max_force:
            closest = result, {key: np.copy(value) for key, value in state.items()}, attempt
    result, end, attempt = closest  # the attempt that came closest goes on from where it stopped
    state.update(end)
    result = fire(forces, result.x, dt0 / 2 ** attempt, f_tol, max_steps)
    steps += result.steps
    if result.max_force <= STALLED * f_tol:
        return result.x, state["xi"], state["rows"], steps
    raise RelaxationFailed(f"the relaxation after the plastic event at gamma = {gamma:.9g} "
                           f"stopped at max |F| = {result.max_force:.3g} after {steps} FIRE steps "
                           f"({ATTEMPTS} attempts, the time step halved each time, and the closest "
                           f"one continued)")


DT_DAMPED = 0.5
"""omega_max dt of the damped relaxation's velocity Verlet step, at most: a quarter of its
stability limit 2, omega_max^2 bounded by ||M^-1 J||_inf (damped_time_step)."""

CHUNK = 200
"""Steps of the damped relaxation between checks of its forces (one compiled call)."""

SEARCH_SHARE = 0.25
"""The damped relaxation finds the contact rows again once a disk may have moved this fraction
of the reach since the last search, and moves at most this fraction between checks (from its
speed and acceleration then): a pair that was no row has then closed at most the reach."""


def drag_rate(scene: PackingScene) -> Optional[float]:
    """The damped relaxation's drag rate eta = damping omega_0 [1 / time] (F_d = -eta M q' on
    every disk, translation and rotation; damping = 2 damps a small disk on one contact at the
    typical overlap critically: PackingScene.omega_0), or None where the scene relaxes by FIRE."""
    return scene.damping * scene.omega_0 if scene.relaxation == "damped" else None


def damped_time_step(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray,
                     gamma: float, mass: np.ndarray) -> float:
    """DT_DAMPED / sqrt(||M^-1 J||_inf) [time] (omega_bound): the stiffest mode's omega dt <=
    DT_DAMPED."""
    return DT_DAMPED / omega_bound(network, q, xi, rows, gamma, mass)


def damped(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray, gamma: float,
           f_tol: float, mass: np.ndarray, eta: float, max_steps: int = MAX_STEPS
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """Newtonian dynamics from rest at (q, xi, rows), M q'' = F(q, xi) - eta M q' (eta [1 /
    time]; velocity Verlet with the exact drag and the Coulomb cap, the kernels' advance), until
    max |F| <= f_tol [force]; returns (q, xi, rows, steps), also where it ran out of steps within
    STALLED times f_tol (the caller's Newton solve finishes it); RelaxationFailed farther away."""
    q, xi, v = q.copy(), xi.copy(), np.zeros(q.size)
    N, inv_mass, params = network.N, 1.0 / mass, network.params(gamma)
    dt = damped_time_step(network, q, xi, rows, gamma, mass)
    share = SEARCH_SHARE * REACH * network.constants[0]
    F, work = np.empty(q.size), np.zeros(1)
    network.kernels.forces(q, xi, network.radii, rows, params, F)
    searched, steps = q.copy(), 0
    while np.abs(F).max() > f_tol and steps < max_steps:
        speed = float(np.hypot(v[:N], v[N:2 * N]).max())
        accel = float(np.hypot(F[:N] * inv_mass[:N], F[N:2 * N] * inv_mass[N:2 * N]).max())
        t = min(0.5 * share / max(speed, 1e-300), np.sqrt(share / max(accel, 1e-300)))
        chunk = int(max(1, min(CHUNK, max_steps - steps, t / dt)))
        network.kernels.advance(q, v, xi, network.radii, rows, params, inv_mass, dt, chunk, F, work,
                                eta)
        steps += chunk
        if np.hypot(q[:N] - searched[:N], q[N:2 * N] - searched[N:2 * N]).max() > share:
            new_rows = network.contacts(q, gamma, REACH * network.constants[0])
            xi, rows, searched = carried(rows, xi, new_rows), new_rows, q.copy()
            network.kernels.forces(q, xi, network.radii, rows, params, F)
    largest = float(np.abs(F).max())
    if largest > STALLED * f_tol:
        raise RelaxationFailed(f"the damped relaxation after the plastic event at gamma = {gamma:.9g} "
                               f"stopped at max |F| = {largest:.3g} after {steps} steps")
    return q, xi if network.frictional else np.zeros_like(xi), rows, steps


def past_fold(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray, gamma: float,
              f_tol: float, mass: np.ndarray, eta: Optional[float] = None
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, int]:
    """The state after the plastic event at the fold (q, xi, rows, gamma): strained affinely by
    PAST_FOLD (x += d gamma y, the histories charged by it), then relaxed: by FIRE (eta None)
    or by damped dynamics with the drag rate eta (drag_rate). Returns (q, xi, rows, gamma +
    PAST_FOLD, steps)."""
    N, gamma_new = network.N, gamma + PAST_FOLD
    q_affine = q.copy()
    q_affine[:N] += PAST_FOLD * q[N:2 * N]
    xi_affine, _ = network.history_step(q, q_affine, gamma, gamma_new, xi, rows)
    if eta is None:
        q1, xi1, rows1, steps = relax(network, q_affine, xi_affine, rows, gamma_new, f_tol)
    else:
        q1, xi1, rows1, steps = damped(network, q_affine, xi_affine, rows, gamma_new, f_tol, mass, eta)
    return q1, xi1, rows1, gamma_new, steps
