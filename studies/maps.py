"""Parameter maps: a full `bifurcate` in every cell of a grid of scene keys and, with slide
runs, where the chain slides below its Coulomb limit N mu F_y; cells run as dask tasks.

A map varies one or two numeric scene keys (scenes.load.number_keys: contacts.mu, disks.N,
...), each over COUNT values from LO to HI, evenly or evenly in log (grid_values). Every
combination is a cell: the base scene with those values, checked as a scene file would be
(scenes.load.with_values), before anything runs (map_cells). Each cell (map_cell, in a dask
worker, raw units):
  * sweeps F_x from F_from to F_to with every collision of `matrix` located, exactly as
    `bifurcate` does (models.chain.sweep, default SweepParams): the collisions, the windows
    between them (studies.verify.windows), the F_x where the first complex window starts,
    and sigma_max = max |Im sqrt(lambda)| over the complex pairs of M^-1 J at the branch's
    points (the growth rate of the fastest oscillatory instability, [1 / time]);
  * with SlideParams, runs the dynamics once per window, as `verify` does
    (studies.verify.window_run: at the window's midpoint, along its largest complex pair of
    M^-1 J, to t_end). F_slide is the lowest load whose run slid; F_slide_lo the highest load
    below it whose run did not: the lowest sliding load lies in (F_slide_lo, F_slide]. Its
    effective friction coefficient mu_eff = F_slide / (N F_y) is to be compared with the
    Coulomb limit: no static equilibrium can hold F_x > N mu F_y, so mu_eff <= mu. A run
    grows as e^(sigma t) from its amplitude a, and can slide within t_end only once that
    reaches the displacements at which the substrate contacts breach (1e-4 .. 1e-3 raw on the
    paper's scene): a window with sigma t_end below about ln(1e-4 / a) (14 for verify's
    a = 1e-10) cannot be seen to slide, so F_slide is an upper bound that can fall as t_end
    grows (docs/maps.md measures by how much).
  * status: "ok" (the branch reached F_to), "ended" (it stopped before F_to; `reason` says
    where and why, as models.chain.equilibrium does), or "failed" (no branch at all, e.g. no
    sticking equilibrium at small mu; `reason` is the continuation's own line).
Results do not depend on which worker ran a cell or when: a cell is a pure function of its
scene and the map's parameters, and a map's table is assembled in grid order.

Layout of a map directory: cells/<key>.json, one record per finished cell (map_cell), written
atomically the moment it arrives. The key hashes the cell's scene, the map's parameters and
the code version (studies/cluster.py), not the grid: a rerun skips the cells on disk,
another grid reuses the cells it shares, and an interrupt loses nothing finished. The table
and figures beside them (map.csv, map.json, map.png) are written by reports/maps.py.
"""
from __future__ import annotations

import itertools
import json
import math
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, Optional

import numpy as np

from diskfriction.studies.cluster import as_finished, code_version, dask_client, task_key
from diskfriction.files import save_json
from diskfriction.scenes import Scene
from diskfriction.scenes.packing import PackingScene
from diskfriction.scenes.load import number_keys, with_values

COLUMNS = ("status", "F_end", "collisions", "windows", "complex_windows", "F_complex",
           "sigma_max", "runs", "sliding_windows", "F_slide", "F_slide_lo", "mu_eff", "reason",
           "wall_time")
"""A cell's summary, in table order (raw units; wall_time in seconds). None: not computed
(no slide runs asked for, no branch, nothing slid)."""


@dataclass(frozen=True)
class Axis:
    """One varied scene key (dotted) and its values, in grid order; log: spaced in log."""

    key: str
    values: tuple
    log: bool = False


@dataclass(frozen=True)
class Cell:
    """One grid point: its index along each axis, the values set ((key, value) pairs) and
    the scene they make."""

    index: tuple[int, ...]
    values: tuple[tuple[str, object], ...]
    scene: Scene


@dataclass(frozen=True)
class SlideParams:
    """One run per window to t_end [time], perturbed with amplitude [length] (verify's)."""

    t_end: float = 1000.0
    amplitude: float = 1e-10


@dataclass(frozen=True)
class MapParams:
    """What every cell runs besides its scene: a sweep F_from -> F_to [force] (F_from < F_to)
    locating the collisions of `matrix` ("J" or "M^-1 J"), and with `slide` the window runs."""

    F_from: float
    F_to: float
    matrix: str
    slide: Optional[SlideParams] = None


EQUILIBRIUM_SECONDS_N10 = 0.035
"""A window run's start: the sweep from rest to its midpoint without spectra, N = 10 [s],
growing as N^0.9 (0.28 s at N = 100)."""
WINDOWS_PER_DISK = 2.3
"""Windows between collisions per disk at eps > 0 (51, 91, 239 at N = 20, 40, 100); at eps = 0
the same 24 collisions at every N, so 25 windows."""


def cell_seconds(scene: Scene, params: MapParams) -> float:
    """Rough wall time of one cell in its worker [s]: the sweep (models.chain.cost) and, with
    slide runs, per window the sweep to its midpoint and the run's steps (dynamics.simulate:
    SECONDS_PER_DISK_STEP, dt = DT_FRACTION 2 / omega_max). Within a factor of 2 of the cells
    of N = 10 .. 40 timed on 2026-11-24 (docs/notes/maps-cost.md, "The estimate printed
    first"); for the estimate `map` prints before it starts."""
    from diskfriction.models.chain.cost import sweep_seconds
    from diskfriction.dynamics.simulate import run_seconds

    dense = scene.eps > 0
    seconds = sweep_seconds(scene.N, dense)
    if params.slide is None:
        return seconds
    windows = WINDOWS_PER_DISK * scene.N + 1 if dense else 25
    run = run_seconds(scene, params.slide.t_end)
    return seconds + windows * (EQUILIBRIUM_SECONDS_N10 * (scene.N / 10) ** 0.9 + run)


def grid_values(lo: float, hi: float, count: int, log: bool = False) -> tuple[float, ...]:
    """count values from lo to hi, both included: lo + k (hi - lo) / (count - 1), or with log
    lo (hi / lo)^(k / (count - 1)). count = 1 takes lo = hi. ValueError, saying what is wrong,
    unless lo and hi are finite, count >= 1, lo < hi (lo = hi for one value), lo > 0 for log."""
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError("LO and HI must be finite numbers")
    if count != int(count) or count < 1:
        raise ValueError(f"COUNT must be an integer >= 1, not {count}")
    if log and lo <= 0:
        raise ValueError(f"log spacing needs LO > 0, not {lo:g}")
    if count == 1 and lo != hi:
        raise ValueError("one value (COUNT = 1) needs LO = HI")
    if count > 1 and not lo < hi:
        raise ValueError(f"LO must be below HI, not {lo:g} >= {hi:g}")
    values = np.geomspace(lo, hi, int(count)) if log else np.linspace(lo, hi, int(count))
    return tuple(float(v) for v in values)


def map_cells(scene: Scene | PackingScene, axes: list[Axis], origin: str) -> list[Cell]:
    """Every combination of the axes' values (the first axis slowest), each the scene with
    those values checked as if file `origin` held them (SceneError for the first bad one;
    a whole number for an integer key such as disks.N becomes an int, any other value is
    refused by the schema). ValueError for a key that holds no single number."""
    kinds = number_keys(scene.geometry)
    for axis in axes:
        if axis.key not in kinds:
            raise ValueError(f"{axis.key} is not a numeric scene key ({', '.join(kinds)})")

    def typed(key: str, value: float):
        return int(value) if kinds[key] is int and float(value).is_integer() else value

    cells = []
    for index in itertools.product(*(range(len(axis.values)) for axis in axes)):
        values = tuple((axis.key, typed(axis.key, axis.values[i])) for axis, i in zip(axes, index))
        cells.append(Cell(index, values, with_values(scene, dict(values), origin)))
    return cells


# ---- one cell (a dask task) -------------------------------------------------------------------

def growth_rate_max(system, branch, rows: np.ndarray) -> float:
    """max sigma = |Im sqrt(lambda)| over the complex pairs of M^-1 J at the branch's `rows`
    [1 / time] (dynamics.start.growth_rates), 0 if M^-1 J is all real there."""
    from diskfriction.dynamics.start import growth_rates

    def eigenvalues(k: int) -> np.ndarray:
        if branch.matrix == "M^-1 J":
            return branch.eigenvalues[k]
        J = system.jacobian(branch.q[k], branch.xi[k])
        return np.linalg.eigvals(system.stability_matrix(J, "M^-1 J"))

    return float(max((growth_rates(eigenvalues(k))[1].max(initial=0.0) for k in rows),
                     default=0.0))


def slide_runs(system, todo, slide: SlideParams) -> list[dict]:
    """One run per window (studies.verify.window_run); a window whose midpoint the branch
    from rest does not reach gets slid = None and the reason."""
    from diskfriction.models.chain.equilibrium import NoEquilibrium
    from diskfriction.studies.verify import window_run

    runs = []
    for k, window in enumerate(todo):
        try:
            runs.append(window_run(system, window, k, slide.t_end, slide.amplitude))
        except NoEquilibrium as error:
            runs.append({"window": [window.start, window.stop], "complex_pairs": window.pairs,
                         "F_x": 0.5 * (window.start + window.stop), "slid": None,
                         "reason": str(error)})
    return runs


def sliding_load(runs: list[dict]) -> tuple[Optional[float], Optional[float]]:
    """(F_slide, F_slide_lo): the lowest load whose run slid, and the highest load below it
    whose run did not (None where there is none)."""
    slid = [r["F_x"] for r in runs if r["slid"] is True]
    if not slid:
        return None, None
    F_slide = min(slid)
    stuck = [r["F_x"] for r in runs if r["slid"] is False and r["F_x"] < F_slide]
    return F_slide, max(stuck, default=None)


def branch_summary(system, branch) -> dict:
    """status, F_end, reason, collisions, windows, complex_windows, F_complex and sigma_max of
    a swept branch (module docstring)."""
    from diskfriction.models.chain.equilibrium import contact_states
    from diskfriction.models.chain.windows import complex_spans
    from diskfriction.studies.verify import windows

    todo = windows(branch)
    spans = complex_spans(todo)
    rows = np.flatnonzero(branch.leg == 1)
    F_end = float(branch.F_x[-1])
    stopped = [leg.status for leg in branch.of_kind("leg") if not leg.status.reached]
    reason = "" if not stopped else (f"branch ended at F_x = {F_end:.6g}: "
                                     f"{stopped[0].sentence(len(branch))}; there "
                                     f"{contact_states(system, branch.q[-1], branch.xi[-1])}")
    return {"status": "ended" if stopped else "ok", "F_end": F_end, "reason": reason,
            "collisions": len(branch.collisions), "windows": len(todo),
            "complex_windows": len(spans), "F_complex": spans[0][0] if spans else None,
            "sigma_max": growth_rate_max(system, branch, rows)}


def map_cell(scene: Scene, params: MapParams) -> dict:
    """The record of one cell (raw units): its scene (physics fields), summary (COLUMNS), the
    located collisions (as bifurcate's collisions.json), windows [start, stop, pairs] and,
    with slide runs, one row per window (studies.verify.window_run)."""
    from diskfriction.continuation.stepping.arclength import ContinuationError
    from diskfriction.models.chain.equilibria import EquilibriumError
    from diskfriction.continuation.records import collision_records
    from diskfriction.models.chain.sweep import SweepParams, sweep
    from diskfriction.studies.verify import windows
    from diskfriction.symbolic import System

    start = time.perf_counter()
    summary = dict.fromkeys(COLUMNS)
    record = {"scene": scene.physics_fields(), "summary": summary, "collisions": [],
              "windows": [], "runs": []}
    system = System.from_scene(scene)
    try:
        # the cells already run one per core: each sweep scans its steps inline
        branch = sweep(system, params.F_from, params.F_to, params.matrix,
                       SweepParams(workers=0))
    except (EquilibriumError, ContinuationError, np.linalg.LinAlgError) as error:
        summary |= {"status": "failed", "reason": f"no branch: {error}"}
    else:
        summary |= branch_summary(system, branch)
        todo = windows(branch)
        record |= {"collisions": collision_records(branch),
                   "windows": [[w.start, w.stop, w.pairs] for w in todo]}
        if params.slide is not None:
            runs = slide_runs(system, todo, params.slide)
            F_slide, F_slide_lo = sliding_load(runs)
            unreached = [f"no result at F_x = {r['F_x']:.6g}: {r['reason']}" for r in runs
                         if r["slid"] is None]
            summary |= {"runs": len(runs), "sliding_windows": sum(r["slid"] is True for r in runs),
                        "F_slide": F_slide, "F_slide_lo": F_slide_lo,
                        "mu_eff": None if F_slide is None else F_slide / (scene.N * scene.F_y),
                        "reason": "; ".join(filter(None, [summary["reason"], *unreached]))}
            record["runs"] = runs
    summary["wall_time"] = round(time.perf_counter() - start, 3)
    return record


# ---- the grid on dask -------------------------------------------------------------------------

def cell_path(out: Path, scene: Scene | PackingScene, params, version: str) -> Path:
    """OUT/cells/<key>.json, the key hashing the scene's physics, the parameters and the code."""
    return Path(out) / "cells" / f"{task_key(scene.physics_fields(), asdict(params), version)}.json"


def run_map(cells: list[Cell], params, out: Path, scheduler: Optional[str] = None,
            workers: Optional[int] = None,
            progress: Optional[Callable[[int, int], None]] = None,
            compute: Callable[..., dict] = map_cell) -> list[dict]:
    """The record of every cell, in the order of `cells`: read from OUT/cells where it is,
    else computed (compute(scene, params): map_cell for chains, with MapParams;
    studies.packing_maps.packing_cell for packings) on dask (the scheduler at `scheduler`, or a local cluster of `workers`
    processes, studies/cluster.py) and written the moment it arrives. progress(done, total)
    before the first cell and after every finished one."""
    version = code_version()
    paths = {cell.index: cell_path(out, cell.scene, params, version) for cell in cells}
    records = {i: json.loads(path.read_text()) for i, path in paths.items() if path.exists()}
    tick = (lambda: progress(len(records), len(cells))) if progress else (lambda: None)
    tick()
    tasks = {cell.index: (cell.scene, params) for cell in cells if cell.index not in records}
    if tasks:
        with dask_client(scheduler, workers) as client:
            for index, record in as_finished(client, compute, tasks):
                save_json(paths[index], record)
                records[index] = record
                tick()
    return [records[cell.index] for cell in cells]
