"""Quasistatic shear of a prepared packing: the branch of equilibria in the strain gamma, with
the history carried, the spectrum tracked and every birth and death of a complex pair located
(docs/packings.md#shear). A thin layer over the core's solve_branch, as models/chain/sweep.py is.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Optional, Sequence

import numpy as np

from diskfriction.continuation.api import Options, solve_in_runs
from diskfriction.continuation.branch import Branch, EventPoint, JoinedRuns, Piece, StopCode, column_of
from diskfriction.continuation.spectra.tracking import count_complex_pairs
from diskfriction.continuation.linalg.solves import LinearSolver
from diskfriction.continuation.spectra.window import SpectralWindow, block_columns
from diskfriction.matrices import EIGENVALUE_UNITS, Matrix
from diskfriction.models.packing.equilibria import (LINEAR_SOLVER, WINDOW_EXTRA, WINDOW_MARGIN, NotJammed,
                                                    PackingEquilibria, largest_force, mass_diagonal, start)
from diskfriction.models.packing.network import Network
from diskfriction.models.packing.plastic import PlasticEvent, drag_rate, past_fold
from diskfriction.models.packing.prepare import Packing
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.sampled import sampled_spectra, with_samples
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
    the packing passes through. linear_solver: SuperLU ordered by minimum degree on A + A^T
    (equilibria.LINEAR_SOLVER: the network's Jacobian is structurally symmetric)."""

    newton_tol: float = 1e-11
    max_steps: int = 20_000
    special_points: tuple[str, ...] = ()
    stop_at_fold: bool = True
    theta: Optional[float] = None
    p_scale: Optional[float] = 1.0
    residual_scale: Optional[float] = 1.0
    linear_solver: LinearSolver = LINEAR_SOLVER


RAGGED = ("rows", "xi")
"""The columns of a shear's branch whose shape varies from point to point: each point's committed
contact rows (i, j, cx, cy) and their histories."""


def network_of(scene: PackingScene, packing: Packing) -> Network:
    """The packing's disks bound to the scene's kernels."""
    return Network.build(packing.radii, packing.L, scene.k_n, scene.k_t, scene.mu,
                         scene.resolved_effects)


def shear(scene: PackingScene, packing: Packing, params: ShearParams = ShearParams(),
          progress: Optional[Callable[[float], None]] = None, plastic_events: int = 0,
          window: Optional[tuple[float, float]] = None, done: Sequence[Branch] = (),
          on_segment: Optional[Callable[[Branch], None]] = None) -> Branch:
    """Follow the equilibria of `packing` with friction switched on from gamma = 0 to the end
    of the scene's gamma range (collisions below its start are left out). At a fold (a plastic
    event) the run ends, unless plastic_events > 0: then up to that many events are passed
    (models/packing/plastic.py: strained past the fold, relaxed with friction) and the shear goes on
    from each relaxed state as a new segment. What it computes of the spectrum is the scene's
    resolved_spectra: "full" tracks it at every accepted state and locates every collision;
    "none" computes no eigenvalue (the same equilibria, contact and plastic events, bit for
    bit); "sample:DGAMMA" adds the spectrum at the grid strains k DGAMMA
    (models/packing/sampled.py; labelled "sample"). window: (lo, hi) of Re lambda tracked by
    sparse shift-invert (continuation/spectra/window.py; its k sized at the start of every
    segment, and where it crowds sized anew, wider, at the last certified state:
    spectra.window.widened), or None: every eigenvalue, a dense spectrum per sample; with
    "sample" the samples' band (ValueError with "none").
    done: the finished segments of an interrupted run with the same inputs (models/packing/segments.py):
    the run goes on where the next one starts, with the same result as a run never
    interrupted; on_segment(segment) is told each segment finished here once it is passed.
    Without tangential forces (mu = 0, or the tangential law "none") the spectrum is real and
    no collision is looked for (with a window the scans stay on: they certify its columns);
    NotJammed where the packing unjams (under shear, or in a relaxation).

    The branch (continuation/branch.Branch, raw units): p = gamma (parameter "gamma", no
    units), u = q (m, 3N) (state "q"); eigenvalues of `matrix` in coordinates relative to the
    reference disk (models/packing/equilibria.py; the translations' and loose disks' zeros
    included: their condition numbers nan, they carry no vectors), or with a window one column
    per eigenvalue that passed through the window or its guard bands (nan elsewhere; n_complex
    and the collisions then those in the window); residual max|F| over the network's disks
    [force]; columns rows and xi (each point's committed contact rows (i, j, cx, cy) and
    their histories, tuples: the state a run starts from), contacts (active contacts), loose
    (loose disks), stress (m, 4) sigma_xx, sigma_yy, sigma_xy, sigma_yx [force / length];
    pieces: the segments (the branch between two plastic events: each segment's eigenvalue
    labels are its own) and the window's runs; labelled "plastic": the plastic events passed
    (folds in gamma), one between each two segments; events: steps cut at a contact event;
    status: the last segment's. Without spectra at the states (none, sample) eigenvalues and
    condition are (m, 0), n_complex -1 (not counted) and there are no collisions; with
    sample, labelled "sample" holds the samples and window is theirs."""
    network = network_of(scene, packing)
    mass = mass_diagonal(network, scene.m, scene.inertia)
    affine = float(np.linalg.norm(packing.positions[:, 1]))
    ds_max = params.ds_max or STEP_IN_STRAIN * affine
    options = replace(params, ds_max=ds_max, ds=params.ds or ds_max / 4,
                      ds_min=params.ds_min or 1e-8 * ds_max)
    every = scene.sample_spacing
    tracked = scene.resolved_spectra == "full"
    if window is not None and scene.resolved_spectra == "none":
        raise ValueError("a spectral window needs spectra \"full\" or \"sample:DGAMMA\", not \"none\"")
    if not tracked:  # no spectrum at the accepted states: the equilibria and their events only
        options = replace(options, detection=replace(options.detection, enabled=False, spectra=False))
    elif not network.frictional and window is None:
        # a real spectrum (J symmetric): no collision to look for (a window's label continuity
        # is certified by the detection's scans, so they stay on there)
        options = replace(options, detection=replace(options.detection, enabled=False))
    segments = list(done)
    begin = segments[-1].plastic[0].after if segments else (*start(network, packing.positions), 0.0)
    while True:
        try:
            segment = shear_segment(network, mass, scene, options, window if tracked else None, begin,
                                    len(segments), sum(len(s.of_kind("run")) for s in segments), progress)
        except NotJammed as error:  # at the start of a segment after a plastic event
            if not segments or error.where != "the packing":
                raise
            raise NotJammed(error.reason, f"after the plastic event at gamma = "
                                          f"{segments[-1].plastic[0].gamma:.9g} the packing relaxed "
                                          f"into a state that") from None
        if every is not None:
            sampled = [x.gamma for s in segments for x in s.sample]
            segment = with_samples(segment, sampled_spectra(
                network, mass, segment, every, window, scene.matrix, options.newton_tol,
                options.detection.rel_tol, sampled[-1] if sampled else -np.inf))
        segments.append(segment)
        if segment.status.code not in PLASTIC or len(segments) > plastic_events:
            break
        q_last, xi_last, rows_last = segment.q[-1], segment.xi[-1], segment.rows[-1]
        gamma_last = float(segment.gamma[-1])
        q, xi, rows, gamma_start, steps = past_fold(network, q_last, xi_last, rows_last, gamma_last,
                                                    params.newton_tol, mass, drag_rate(scene))
        after = network.stress(q, xi, rows, gamma_start)[2]
        event = PlasticEvent(gamma_last, float(segment.stress[-1][2]), float(after),
                             float(np.linalg.norm(q - q_last)), steps, str(segment.status.code),
                             after=(q, xi, rows, gamma_start))
        segments[-1] = segment = replace(segment, labelled={**segment.labelled, "plastic": (event,)})
        if on_segment is not None:
            on_segment(segment)
        begin = event.after
    branch = joined(segments, scene)
    return branch if every is None else replace(branch, window=window)  # the samples' window


def shear_segment(network: Network, mass: np.ndarray, scene: PackingScene, options: ShearParams,
                  window: Optional[tuple[float, float]], begin: tuple, index: int, base: int,
                  progress: Optional[Callable[[float], None]]) -> Branch:
    """Segment `index` of a shear run from the relaxed state begin = (q, xi, rows, gamma) to the
    end of the scene's strain range or the first plastic event, as a branch (shear's) of one
    segment, its rows from 0, no plastic event yet and every collision (the scene's strain
    range is applied when the segments are joined); its window runs are numbered from `base`
    (a window is sized again for every segment: its columns start anew there)."""
    q, xi, rows, gamma_start = begin
    problem = PackingEquilibria(network, q, xi, rows, gamma_start, mass, scene.matrix, options.newton_tol)
    if window is not None:  # sized at the segment's start
        options = replace(options, eigensolver=SpectralWindow(*window, margin=WINDOW_MARGIN, extra=WINDOW_EXTRA))

    def record(gamma, q_k):  # the point's columns (branch.Record)
        xi_all = problem.trial(q_k, gamma)[0]
        xi_k, rows_k = xi_all[problem.active], problem.rows_c[problem.active]
        delta = network.overlaps(q_k, rows_k, gamma)
        return {"rows": problem.rows_c.copy(), "xi": xi_all,
                "residual": largest_force(problem, q_k, gamma), "contacts": int((delta > 0).sum()),
                "loose": int(problem.gauge.loose.sum()),
                "stress": network.stress(q_k, xi_k, rows_k, gamma)}

    def callback_of(run):
        return None if progress is None else (lambda k, gamma, q_k, eigvals: progress(gamma))

    runs, widened, _ = solve_in_runs(problem, q, (gamma_start, scene.gamma_range[1]), options,
                                     callback_of, record, problem.committed)
    rows, pieces = JoinedRuns(), []
    for run, branch in enumerate(runs):  # a run after the first follows a widened window
        skip = int(run > 0)  # its first point is the last one's
        offset = rows.add(branch, base + run, skip, continued=window is not None)
        pieces.append(Piece("run", base + run, offset + skip, len(rows), branch.status))
    columns = {name: column_of(values, name in RAGGED) for name, values in rows.columns.items()}
    eig, kappas, collisions = rows.eigenvalues, rows.condition, rows.collisions
    rel_tol = options.detection.rel_tol
    if not options.detection.spectra:  # none computed: no pair counted
        eig, condition = np.zeros((len(rows), 0), complex), np.zeros((len(rows), 0))
        n_complex = np.full(len(rows), -1)
    elif window is None:
        eig, condition = np.array(eig), np.array(kappas)
        n_complex = np.array([count_complex_pairs(e[e != 0], rel_tol) for e in eig])
    else:  # the pairs in the window; collisions with their double eigenvalue there
        band = SpectralWindow(*window)
        n_complex = np.array([count_complex_pairs(e[band.inside(e)], rel_tol) for e in eig])
        collisions = [c for c in collisions if band.lo <= c.eigenvalue <= band.hi]
        eig, condition = block_columns(eig, np.array(rows.blocks), rows.continued, band, kappas)
    status = runs[-1].status
    matrix = Matrix(scene.matrix)
    return Branch(np.array(rows.p), np.array(rows.u), eig, n_complex, np.array(rows.residual), tuple(collisions),
                  status, condition, columns, (Piece("segment", index, 0, len(rows), status), *pieces),
                  {"event": tuple(rows.event_points), "plastic": ()}, events=rows.events, window=window,
                  widenings=widened,
                  parameter="gamma", units="", state="q", matrix=matrix,
                  eigenvalue_units=EIGENVALUE_UNITS[matrix])


def joined(segments: Sequence[Branch], scene: PackingScene) -> Branch:
    """The branch of a shear run from its segments in order (shear_segment's, each with the
    plastic event passed at its end; the last one's status is the run's): the segments' rows
    one after another, their window columns side by side (each segment's own, nan at the
    other segments' points), collisions below the scene's strain range left out."""
    starts = np.cumsum([0] + [len(s) for s in segments])
    first = segments[0]
    columns = {name: column_of([v for s in segments for v in s.columns[name]], name in RAGGED)
               for name in first.columns}
    kept = [replace(c, step=int(start) + c.step) for s, start in zip(segments, starts)
            for c in s.collisions if c.p >= scene.gamma_range[0]]
    pieces = tuple(replace(piece, start=int(start) + piece.start, stop=int(start) + piece.stop)
                   for s, start in zip(segments, starts) for piece in s.pieces)
    side_by_side = np.concatenate if first.window is None else _diagonal
    return replace(first, p=np.concatenate([s.p for s in segments]),
                   u=np.concatenate([s.u for s in segments]),
                   eigenvalues=side_by_side([s.eigenvalues for s in segments]),
                   condition=side_by_side([s.condition for s in segments]),
                   n_complex=np.concatenate([s.n_complex for s in segments]),
                   residual=np.concatenate([s.residual for s in segments]), collisions=tuple(kept),
                   status=segments[-1].status, columns=columns, pieces=pieces,
                   labelled={"event": tuple(EventPoint(e.p, int(start) + e.row)
                                            for s, start in zip(segments, starts) for e in s.event),
                             "plastic": tuple(e for s in segments for e in s.plastic),
                             **({"sample": tuple(x for s in segments for x in s.sample)}
                                if "sample" in first.labelled else {})},
                   events=sum(s.events for s in segments),
                   widenings=sum(s.widenings for s in segments))


def _diagonal(blocks: Sequence[np.ndarray]) -> np.ndarray:
    """The (m_i, k_i) arrays as one (sum m_i, sum k_i) array, each in its own rows and columns,
    nan elsewhere (window.block_columns across segments)."""
    out = np.full((sum(b.shape[0] for b in blocks), sum(b.shape[1] for b in blocks)), np.nan,
                  dtype=blocks[0].dtype)
    r = c = 0
    for b in blocks:
        out[r:r + b.shape[0], c:c + b.shape[1]] = b
        r, c = r + b.shape[0], c + b.shape[1]
    return out


def shear_scene(scene: PackingScene, plastic_events: int,
                stage: Optional[Callable[[str], None]] = None,
                relax_progress=None, on_gamma: Optional[Callable[[float], None]] = None
                ) -> tuple[Branch, Network, np.ndarray]:
    """(branch, network, mass diagonal): the scene's packing prepared (prepared.prepare_scene)
    and sheared over its strain range with the scene's spectra (shear), passing up to
    `plastic_events` plastic events; `stage` is told each stage, `relax_progress` is the
    preparation's progress, `on_gamma` each accepted strain."""
    say = stage or (lambda line: None)
    say(f"prepare {scene.N} disks to pressure {scene.pressure:g}")
    packing = prepare_scene(scene, relax_progress)
    say(f"shear gamma 0 -> {scene.gamma_range[1]:g}")
    branch = shear(scene, packing, ShearParams(workers=0), on_gamma, plastic_events=plastic_events)
    network = network_of(scene, packing)
    return branch, network, mass_diagonal(network, scene.m, scene.inertia)
