"""Parameter maps of packings: in every cell of a grid of packing scene keys (contacts.mu,
packing.pressure, packing.N, packing.seed, ...), the shear run `bifurcate` makes, summarised
as docs/packings.md#what-the-tool-finds tabulates it (benchmarks/packing_physics.py's row).

A cell (packing_cell, a dask task as studies/maps.py runs it, raw units) prepares the cell's
packing, shears it over the scene's strain range passing up to `plastic_events` plastic events
(models/packing/shear.py; with `window` only the eigenvalues with Re lambda in it, by sparse
shift-invert) and summarises the branch (PACKING_COLUMNS):
  * status: "ok" (the shear reached the range's end), "ended" (it stopped before, at a
    plastic event it may not pass or where the branch ended: `reason` says where and why) or
    "failed" (the preparation or the shear raised, e.g. a spectral window crowded: `reason`
    is its line, and nothing of the branch is kept);
  * gamma_end, the strain reached; states, the accepted equilibria;
  * per unit strain, not per state (models/packing/strain_statistics.py: each state stands for
    the strain halfway to its neighbours in its segment; the states crowd near contact events,
    collisions and folds, where a mean over states would weigh them): complex_fraction, the
    fraction of the strain covered with at least one complex pair of the matrix (in the
    window, if one); pairs_mean, the mean number of pairs; sigma_median, the median of the
    fastest mode's growth rate at zero drag sigma = max Re sqrt(-lambda) over the eigenvalues
    of M^-1 J [1 / time] (the fastest pair's |Im sqrt(lambda)|; a real lambda < 0, a static
    instability, would grow at sqrt(-lambda)) over the strain where a mode grows;
    sigma_max, its largest at a state; omega_c = sqrt(k_c / m) (PackingScene.omega_0), k_c =
    dF_n/ddelta at the typical overlap delta_0, the frequency of one small disk on one typical
    contact [1 / time], to read them against (sigma / omega_c is comparable across pressures
    and stiffnesses). sigma None for "J";
  * collisions located, collisions_per_disk_strain the same per disk per unit strain covered
    (the plastic events' jumps left out), plastic_events passed, max_drop the largest
    relative drop of sigma_xy at one, sigma_xy_end the shear stress at the end
    [force / length];
  * wall_time [s], the only field that depends on the machine.
A cell is a pure function of its scene and parameters, as a chain's is (studies/maps.py).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Optional

import numpy as np

from diskfriction.scenes.packing import PackingScene

PACKING_COLUMNS = ("status", "gamma_end", "states", "complex_fraction", "pairs_mean",
                   "sigma_median", "sigma_max", "omega_c", "collisions", "collisions_per_disk_strain",
                   "plastic_events", "max_drop", "sigma_xy_end", "reason", "wall_time")
"""A packing cell's summary, in table order (raw units; module docstring). None: not computed
(no branch; no growth rate for J or without complex pairs; the fractions and means of a branch
that covers no strain)."""

SECONDS_PER_STRAIN_N2 = 3.4
"""A cell's shear (full spectra, scans inline) is estimated at this times N^2 seconds per unit
strain, fitted to the shears of 2026-11-26 (d376047: 32 disks to gamma = 0.01 at mu = 10,
P = 0.1 in 21-51 s, 64 disks in 129-161 s; the rule gives 35 and 139 s). The same shears took
2 to 4 times less on 2026-12-02 (a18432b, inline: 9.0-17.4 s and 51-52 s): the estimate errs
high (docs/notes/packings-speed.md, "The time estimates against the shears they were fitted
on")."""

CELL_START_SECONDS = 4.0
"""What a cell costs besides its strain: loading the kernels in a fresh worker, the preparation,
the first spectra (16 disks to gamma = 0.002: 4-9 s)."""


@dataclass(frozen=True)
class PackingMapParams:
    """What every packing cell runs besides its scene: the shear's matrix ("J" or "M^-1 J"),
    the spectral window (lo, hi) of Re lambda [raw] or None for every eigenvalue, the
    plastic events passed before a cell's shear stops at the next, the drags [omega_0]
    of the damped-stability study (studies/damped_study.py; none: no study) and whether it runs
    the damped dynamics from every onset at each drag above 0 (models/packing/causality.py)."""

    matrix: str
    window: Optional[tuple[float, float]] = None
    plastic_events: int = 1000
    damping: tuple[float, ...] = ()
    causality: bool = False


def packing_cell_seconds(scene: PackingScene, params: PackingMapParams) -> float:
    """Rough wall time of one cell [s] (CELL_START_SECONDS + SECONDS_PER_STRAIN_N2 N^2 gamma;
    without a window), for the
    estimate `map` prints before it starts."""
    return CELL_START_SECONDS + SECONDS_PER_STRAIN_N2 * scene.N ** 2 * scene.gamma_range[1]


def branch_summary(scene: PackingScene, branch) -> dict:
    """The PACKING_COLUMNS of a sheared branch but wall_time (module docstring)."""
    from diskfriction.continuation.branch import StopCode
    from diskfriction.files import json_values
    from diskfriction.models.packing.strain_statistics import strain_statistics

    undamped = (0.0,) if str(branch.matrix) == "M^-1 J" else ()  # growth rates of M^-1 J only
    per_strain = strain_statistics(branch, undamped, counted_from=scene.gamma_range[0])
    drops = [(e.stress_before - e.stress_after) / e.stress_before for e in branch.plastic]
    gamma_end = float(branch.gamma[-1])
    reason = ""
    if not branch.status.reached:
        why = ("a plastic event (a fold in gamma) beyond the plastic events passed"
               if branch.status.code is StopCode.FOLD else branch.status.sentence(len(branch)))
        reason = f"shear ended at gamma = {gamma_end:.9g}: {why}"
    return json_values({
        "status": "ok" if branch.status.reached else "ended", "gamma_end": gamma_end,
        "states": len(branch), "complex_fraction": per_strain.complex_fraction,
        "pairs_mean": per_strain.pairs_mean,
        "sigma_median": per_strain.growth_median[0] if undamped else None,
        "sigma_max": per_strain.growth_max[0] if undamped else None,
        "omega_c": scene.omega_0, "collisions": len(branch.collisions),
        "collisions_per_disk_strain": per_strain.collisions_per_disk_strain,
        "plastic_events": len(branch.plastic), "max_drop": float(max(drops, default=0.0)),
        "sigma_xy_end": float(branch.stress[-1, 2]), "reason": reason})


def packing_cell(scene: PackingScene, params: PackingMapParams) -> dict:
    """The record of one packing cell (raw units): its scene (physics fields), summary
    (PACKING_COLUMNS), the located collisions (as bifurcate's collisions.json), the plastic
    events [gamma, sigma_xy before, after] and, with params.damping, the study's "damped" (one
    summary per drag, studies/damped_study.DAMPED_COLUMNS), "events" (the precursor rows,
    models/packing/precursors.EVENT_COLUMNS) and, with params.causality, "runs" (one row per
    damped run from an onset, studies/damped_study.RUN_COLUMNS)."""
    from dataclasses import replace

    from diskfriction.continuation.linalg.solves import SingularMatrix
    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.continuation.stepping.segment import SegmentSolveError
    from diskfriction.continuation.spectra.window import WindowCrowded
    from diskfriction.errors import OneLineError
    from diskfriction.models.packing.equilibria import MissedContact
    from diskfriction.models.packing.plastic import RelaxationFailed
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.continuation.records import collision_records
    from diskfriction.models.packing.shear import ShearParams, shear

    start = time.perf_counter()
    summary = dict.fromkeys(PACKING_COLUMNS)
    record = {"scene": scene.physics_fields(), "summary": summary, "collisions": [],
              "plastic": []}
    scene = replace(scene, matrix=params.matrix, spectra="full")  # every state's pairs, every collision
    try:
        packing = prepare_scene(scene)
        branch = shear(scene, packing, ShearParams(workers=0),
                       plastic_events=params.plastic_events, window=params.window)
    except (ContinuationError, MissedContact, RelaxationFailed, WindowCrowded, OneLineError,
            np.linalg.LinAlgError) as error:
        summary |= {"status": "failed", "reason": f"the shear stopped: {error}"}
    else:
        summary |= branch_summary(scene, branch)
        record |= {"collisions": collision_records(branch),
                   "plastic": [[e.gamma, e.stress_before, e.stress_after] for e in branch.plastic]}
        if params.damping:
            try:
                record |= damped_parts(scene, packing, branch, params.damping, params.causality)
            except (SegmentSolveError, SingularMatrix, np.linalg.LinAlgError) as error:
                summary |= {"status": "failed", "reason": f"the damped study stopped: {error}"}
    summary["wall_time"] = round(time.perf_counter() - start, 3)
    return record


def damped_parts(scene: PackingScene, packing, branch, drags: tuple[float, ...],
                 runs: bool = False) -> dict:
    """A cell's "damped" and "events" (packing_cell) at the drags [omega_0]: the damped Hopf
    points of its branch at each, the precursor rows and the strain statistics
    (models/packing/precursors.drag_study, from the scene's strain range); with
    `runs`, "runs": the damped dynamics from every onset of each drag above 0
    (models/packing/causality.py; at drag 0 nothing damps a run to rest)."""
    from diskfriction.files import json_values
    from diskfriction.models.packing.causality import causality
    from diskfriction.models.packing.equilibria import mass_diagonal
    from diskfriction.models.packing.precursors import drag_study
    from diskfriction.models.packing.shear import network_of
    from diskfriction.studies.damped_study import damped_summary, run_rows

    network = network_of(scene, packing)
    mass = mass_diagonal(network, scene.m, scene.inertia)
    etas = tuple(drag * scene.omega_0 for drag in drags)
    hopfs, events, statistics = drag_study(network, mass, branch, scene.omega_0, drags, scene.gamma_range[0])
    summaries = [damped_summary(statistics, drag, eta, i, hopfs[drag],
                                [r for r in events if r["drag"] == drag], scene.N)
                 for i, (drag, eta) in enumerate(zip(drags, etas))]
    parts = {"damped": summaries, "events": events}
    if runs:
        parts["runs"] = [row for drag, eta in zip(drags, etas) if drag > 0
                         for row in run_rows(drag, causality(branch, network, mass, eta, scene.delta_0))]
    return json_values(parts)
