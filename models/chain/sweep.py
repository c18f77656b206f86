"""Quasistatic sweeps of F_x: the branch of equilibria from the rest state, with history.

A sweep A -> B always starts at the rest state (F_x = 0, xi = 0), because the history makes the
equilibrium at A depend on how A was reached. If A != 0 a preparation leg loads 0 -> A first
(leg 0), then the requested leg runs A -> B (leg 1): `--fx 0.12:0` is loading to 0.12 and
unloading back to 0, so both legs together show the hysteresis.

The rest state with eps = 0 is a singular point (pairs touching at delta = 0, N free rolling
modes: J is singular, no tangent exists). The branch therefore starts at F_1 = START_FRACTION
times F_y (the scene's force scale; at most half the first target), reached from the rest state
in one quasistatic step by pseudo-transient relaxation (equilibria.relax); an unloading leg to
0 ends at F_1 too. Collisions between 0 and F_1 are not resolved; complex pairs present at F_1 are
counted in the branch's first row. On the paper's scene the collisions above F_x = 0.006 agree
to all printed digits for F_1 = 1e-5, 1e-4 and 1e-3 (docs/chain.md, "The equilibrium branch";
docs/notes/chain-performance.md, "The start at rest"); below ~1e-7 the branch is still
numerically singular.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.api import Options, solve_in_runs
from diskfriction.continuation.branch import Branch, JoinedRuns, Piece, column_of
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.continuation.spectra.window import SpectralWindow, block_columns
from diskfriction.continuation.spectra.tracking import count_complex_pairs, match_eigenvalues
from diskfriction.matrices import EIGENVALUE_UNITS, Matrix
from diskfriction.symbolic import System

START_FRACTION = 1e-4
SWEEP_STEPS_PER_SPAN = 60
"""A sweep's largest step is its span over this (api.STEPS_PER_SPAN is 50 for other problems):
the chain's reference sweeps (benchmarks/reference_sweeps.py) and the timings in docs/notes are
taken with it."""


@dataclass(frozen=True)
class SweepParams(Options):
    """The options of a disk sweep: solve_branch's Options (api.py), one set of parameters for
    every continuation, plus a spectral window. Steps in the arclength of x = (q, F_x), raw
    units. Where the disk problem takes other defaults than Options', they are set here:
    ds_max = None takes span / SWEEP_STEPS_PER_SPAN (60) of the whole sweep (not of a leg;
    Options: span / 50 of its span), the first step ds_max / 2 (graded from rest on the first
    leg; Options: ds_max / 4), ds_min 1e-10 raw force units (Options: 1e-8 ds_max), newton_tol
    1e-11: max|F| at every stored point [force], a tenth of Options' (the history follows q, so
    the corrector must hold the contacts' forces well below the Coulomb limit's resolution),
    max_steps 20 000 (N = 1000 takes up to 6000 points), and no special points (the disk
    problem carries history: its folds cannot be located after the run), theta None: steps in
    the Euclidean arclength of (q, F_x) (Options: theta = 1, the mesh-independent metric of a
    discretised problem), p_scale and residual_scale 1: steps,
    tolerances in F_x and newton_tol in raw units (Options: relative to the span and to the
    size of F at the start). workers (Options):
    processes scanning steps while the sweep goes on (None: automatic; 0: inline). window:
    (lo, hi) of Re lambda [the matrix's raw units] to track instead of the whole spectrum
    (continuation/spectra/window.py); None: every eigenvalue.
    """

    ds_min: Optional[float] = 1e-10
    newton_tol: float = 1e-11
    max_steps: int = 20_000
    special_points: tuple[str, ...] = ()
    theta: Optional[float] = None
    p_scale: Optional[float] = 1.0
    residual_scale: Optional[float] = 1.0
    window: Optional[tuple[float, float]] = None


Progress = Callable[[float], None]


def sweep(system: System, F_from: float, F_to: float, matrix: Optional[str] = None,
          params: SweepParams = SweepParams(), progress: Optional[Progress] = None) -> Branch:
    """Follow the equilibria from rest to F_from (leg 0, if F_from != 0), then to F_to (leg 1).

    The branch (continuation/branch.Branch, raw units): p = F_x [force] (parameter "F_x"), u =
    q (state "q"); columns xi (m, 2N) the committed histories and free (m,) the free rolling
    modes (disks touching only the substrate, models/chain/equilibria.py, excluded from the
    collisions); residual max|F| with the committed history [force]; pieces: the legs (0 the
    preparation from rest, 1 the requested sweep; a leg that ended short is the last) and the
    runs of the spectral window (sized anew, wider, where it crowded: their columns start anew);
    collisions: the requested leg's; events: contact events (opening, closing, Coulomb cap, a
    free disk joining) the steps were cut at; window (lo, hi) of Re lambda tracked, or None
    (every eigenvalue): with one, eigenvalues holds one column per eigenvalue that passed
    through the window or its guard bands (window.block_columns: nan where it was not
    tracked), of which those with Re lambda in [lo, hi] are certified, and n_complex and the
    collisions count only those there. condition: each eigenvalue's condition number, in the
    columns of eigenvalues (diverging like |F_x - F_c|^(-1/2) at a collision F_c; nan where
    no vectors were computed: the exhaustive detection, a free disk's mode)."""
    if F_from == F_to:
        raise ValueError(f"empty sweep {F_from}:{F_to}")
    if F_from < 0 or F_to < 0:
        raise ValueError(f"F_x must be >= 0 (got {F_from}:{F_to}); the load pushes disk 1 along +x")
    matrix = Matrix(matrix or system.scene.matrix)
    legs = [(0, 0.0, F_from), (1, F_from, F_to)] if F_from != 0 else [(1, 0.0, F_to)]
    span = max(abs(F_to - F_from), F_from)
    ds_max = params.ds_max or span / SWEEP_STEPS_PER_SPAN
    F_1 = min(START_FRACTION * system.scene.F_y, 0.5 * legs[0][2])
    q, xi = relax(system, *system.rest_state(), F_1)
    window = None if params.window is None else SpectralWindow(*params.window)
    problem = DiskEquilibria(system, q, xi, F_1, matrix, params.newton_tol, sparse=None if window is None else True)
    eigensolver = params.eigensolver if window is None else window  # sized at the first leg's start

    def record(F_x, q_k):  # the point's columns (branch.Record)
        xi_k = problem.trial(q_k)[0]
        return {"xi": xi_k, "free": problem.free_count,
                "residual": np.abs(system.forces(q_k, xi_k, F_x)).max()}

    def callback_of(run):  # progress once per point: a later leg's first is the last one's
        if progress is None:
            return None
        return lambda k, F_x, q_k, eigvals: None if k == 0 and len(rows) else progress(F_x)

    rows, pieces, ended, widenings, blocks_used = JoinedRuns(), [], {}, 0, 0
    F_start = F_1
    for leg, _, b in legs:
        b = max(b, F_1)  # unloading ends where loading started: F_x = 0 is the singular rest state
        ds = min(F_1, ds_max) if leg == legs[0][0] else ds_max / 2  # graded away from rest
        options = replace(params, ds_max=ds_max, ds=ds, ds_min=min(params.ds_min, ds), eigensolver=eigensolver)
        first, base = len(rows), max(blocks_used - 1, 0)  # a leg continues the last block
        runs, widened, eigensolver = solve_in_runs(problem, problem.q_c, (F_start, b), options, callback_of,
                                                   record, problem.committed)
        for run, branch in enumerate(runs):  # a run after the first follows a widened window
            if run == 0 and first > 0:
                branch = _continue_leg(rows.eigenvalues[first - 1], branch)
            # its first point is the last one recorded; the preparation leg's collisions are not the sweep's
            rows.add(branch, base + run, skip=int(run > 0 or first > 0), collisions=leg == 1,
                     continued=window is not None)
            ended[base + run] = branch.status
        blocks_used, widenings, status = base + len(runs), widenings + widened, runs[-1].status
        pieces.append(Piece("leg", leg, first, len(rows), status))
        F_start = float(runs[-1].p[-1])
        if not status.reached:
            break  # a leg that ended short: the next would start from a load never asked for
    columns = {name: column_of(values) for name, values in rows.columns.items()}
    blocks, eig, condition, collisions = np.array(rows.blocks), rows.eigenvalues, rows.condition, rows.collisions
    pieces += [Piece("run", int(b), int(on[0]), int(on[-1]) + 1, ended[b])
               for b in np.unique(blocks) for on in [np.flatnonzero(blocks == b)]]
    rel_tol = params.detection.rel_tol
    if window is None:
        eig, condition = np.array(eig), np.array(condition)
        n_complex = np.array([count_complex_pairs(e, rel_tol) for e in eig])
    else:  # the pairs in the window; collisions with their double eigenvalue there
        n_complex = np.array([count_complex_pairs(e[window.inside(e)], rel_tol) for e in eig])
        collisions = [c for c in collisions if window.lo <= c.eigenvalue <= window.hi]
        eig, condition = block_columns(eig, blocks, rows.continued, window, condition)
    return Branch(np.array(rows.p), np.array(rows.u), eig, n_complex, np.array(rows.residual), tuple(collisions),
                  status, condition, columns, tuple(pieces), {"event": tuple(rows.event_points)},
                  events=rows.events, window=params.window,
                  widenings=widenings, parameter="F_x", units="force", state="q", matrix=matrix,
                  eigenvalue_units=EIGENVALUE_UNITS[matrix])


def _continue_leg(before: np.ndarray, branch: Branch) -> Branch:
    """A leg after another starts at that one's last point, whose eigenvalues are `before`, with
    its labels in order of value (arclength._sorted): its branch relabelled to continue the last
    point's labels, the same eigenvalues at the same point matched by value
    (tracking.match_eigenvalues), and the branch's collision pairs, window columns
    (Branch.continued) and condition numbers with them."""
    perm = match_eigenvalues(before, branch.eigenvalues[0])  # new label i holds old perm[i]
    of_label = np.argsort(perm)
    pairs = tuple(replace(c, pair=(int(of_label[c.pair[0]]), int(of_label[c.pair[1]])))
                  for c in branch.collisions)
    continued = None if branch.continued is None else branch.continued[:, perm]
    return replace(branch, eigenvalues=branch.eigenvalues[:, perm], collisions=pairs,
                   continued=continued, condition=branch.condition[:, perm])
