"""Quasistatic shear of a prepared packing: the branch of equilibria in the strain gamma, with
the history carried, the spectrum tracked and every birth and death of a complex pair located
(docs/packings.md#shear). A thin layer over the core's solve_branch, as models/chain/sweep.py is.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Optional, Sequence

import numpy as np

from diskfriction.continuation.api import Options, solve_in_runs
from diskfriction.continuation.branch import Stop, StopCode
from diskfriction.continuation.detection.collisions import Collision
from diskfriction.continuation.spectra.tracking import count_complex_pairs
from diskfriction.continuation.spectra.window import Window, block_columns
from diskfriction.matrices import Matrix
from diskfriction.models.packing.equilibria import (NotJammed, PackingEquilibria, largest_force,
                                              mass_diagonal, start)
from diskfriction.models.packing.network import Network
from diskfriction.models.packing.plastic import PlasticEvent, drag_rate, past_fold
from diskfriction.models.packing.prepare import Packing
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.segments import Point, ShearSegment
from diskfriction.scenes.packing import PackingScene

PLASTIC = (StopCode.FOLD, StopCode.COMMIT, StopCode.DS_MIN, StopCode.TURNED_BACK)
"""How a segment ends at a plastic event, the branch lost: a fold in gamma (a saddle-node); a
commit after which no equilibrium is near (a contact sliding or a disk turning loose took the
state's stability with it); a step that had to shrink below ds_min (a singular point the
corrector cannot pass); or, at the start of a segment, a branch that turns back at once (the
relaxed state sits at a fold)."""

STEP_IN_STRAIN = 2e-4
"""The largest step moves the disks by about this strain: ds_max = STEP_IN_STRAIN times the
arclength of an affine shear of unit strain, |(y_i, 0, 0)| over the disks [length]."""


@dataclass(frozen=True)
class ShearParams(Options):
    """solve_branch's Options with the packing's defaults: ds_max from STEP_IN_STRAIN (None),
    newton_tol 1e-11 [force] (of a contact's force P 2R = 0.1 at the default pressure),
    max_steps 20 000, no special points (the problem carries history), steps in the Euclidean
    arclength of (q, gamma) (theta None, p_scale 1: ds_max is set from the affine shear),
    newton_tol in force units (residual_scale 1), and the run ends at a
    fold in gamma (stop_at_fold): the saddle-node where quasistatic shear loses the branch is a
    plastic event; beyond it the branch of unstable states it would follow back is no state
    the packing passes through."""

    newton_tol: float = 1e-11
    max_steps: int = 20_000
    special_points: tuple[str, ...] = ()
    stop_at_fold: bool = True
    theta: Optional[float] = None
    p_scale: Optional[float] = 1.0
    residual_scale: Optional[float] = 1.0


@dataclass(frozen=True)
class PackingBranch:
    """Accepted equilibria of a shear run, one row per point (raw units).

    gamma (m,); q (m, 3N); rows, xi: each point's contact rows (i, j, cx, cy) and their
    committed histories (the state a run starts from); eigenvalues (m, 3N) of `matrix` in
    coordinates relative to the reference disk (models/packing/equilibria.py; the translations' and
    loose disks' zeros included), or with a window one column per eigenvalue that passed
    through the window or its guard bands (spectral_window.window_columns; nan elsewhere);
    n_complex (m,) (in the window, if one); residual (m,) max|F| over the network's disks
    [force]; contacts (m,) active contacts; loose (m,) loose disks; stress (m, 4) sigma_xx, sigma_yy, sigma_xy,
    sigma_yx [force / length]; collisions in branch order (each segment's eigenvalue labels are
    its own); status of the last segment; events: steps cut at a contact event; segment (m,)
    the segment of each point: the branch between two plastic events; plastic: the plastic
    events (folds in gamma) passed, one between each two segments; window: (lo, hi) of Re
    lambda tracked (collisions then only those with lo <= lambda <= hi), or None; widenings:
    how often the window crowded and was sized anew, wider, at the last certified state;
    condition, as eigenvalues: each eigenvalue's condition number |l| |r| / |l^H r|
    (spectra.condition_numbers; nan for the zeros of the translations and loose disks, which
    carry no vectors)."""

    gamma: np.ndarray
    q: np.ndarray
    rows: tuple[np.ndarray, ...]
    xi: tuple[np.ndarray, ...]
    eigenvalues: np.ndarray
    n_complex: np.ndarray
    residual: np.ndarray
    contacts: np.ndarray
    loose: np.ndarray
    stress: np.ndarray
    collisions: tuple[Collision, ...]
    matrix: Matrix
    status: Stop
    events: int
    segment: np.ndarray
    plastic: tuple[PlasticEvent, ...] = ()
    window: Optional[tuple[float, float]] = None
    widenings: int = 0
    condition: Optional[np.ndarray] = None

    def __len__(self) -> int:
        return self.gamma.size


def collision_records(branch: PackingBranch) -> list[dict]:
    """One record per collision: strain, kind, the double eigenvalue, the matrix, the bracket
    of strain it lies in and whether it is located to the detection's tolerance (resolved;
    docs/outputs.md)."""
    return [{"gamma": c.p, "kind": str(c.kind), "lambda_re": c.eigenvalue,
             "lambda_im": 0.0, "matrix": str(branch.matrix),
             "bracket": [float(b) for b in c.bracket], "resolved": bool(c.resolved)}
            for c in branch.collisions]


def network_of(scene: PackingScene, packing: Packing) -> Network:
    """The packing's disks bound to the scene's kernels."""
    return Network.build(packing.radii, packing.L, scene.k_n, scene.k_t, scene.mu,
                         scene.resolved_effects)


def shear(scene: PackingScene, packing: Packing, params: ShearParams = ShearParams(),
          progress: Optional[Callable[[float], None]] = None, plastic_events: int = 0,
          window: Optional[tuple[float, float]] = None, done: Sequence[ShearSegment] = (),
          on_segment: Optional[Callable[[ShearSegment], None]] = None) -> PackingBranch:
    """Follow the equilibria of `packing` with friction switched on from gamma = 0 to the end
    of the scene's gamma range (collisions below its start are left out). At a fold (a plastic
    event) the run ends, unless plastic_events > 0: then up to that many events are passed
    (models/packing/plastic.py: strained past the fold, relaxed with friction) and the shear goes on
    from each relaxed state as a new segment. window: (lo, hi) of Re lambda tracked by sparse
    shift-invert (continuation/spectra/window.py; its k sized at the start of every segment,
    and where it crowds sized anew, wider, at the last certified state:
    spectral_window.widened), or None: every eigenvalue, a dense spectrum per sample.
    done: the finished segments of an interrupted run with the same inputs (models/packing/segments.py):
    the run goes on where the next one starts, with the same result as a run never
    interrupted; on_segment(segment) is told each segment finished here once it is passed.
    Without tangential forces (mu = 0, or the tangential law "none") the spectrum is real and
    no collision is looked for (with a window the scans stay on: they certify its columns);
    NotJammed where the packing unjams (under shear, or in a relaxation)."""
    network = network_of(scene, packing)
    mass = mass_diagonal(network, scene.m, scene.inertia)
    affine = float(np.linalg.norm(packing.positions[:, 1]))
    ds_max = params.ds_max or STEP_IN_STRAIN * affine
    options = replace(params, ds_max=ds_max, ds=params.ds or ds_max / 4,
                      ds_min=params.ds_min or 1e-8 * ds_max)
    if not network.frictional and window is None:
        # a real spectrum (J symmetric): no collision to look for (a window's label continuity
        # is certified by the detection's scans, so they stay on there)
        options = replace(options, detection=replace(options.detection, enabled=False))
    segments = list(done)
    begin = segments[-1].next_start if segments else (*start(network, packing.positions), 0.0)
    while True:
        try:
            segment = shear_segment(network, mass, scene, options, window, begin, len(segments),
                                    sum(len(s.continued) for s in segments), progress)
        except NotJammed as error:  # at the start of a segment after a plastic event
            if not segments or error.where != "the packing":
                raise
            raise NotJammed(error.reason, f"after the plastic event at gamma = "
                                          f"{segments[-1].plastic.gamma:.9g} the packing relaxed "
                                          f"into a state that") from None
        segments.append(segment)
        if segment.status.code not in PLASTIC or len(segments) > plastic_events:
            break
        last = segment.points[-1]
        q, xi, rows, gamma_start, steps = past_fold(network, last.q, last.xi, last.rows, last.gamma,
                                                    params.newton_tol, mass, drag_rate(scene))
        after = network.stress(q, xi, rows, gamma_start)[2]
        event = PlasticEvent(last.gamma, float(last.stress[2]), float(after),
                             float(np.linalg.norm(q - last.q)), steps, str(segment.status.code))
        segments[-1] = segment = replace(segment, plastic=event, next_start=(q, xi, rows, gamma_start))
        if on_segment is not None:
            on_segment(segment)
        begin = segment.next_start
    return joined(segments, scene, window, params.detection.rel_tol)


def shear_segment(network: Network, mass: np.ndarray, scene: PackingScene, options: ShearParams,
                  window: Optional[tuple[float, float]], begin: tuple, index: int, base: int,
                  progress: Optional[Callable[[float], None]]) -> ShearSegment:
    """Segment `index` of a shear run from the relaxed state begin = (q, xi, rows, gamma) to the
    end of the scene's strain range or the first plastic event; its window blocks are numbered
    from `base` (a window is sized again for every segment: its columns start anew there)."""
    q, xi, rows, gamma_start = begin
    problem = PackingEquilibria(network, q, xi, rows, gamma_start, mass, scene.matrix,
                                options.newton_tol, None if window is None else Window(*window))
    records, continued, condition, events, collisions = [], {}, [], 0, []

    def record_of(run):
        def record(k, gamma, q_k, eigvals):
            xi_all = problem.trial(q_k, gamma)[0]
            xi_k, rows_k = xi_all[problem.active], problem.rows_c[problem.active]
            delta = network.overlaps(q_k, rows_k, gamma)
            records.append((gamma, q_k.copy(), problem.rows_c.copy(), xi_all, eigvals,
                            largest_force(problem, q_k, gamma), int((delta > 0).sum()),
                            int(problem.gauge.loose.sum()), network.stress(q_k, xi_k, rows_k, gamma),
                            index, base + run))
            if progress is not None:
                progress(gamma)
        return record

    runs, widened = solve_in_runs(problem, q, (gamma_start, scene.gamma_range[1]), options, record_of)
    for run, branch in enumerate(runs):  # a run after the first follows a widened window
        collisions += branch.collisions
        events += branch.events
        continued[base + run] = branch.continued if run == 0 else branch.continued[1:]
        condition += list(branch.condition if run == 0 else branch.condition[1:])
    points = tuple(Point(*record, condition=kappa) for record, kappa in zip(records, condition))
    return ShearSegment(points, tuple(collisions), events, continued, widened, runs[-1].status)


def joined(segments: Sequence[ShearSegment], scene: PackingScene, window: Optional[tuple[float, float]],
           rel_tol: float) -> PackingBranch:
    """The branch of a shear run from its segments in order (the last one's status is the
    run's); collisions below the scene's strain range, or with a window outside it, left out."""
    points = [p for s in segments for p in s.points]
    gamma, q, residual, contacts, loose, stress, segment = (
        np.array([getattr(p, name) for p in points])
        for name in ("gamma", "q", "residual", "contacts", "loose", "stress", "segment"))
    eig, kappas = [p.eigenvalues for p in points], [p.condition for p in points]
    continued = {b: rows for s in segments for b, rows in s.continued.items()}
    kept = [c for s in segments for c in s.collisions if c.p >= scene.gamma_range[0]]
    if window is None:
        eig, condition = np.array(eig), np.array(kappas)
        n_complex = np.array([count_complex_pairs(e[e != 0], rel_tol) for e in eig])
    else:  # the pairs in the window; collisions with their double eigenvalue there
        band = Window(*window)
        n_complex = np.array([count_complex_pairs(e[band.inside(e)], rel_tol) for e in eig])
        kept = [c for c in kept if band.lo <= c.eigenvalue <= band.hi]
        eig, condition = block_columns(eig, np.array([p.block for p in points]), continued, band, kappas)
    return PackingBranch(gamma, q, tuple(p.rows for p in points), tuple(p.xi for p in points), eig,
                         n_complex, residual, contacts, loose, stress, tuple(kept),
                         Matrix(scene.matrix), segments[-1].status, sum(s.events for s in segments),
                         segment, tuple(s.plastic for s in segments if s.plastic is not None),
                         window, sum(s.widenings for s in segments), condition)


def shear_scene(scene: PackingScene, plastic_events: int,
                stage: Optional[Callable[[str], None]] = None,
                relax_progress=None, on_gamma: Optional[Callable[[float], None]] = None
                ) -> tuple[PackingBranch, Network, np.ndarray]:
    """(branch, network, mass diagonal): the scene's packing prepared (prepared.prepare_scene)
    and sheared over its strain range with every eigenvalue tracked, passing up to
    `plastic_events` plastic events; `stage` is told each stage, `relax_progress` is the
    preparation's progress, `on_gamma` each accepted strain."""
    say = stage or (lambda line: None)
    say(f"prepare {scene.N} disks to pressure {scene.pressure:g}")
    packing = prepare_scene(scene, relax_progress)
    say(f"shear gamma 0 -> {scene.gamma_range[1]:g}")
    branch = shear(scene, packing, ShearParams(workers=0), on_gamma, plastic_events=plastic_events)
    network = network_of(scene, packing)
    return branch, network, mass_diagonal(network, scene.m, scene.inertia)
