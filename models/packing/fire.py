"""FIRE, the fast inertial relaxation engine (Bitzek, Koskinen, Gaehler, Moseler, Gumbsch,
PRL 97, 170201 (2006)): damped molecular dynamics that steers the velocity towards the force
and restarts from rest whenever it goes uphill. Generic over plain numpy arrays; the force is
any Python callable. The step itself is compiled (fire_update, max_row_force): with numpy,
max_row_force alone took 5.7 microseconds and each of the step's sums about 2 at 256 sheared
disks, whose relaxation step takes 48 microseconds in all (docs/notes/packings-plastic-events.md,
"FIRE's time step from the state's stiffest mode").

One step, with unit masses (semi-implicit Euler, the velocity mixed before the drift):
    P = F . v
    P > 0:  after N_MIN such steps in a row, dt <- min(F_INC dt, dt_max), alpha <- F_ALPHA alpha
    P <= 0: v <- 0, dt <- F_DEC dt, alpha <- ALPHA_START
    v <- v + dt F;  v <- (1 - alpha) v + alpha |v| F / |F|;  x <- x + dt v
Dot products and norms are sums over every component in index order (no BLAS), so the same
input gives a bit-identical result.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Optional

import numba
import numpy as np

N_MIN = 5            # uphill-free steps before dt may grow
F_INC = 1.1          # dt growth factor
F_DEC = 0.5          # dt cut after an uphill step
ALPHA_START = 0.1    # velocity mixing after a restart
F_ALPHA = 0.99       # mixing decay per downhill step
DT_MAX_RATIO = 10.0  # dt_max = 10 dt0
PROGRESS_EVERY = 1000  # steps between progress calls

Forces = Callable[[np.ndarray], tuple[np.ndarray, float]]
"""forces(x) -> (F, energy), F = -dE/dx with the shape of x."""
Progress = Callable[[str, Optional[float]], None]
"""progress(stage, fraction or None), as in symbolic.generated."""


@dataclass(frozen=True, eq=False)
class FireResult:
    """Where FIRE stopped. x: the coordinates; energy: E(x); max_force: max_row |F(x)| (see
    max_row_force); steps: MD steps taken (force evaluations = steps + 1); converged:
    max_force <= f_tol."""
    x: np.ndarray
    energy: float
    max_force: float
    steps: int
    converged: bool


def max_row_force(F: np.ndarray) -> float:
    """max_i |F_i|, F_i the i-th row of F (all components but the first axis): for positions
    (N, 2) the largest net force on one disk, for a flat array the largest component
    [force units]."""
    F = np.ascontiguousarray(F, dtype=float)
    return _max_row_norm(F.reshape(F.shape[0], -1)) if F.size else 0.0


@numba.njit(cache=True)
def _max_row_norm(rows):
    largest = 0.0
    for i in range(rows.shape[0]):
        squared = 0.0
        for a in range(rows.shape[1]):
            squared += rows[i, a] * rows[i, a]
        largest = max(largest, squared)
    return np.sqrt(largest)


@numba.njit(cache=True)
def fire_update(x, v, F, dt, alpha, downhill, dt_max):
    """One FIRE step (module docstring) on the flat arrays x, v in place, F the force at x;
    returns the new (dt, alpha, downhill)."""
    power = 0.0
    for i in range(x.shape[0]):
        power += F[i] * v[i]
    if power > 0.0:
        downhill += 1
        if downhill > N_MIN:
            dt, alpha = min(F_INC * dt, dt_max), F_ALPHA * alpha
    else:
        v[:] = 0.0
        dt, alpha, downhill = F_DEC * dt, ALPHA_START, 0
    vv, ff = 0.0, 0.0
    for i in range(x.shape[0]):
        v[i] += dt * F[i]
        vv += v[i] * v[i]
        ff += F[i] * F[i]
    mix = alpha * np.sqrt(vv / ff)
    for i in range(x.shape[0]):
        v[i] = (1.0 - alpha) * v[i] + mix * F[i]
        x[i] += dt * v[i]
    return dt, alpha, downhill


def fire(forces: Forces, x0: np.ndarray, dt0: float, f_tol: float, max_steps: int,
         progress: Optional[Progress] = None) -> FireResult:
    """Minimise E from x0 by FIRE (module docstring) until max_row_force(F) <= f_tol [force
    units] or max_steps MD steps. dt0: the first time step [time units with unit masses],
    dt_max = 10 dt0. progress("FIRE step n, max |F| = ...", None) every 1000 steps.
    x0 is not modified."""
    if dt0 <= 0 or f_tol < 0 or max_steps < 0:
        raise ValueError(f"fire needs dt0 > 0, f_tol >= 0, max_steps >= 0 "
                         f"(got {dt0}, {f_tol}, {max_steps})")
    x = np.array(x0, dtype=float)
    v = np.zeros(x.size)
    F, energy = forces(x)
    dt, alpha, downhill = dt0, ALPHA_START, 0
    dt_max = DT_MAX_RATIO * dt0
    steps = 0
    max_force = max_row_force(F)
    while max_force > f_tol and steps < max_steps:
        flat = np.ascontiguousarray(F, dtype=float).reshape(-1)
        dt, alpha, downhill = fire_update(x.reshape(-1), v, flat, dt, alpha, downhill, dt_max)
        F, energy = forces(x)
        max_force = max_row_force(F)
        steps += 1
        if progress is not None and steps % PROGRESS_EVERY == 0:
            progress(f"FIRE step {steps}, max |F| = {max_force:.2e}", None)
    return FireResult(x, float(energy), max_force, steps, max_force <= f_tol)
