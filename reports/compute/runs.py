"""Dynamics-derived computations: single runs (Figs. 3, 4, 7 upper) and ensembles (Fig. 5,
Fig. 7 lower). Raw units in every result (docs/model.md#units)."""
from __future__ import annotations

import importlib.util

import numpy as np

from diskfriction.reports.compute.branches import _system
from diskfriction.reports.registry import DYNAMICS_DEPS, ComputationFailed, computation
from diskfriction.scenes import Scene

MAX_FRAMES = 40_000
"""Frames kept of M, C_x, C_y (evenly thinned beyond this); the tracked disk keeps every frame
up to the end of its spiral."""


def missing(module: str) -> str | None:
    """None if `module` can be imported, else the line a report prints instead."""
    try:
        found = importlib.util.find_spec(module) is not None
    except ImportError as error:  # the parent package itself does not import
        return f"needs {module} (import failed: {error})"
    return None if found else f"needs {module} (not in this checkout)"


def _thin(n: int) -> slice:
    return slice(None, None, max(1, -(-n // MAX_FRAMES)))


@computation("trajectory", DYNAMICS_DEPS)
def trajectory(scene: Scene, F_x: float, t_end: float, kick: float, seed: int, disk: int) -> dict:
    """One run from the branch point at F_x with a seeded random velocity kick of amplitude
    `kick` [length / time] (dynamics.simulate, default dt and recording), to t_end [time].
    Keeps t, M [length^2], C_x, C_y [length] (thinned to MAX_FRAMES), x, y of `disk` (1-based)
    at every frame until 10 % past its first breach or onset of sliding, and the summary."""
    from diskfriction.models.chain.equilibrium import equilibrium_at
    from diskfriction.dynamics import Perturbation, simulate, summarize

    if not 1 <= disk <= scene.N:
        raise ComputationFailed(f"disk {disk} is not one of 1..{scene.N}")
    system = _system(scene)
    eq = equilibrium_at(system, F_x)
    traj = simulate(system, eq.q, eq.xi, F_x, t_end,
                    perturbation=Perturbation("random-velocity", kick, seed))
    events = np.r_[traj.breach_t[disk - 1], traj.onset_t[disk - 1]]
    events = events[np.isfinite(events)]
    stop = 1.1 * events.min() if events.size else traj.t[-1]
    keep = traj.t <= stop
    s = _thin(traj.t.size)
    return {"t": traj.t[s], "M": traj.M[s], "C_x": traj.C_x[s], "C_y": traj.C_y[s],
            "disk_t": traj.t[keep], "disk_x": traj.x[keep, disk - 1], "disk_y": traj.y[keep, disk - 1],
            "summary": summarize(traj)}


@computation("ensemble", DYNAMICS_DEPS)
def ensemble(scene: Scene, loads: list[float], realizations: int, t_end: float, kick: float,
             seed: int, workdir: str) -> dict:
    """studies.ensemble.run_ensemble (seeded random-velocity kicks, seeds seed..seed+R-1):
    V1 per load, V2 pooled, V_cm per load and its linear fit [raw units], and per load the
    first-breach and sliding-onset times and positions of every disk in every realization
    (arrays realizations x N, nan where it never happened)."""
    from diskfriction.studies.ensemble import run_ensemble

    ens = run_ensemble(scene, loads, realizations, t_end, out=workdir, seed=seed, amplitude=kick)
    out = ens.as_dict()
    for F, summaries in ens.summaries.items():
        for event in ("first_breach", "onset"):
            for part in ("t", "x"):
                out[f"{event}_{part}@{F!r}"] = np.array(
                    [[np.nan if v is None else v for v in s[event][part]] for s in summaries],
                    dtype=float).reshape(len(summaries), scene.N)
        out[f"sigma_predicted@{F!r}"] = np.array([s["sigma_predicted"] for s in summaries], dtype=float)
    return out
