"""Past a plastic event: where quasistatic shear reaches a fold in gamma (the saddle-node where
the branch is lost), the packing is strained a little further and relaxed with friction to the
next mechanically stable state, from which the shear goes on (docs/packings.md#plastic-events).

The relaxation is FIRE (packings/fire.py) on the frictional forces, the history following the
relaxation path by the chain's rule (the Coulomb cap included: contacts slide during the
rearrangement), the contact rows found again whenever the disks may have moved half the reach.
FIRE's quenches (velocities zeroed going uphill) stand for the dissipation of a real
rearrangement; the state it finds is an equilibrium with the history the path charged, not the
one an undamped run would settle in (which needs the dynamics: packings/dynamics.py).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from diskfriction.packings.equilibria import REACH, carried
from diskfriction.packings.fire import DT_MAX_RATIO, fire
from diskfriction.packings.network import Network

PAST_FOLD = 1e-7
"""The strain beyond a fold at which the packing is relaxed [1]: the run ends within about
ds_min of the fold, so this is past it, and small against the strain between events."""


MAX_STEPS = 200_000
"""FIRE steps a relaxation may take."""

STALLED = 1e3
"""FIRE that ends its steps with max |F| within this factor of the tolerance is taken: the
next segment starts with Newton at fixed strain from that state (arclength's first corrector
solve), which takes the last digits in an iteration or two. 256 disks (seed 1) after the
plastic event at gamma = 0.0212 stalled at 2.5e-11 against 1e-11 after 200 000 steps, and the
run ended there (stop 42)."""


DT_MAX_STABLE = 1.5
"""omega dt_max of the relaxation's stiffest mode, at most (time_step), on the first attempt.
FIRE's step is semi-implicit Euler, stable for omega dt < 2. The preparation's dt0
(prepare.first_time_step, sized for the overlaps of a random start) made it about 0.75 after
the plastic events of 256 sheared disks (seed 1): their first 30 relaxations took 456 344
steps with it and stop 42's code, one of them failing (stuck at max |F| = 9.8e-6), against
159 271 with this rule, none failing (docs/packings.md#plastic-events; the two rules alone, on
the same compiled step: benchmarks/plastic_relaxations.py)."""

ATTEMPTS = 3
"""Relaxations tried from the same state, each with half the last one's time step, before
RelaxationFailed. With the Coulomb cap the forces are not a gradient, and FIRE can circle
without settling: 256 disks (seed 1) after the event at gamma = 0.0147 stayed near max |F| =
6e-4 for 200 000 steps at omega dt_max <= 1.5 and settled in 15 313 at half of it (stop 43)."""


class RelaxationFailed(RuntimeError):
    """FIRE did not bring the forces near the tolerance after a plastic event (STALLED)."""


@dataclass(frozen=True)
class PlasticEvent:
    """A plastic event: the strain gamma where the branch was lost, the shear stress sigma_xy
    before and after [force / length], the mass-free displacement |q_after - q_before|
    [length], the FIRE steps the relaxation took, and how the branch was lost (the segment's
    Stop code, packings/shear.py: PLASTIC)."""

    gamma: float
    stress_before: float
    stress_after: float
    displacement: float
    steps: int
    kind: str = "fold"


def time_step(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray,
              gamma: float) -> float:
    """FIRE's dt0 for a relaxation from (q, xi, rows) [time with unit masses]: dt_max = 10 dt0
    = DT_MAX_STABLE / sqrt(||J||_inf), J = -dF/dq there. ||J||_inf (the largest absolute row
    sum) bounds every |lambda| of J, so the stiffest mode's omega dt_max <= DT_MAX_STABLE,
    inside the semi-implicit Euler step's limit 2."""
    J = network.evaluate(q, xi, rows, gamma)[1]
    return DT_MAX_STABLE / (DT_MAX_RATIO * np.sqrt(abs(J).sum(axis=1).max()))


def relax(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray, gamma: float,
          f_tol: float, max_steps: int = MAX_STEPS) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """FIRE on the frictional forces at fixed strain from (q, xi, rows) until max |F| <= f_tol
    [force]; returns (q, xi, rows, steps) of the relaxed state, also where FIRE ran out of
    steps within STALLED times f_tol (the caller's Newton solve finishes it). Where it stops
    farther away, FIRE starts again from (q, xi, rows) with half the time step, up to ATTEMPTS
    runs in all (steps: over all of them); RelaxationFailed after them."""
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

    dt0, steps = time_step(network, q, xi, rows, gamma), 0
    for attempt in range(ATTEMPTS):
        state.update(q=q.copy(), xi=xi.copy(), delta=network.overlaps(q, rows, gamma), rows=rows,
                     searched=q.copy())
        result = fire(forces, q, dt0 / 2 ** attempt, f_tol, max_steps)
        steps += result.steps
        if result.max_force <= STALLED * f_tol:
            return result.x, state["xi"], state["rows"], steps
    raise RelaxationFailed(f"the relaxation after the plastic event at gamma = {gamma:.9g} "
                           f"stopped at max |F| = {result.max_force:.3g} after {result.steps} "
                           f"FIRE steps ({ATTEMPTS} attempts, the time step halved each time)")


def past_fold(network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray, gamma: float,
              f_tol: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, float, int]:
    """The state after the plastic event at the fold (q, xi, rows, gamma): strained affinely by
    PAST_FOLD (x += d gamma y, the histories charged by it), then relaxed. Returns (q, xi,
    rows, gamma + PAST_FOLD, FIRE steps)."""
    N, gamma_new = network.N, gamma + PAST_FOLD
    q_affine = q.copy()
    q_affine[:N] += PAST_FOLD * q[N:2 * N]
    xi_affine, _ = network.history_step(q, q_affine, gamma, gamma_new, xi, rows)
    q1, xi1, rows1, steps = relax(network, q_affine, xi_affine, rows, gamma_new, f_tol)
    return q1, xi1, rows1, gamma_new, steps
