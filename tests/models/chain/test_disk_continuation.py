"""The disk chain's equilibrium branch: residual, spectra, collisions, history, events."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation.branch import Stop, StopCode
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.matrices import Matrix
from diskfriction.scenes import Scene
from diskfriction.symbolic import System

PAPER = Scene()


@pytest.fixture(scope="module")
def paper_system():
    return System.from_scene(PAPER)


@pytest.fixture(scope="module", params=["J", "M^-1 J"])
def paper_branch(request, chain_sweep):
    return chain_sweep(PAPER, request.param)[0]  # conftest: the paper's sweeps, shared


def test_a_matrix_name_other_than_J_or_M_inv_J_is_refused(paper_system):
    """Before, any matrix name other than "J" meant M^-1 J silently."""
    q, xi = paper_system.rest_state()
    with pytest.raises(ValueError, match="'M J' is not a valid Matrix"):
        DiskEquilibria(paper_system, q, xi, 1e-5, "M J")
    assert DiskEquilibria(paper_system, q, xi, 1e-5, "M^-1 J").matrix is Matrix.M_INV_J


def test_rest_state_is_singular_and_relaxation_starts_the_branch(paper_system):
    """eps = 0: the pairs touch at delta = 0 and each disk rolls freely (N zero modes of J);
    pseudo-transient relaxation still reaches the equilibrium at a small load."""
    q, xi = paper_system.rest_state()
    eig = np.linalg.eigvals(paper_system.jacobian(q, xi))
    assert np.sum(np.abs(eig) < 1e-9) == PAPER.N
    q1, xi1 = relax(paper_system, q, xi, 1e-5)
    assert np.abs(paper_system.forces(q1, xi1, 1e-5)).max() <= 1e-11
    assert np.all(np.abs(np.linalg.eigvals(paper_system.jacobian(q1, xi1))) > 1e-3)


def test_equilibrium_residual_stays_below_1e10_along_the_paper_branch(paper_branch, paper_system):
    assert paper_branch.status == Stop(StopCode.REACHED) and paper_branch.F_x[-1] == 0.12
    res = [np.abs(paper_system.forces(q, xi, F)).max()
           for F, q, xi in zip(paper_branch.F_x, paper_branch.q, paper_branch.xi)]
    assert max(res) <= 1e-10


def test_stored_eigenvalues_equal_recomputed_ones(paper_branch, paper_system):
    for q, xi, stored in zip(paper_branch.q, paper_branch.xi, paper_branch.eigenvalues):
        A = paper_system.stability_matrix(paper_system.jacobian(q, xi), paper_branch.matrix)
        again = np.sort_complex(np.linalg.eigvals(A))
        assert np.abs(np.sort_complex(stored) - again).max() <= 1e-9 * np.abs(again).max()


def expected_count(branch, F_x):
    """Complex pairs at F_x predicted from the first point's count and the collision list."""
    n = int(branch.n_complex[0])
    for c in branch.collisions:
        if c.p < F_x:
            n += 1 if c.kind == "birth" else -1
    return n


def test_complex_pair_count_changes_across_every_collision_and_nowhere_else(paper_branch, paper_system):
    """Checked on the branch's own points and on an independent, 3x finer sweep."""
    for F, n in zip(paper_branch.F_x, paper_branch.n_complex):
        assert n == expected_count(paper_branch, F)
    fine = sweep(paper_system, 0.0, 0.12, paper_branch.matrix, SweepParams(ds_max=0.12 / 180))
    near = [min(abs(F - c.p) for c in paper_branch.collisions) for F in fine.F_x]
    for F, n, gap in zip(fine.F_x, fine.n_complex, near):
        if gap > 1e-7:  # the two sweeps' branches differ by ~1e-9 in F_x at a collision
            assert n == expected_count(paper_branch, F), F
    assert all(c.resolved and c.bracket[1] - c.bracket[0] <= 1e-10 for c in paper_branch.collisions)


@pytest.mark.slow
def test_collision_locations_converge_as_the_step_shrinks(paper_system):
    """The history is integrated per step, so the branch itself depends on the step; the located
    collisions must converge: successive halvings change them by less and less, below 1e-8.
    Even the coarsest steps (span / 15) must find all of them: a 1.3e-4 wide bubble at
    F_x = 0.0243, where a fast eigenvalue passes through the y-mode cluster, was once missed."""
    runs = [sweep(paper_system, 0.0, 0.12, "J", SweepParams(ds_max=0.12 / n)).collisions
            for n in (15, 30, 60, 120)]
    assert len({len(r) for r in runs}) == 1 and len(runs[0]) > 0
    d = [max(abs(a.p - b.p) for a, b in zip(r0, r1)) for r0, r1 in zip(runs, runs[1:])]
    assert d[-1] <= 1e-8 and d[-1] <= d[-2] + 1e-12


def test_unloading_without_slip_retraces_the_loading_branch(paper_system):
    """No contact slides on the paper's branch, and the Mindlin history is then reversible:
    unloading meets the same collisions with birth and death exchanged."""
    loading = sweep(paper_system, 0.0, 0.06).collisions
    unloading = sweep(paper_system, 0.06, 0.0).collisions
    assert len(loading) == len(unloading)
    for a, b in zip(loading, reversed(unloading)):
        assert abs(a.p - b.p) <= 1e-8 and {a.kind, b.kind} == {"birth", "death"}


def test_coulomb_events_split_the_steps_and_leave_hysteresis():
    """mu = 2 loaded to F_x = 1: contacts reach their Coulomb limit; steps are split there, no
    stored history exceeds t*, the residual stays small, and unloading does not retrace."""
    system = System.from_scene(Scene(mu=2.0))
    branch = sweep(system, 1.0, 0.5)
    assert branch.events >= 1
    s = system.scene
    for F, q, xi in zip(branch.F_x, branch.q, branch.xi):
        t_star = s.mu * s.k_n * np.clip(system.overlaps(q), 0, None) / s.k_t
        assert np.all(np.abs(xi) <= t_star * (1 + 1e-12))
        assert np.abs(system.forces(q, xi, F)).max() <= 1e-10
    at_half = [np.argmin(np.abs(branch.F_x - 0.5) + 10 * (branch.leg != leg)) for leg in (0, 1)]
    x1_loading, x1_unloading = (branch.q[k][0] for k in at_half)
    assert abs(x1_unloading - x1_loading) > 1e-6  # slip left the chain displaced


@pytest.mark.parametrize("F_from, F_to", [(0.0, 0.0), (-0.1, 0.1), (0.1, -0.1)])
def test_bad_sweep_ranges_are_refused(paper_system, F_from, F_to):
    with pytest.raises(ValueError):
        sweep(paper_system, F_from, F_to)


def test_a_sweeps_parameters_are_the_apis_options_with_the_disk_problems_defaults():
    """One set of continuation parameters (issue 24 item 5): SweepParams is an Options, and
    differs from its defaults only where its docstring says why (steps, their metric, raw units
    and the tolerance of the disk problem, no special points) and by the spectral window; Options takes the core's
    Newton defaults rather than copies."""
    from dataclasses import fields

    from diskfriction.continuation import ContinuationParams, Options
    from diskfriction.models.chain.sweep import SweepParams

    sweep, api = SweepParams(), Options()
    assert isinstance(sweep, Options)
    differ = {f.name for f in fields(SweepParams) if getattr(sweep, f.name) != getattr(api, f.name, None)}
    assert differ == {"ds_min", "newton_tol", "max_steps", "special_points", "theta", "p_scale",
                      "residual_scale"}  # window: None in both; the chain's raw units (scales 1)
    core = ContinuationParams()
    assert (api.newton_tol, api.max_newton, api.max_steps) == (core.newton_tol, core.max_newton, core.max_steps)
