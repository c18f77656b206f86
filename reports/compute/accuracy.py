"""Accuracy against cost: continuation steps and tolerances, the Jacobian against finite
differences, the dynamics' time step. Each result names its reference. Raw units; times are
wall-clock seconds on this machine (warm: compiled code loaded before timing)."""
from __future__ import annotations

import time

import numpy as np

from diskfriction.reports.compute.branches import _sweep, _system, sweep_span
from diskfriction.reports.registry import DYNAMICS_DEPS, computation
from diskfriction.scenes import Scene


def collision_error(F: np.ndarray, kinds: list[str], F_ref: np.ndarray, kinds_ref: list[str]) -> float:
    """max over the reference collisions of the distance to the nearest one of the same kind
    (inf if a kind is missing altogether) [force]."""
    worst = 0.0
    for p, kind in zip(F_ref, kinds_ref):
        same = np.array([f for f, k in zip(F, kinds) if k == kind])
        worst = max(worst, float(np.min(np.abs(same - p))) if same.size else np.inf)
    return worst


def _timed_sweep(scene: Scene, matrix: str, ds_max: float, tol_p: float | None):
    t0 = time.perf_counter()
    b = _sweep(scene, *scene.F_x_range, matrix, ds_max, tol_p=tol_p)
    return b, time.perf_counter() - t0


@computation("continuation_accuracy")
def continuation_accuracy(scene: Scene, matrix: str, divisions: list[int], tol_ps: list[float],
                          reference_divisions: int, reference_tol_p: float) -> dict:
    """Collision-location error against a fine reference sweep (ds_max = span /
    reference_divisions, bracket tol_p = reference_tol_p), and the sweep's wall time, for
    ds_max = span / d (d in divisions, default tol_p) and for tol_p in tol_ps (default ds_max)."""
    span = sweep_span(scene)
    ref, ref_time = _timed_sweep(scene, matrix, span / reference_divisions, reference_tol_p)
    F_ref, k_ref = [c.p for c in ref.collisions], [c.kind for c in ref.collisions]
    out = {"reference_seconds": ref_time, "reference_collisions": len(F_ref)}
    for name, values, make in (("ds", divisions, lambda d: (span / d, None)),
                               ("tol", tol_ps, lambda t: (None, t))):
        err, sec, count = [], [], []
        for v in values:
            b, s = _timed_sweep(scene, matrix, *make(v))
            err.append(collision_error(np.array([c.p for c in b.collisions]),
                                       [c.kind for c in b.collisions], F_ref, k_ref))
            sec.append(s)
            count.append(len(b.collisions))
        out.update({f"{name}_values": np.array(values, dtype=float), f"{name}_error": np.array(err),
                    f"{name}_seconds": np.array(sec), f"{name}_collisions": np.array(count)})
    return out


def _fd_jacobian(system, q, xi, h: float, order: int) -> np.ndarray:
    """-dF/dq by central differences of the generated F with the history following q (trial
    history of the quasistatic step, no cap): order 2 (2n forces) or 4 (4n forces)."""
    n = q.size
    stencil = {2: ((1, 0.5),), 4: ((1, 2 / 3), (2, -1 / 12))}[order]
    J = np.zeros((n, n))
    for c in range(n):
        for k, weight in stencil:
            for sign in (1, -1):
                q1 = q.copy()
                q1[c] += sign * k * h
                xi1 = system.history_step(q, q1, xi, cap=False)[0]
                J[:, c] -= sign * weight * system.forces(q1, xi1, 0.0) / h
    return J


def row_relative_error(J: np.ndarray, J_ref: np.ndarray) -> float:
    """max over rows of max|J - J_ref| / max|J_ref row| (rows of zeros skipped)."""
    scale = np.abs(J_ref).max(axis=1)
    rows = scale > 0
    return float(np.max(np.abs(J - J_ref).max(axis=1)[rows] / scale[rows]))


@computation("jacobian_accuracy")
def jacobian_accuracy(scene: Scene, F_x: float, steps: list[float]) -> dict:
    """Finite-difference Jacobians (central, 2nd and 4th order, step h) of the generated F at
    the branch point at F_x, against the generated exact J; wall time of one Jacobian each."""
    from diskfriction.models.chain.equilibrium import equilibrium_at

    system = _system(scene)
    eq = equilibrium_at(system, F_x)
    q, xi = eq.q, eq.xi
    J = system.jacobian(q, xi)
    reps = 200
    t0 = time.perf_counter()
    for _ in range(reps):
        system.forces_and_jacobian(q, xi, F_x)
    out = {"exact_seconds": (time.perf_counter() - t0) / reps, "steps": np.array(steps, dtype=float),
           "min_overlap": float(np.min(system.overlaps(q)[system.overlaps(q) > 0]))}
    for order in (2, 4):
        err, sec = [], []
        for h in steps:
            t0 = time.perf_counter()
            J_fd = _fd_jacobian(system, q, xi, h, order)
            sec.append(time.perf_counter() - t0)
            err.append(row_relative_error(J_fd, J))
        out[f"fd{order}_error"], out[f"fd{order}_seconds"] = np.array(err), np.array(sec)
    return out


@computation("dynamics_accuracy", DYNAMICS_DEPS)
def dynamics_accuracy(scene: Scene, F_x: float, fractions: list[float], reference_fraction: float,
                      t_end: float) -> dict:
    """Runs from the branch point at F_x started on the growing solution of its largest
    complex pair of M^-1 J (amplitude 1e-10; a random velocity kick 1e-6 if there is none) with
    dt = fraction * 2 / omega_max: wall time, growth rate sigma of M's exponential phase
    (reference: the spectrum's |Im sqrt(lambda)|, and the finest dt), energy-budget drift
    max|budget - budget(0)| (reference: exact conservation), V_cm over the last half (reference:
    the finest dt)."""
    from diskfriction.models.chain.equilibrium import equilibrium_at
    from diskfriction.dynamics import Perturbation, simulate, spectrum, summarize

    system = _system(scene)
    eq = equilibrium_at(system, F_x)
    q, xi = eq.q, eq.xi
    has_pair = spectrum(system, q, xi).pairs.size > 0
    start = Perturbation("eigenvector", 1e-10) if has_pair else Perturbation("random-velocity", 1e-6)
    simulate(system, q, xi, F_x, 1e-3, perturbation=start)  # load the compiled stepper
    rows = []
    for f in list(fractions) + [reference_fraction]:
        t0 = time.perf_counter()
        traj = simulate(system, q, xi, F_x, t_end, perturbation=start, dt_fraction=f)
        seconds = time.perf_counter() - t0
        s = summarize(traj)
        rows.append((f, traj.dt, seconds, s["sigma_measured"], s["sigma_predicted"],
                     s["budget_error"], s["V_cm"], traj.steps))
    f, dt, sec, sigma, pred, budget, vcm, steps = (np.array([np.nan if v is None else v for v in c],
                                                            dtype=float) for c in zip(*rows))
    return {"fraction": f[:-1], "dt": dt[:-1], "seconds": sec[:-1], "sigma": sigma[:-1],
            "budget_error": budget[:-1], "V_cm": vcm[:-1], "steps": steps[:-1],
            "sigma_predicted": float(pred[-1]), "reference": {
                "fraction": float(f[-1]), "dt": float(dt[-1]), "seconds": float(sec[-1]),
                "sigma": None if np.isnan(sigma[-1]) else float(sigma[-1]),
                "budget_error": float(budget[-1]), "V_cm": float(vcm[-1])},
            "start": start.kind}
