"""Collisions of eigenvalues located by the continuation core on problems with known answers
(tests/core_problems.py): 2x2 blocks with a Jordan block at a root of c(p), bubbles narrower than
the step, two pairs born at once, a collision past a fold, the tracked spectrum, an added
detector, and a spectral window that crowds."""
from __future__ import annotations

import numpy as np
import pytest
from core_problems import (P0, TOL_P, assert_count_changes_only_at_collisions, block_diag, blocks_family,
                           brusselator, bubble_problem, fast_eigenvalue_through_a_cluster, located, pair_block,
                           run, spectrum)

from diskfriction.continuation import (ContinuationParams, DetectionParams, FunctionProblem, continuation,
                                       count_complex_pairs)
from diskfriction.continuation.branch import StopCode
from diskfriction.continuation.detection.detectors import DETECTORS, Kind
from diskfriction.continuation.detection.detectors.fast import Fast
from diskfriction.continuation.spectra.tracking import sort_spectrum


@pytest.mark.parametrize("direction, kind", [(1, "death"), (-1, "birth")])
def test_2x2_collision_located_to_1e10_with_jordan_vectors(direction, kind):
    """A(p) = [[a, 1], [p - p0, a]]: eigenvalues a +- sqrt(p - p0); complex below p0, so a
    death at p0 going up in p (a birth going down) with the Jordan block [[a, 1], [0, a]]:
    v = e1, w = e2."""
    a = -0.7
    problem = blocks_family([(a, lambda p: p - P0, lambda p: 1.0)])
    br = run(problem, 2, ds=0.07, ds_max=0.1, direction=direction)
    assert br.status.reached and br.p[-1] == (1.0 if direction > 0 else 0.0)
    (c,) = br.collisions
    assert c.kind == kind and c.resolved
    assert abs(c.p - P0) <= TOL_P and c.bracket[0] <= c.p <= c.bracket[1]
    assert c.bracket[1] - c.bracket[0] <= TOL_P and c.bracket[0] - TOL_P <= P0 <= c.bracket[1] + TOL_P
    assert c.eigenvalue == pytest.approx(a, abs=1e-5)
    assert np.allclose(np.abs(c.eigenvector), [1, 0], atol=1e-5)
    assert np.allclose(np.abs(c.generalized_eigenvector), [0, 1], atol=1e-5)
    assert c.left_right_overlap <= 1e-5
    assert_count_changes_only_at_collisions(problem, br, 0.0, 1.0)


@pytest.mark.parametrize("ds", [1e-2, 3.7e-2])
@pytest.mark.slow
def test_bubble_narrower_than_the_step_is_found(ds):
    """Birth at p1, death at p2 = p1 + 1e-3, with steps of 10x and 37x the bubble width."""
    p1 = 0.41 + 1e-4 / np.e
    p2 = p1 + 1e-3
    problem = bubble_problem(p1, p2)
    br = run(problem, 3, ds=ds, u0=np.array([0.0, 0.0, 0.0]))
    assert br.status.reached and np.max(np.diff(br.p)) >= 9 * (p2 - p1)
    assert located(br, "birth") == pytest.approx([p1], abs=TOL_P)
    assert located(br, "death") == pytest.approx([p2], abs=TOL_P)
    assert all(c.resolved and c.residual <= 1e-12 for c in br.collisions)
    assert_count_changes_only_at_collisions(problem, br, 0.0, 1.0, n_grid=20001)


@pytest.mark.parametrize("a2, k", [(0.5, 2.0), (0.0, 1.0)], ids=["distinct", "identical-blocks"])
@pytest.mark.slow
def test_two_pairs_born_at_the_same_p_are_both_reported(a2, k):
    """blockdiag([[0, 1], [p0 - p, 0]], [[a2, 1], [k (p0 - p), a2]]): two births at p0. The
    distinct case also has real eigenvalues of the two blocks crossing before p0 (no collision);
    the identical case has every eigenvalue double (semisimple)."""
    problem = blocks_family([(0.0, lambda p: P0 - p, lambda p: -1.0),
                             (a2, lambda p: k * (P0 - p), lambda p: -k)])
    br = run(problem, 4, ds=0.1)
    assert located(br, "birth") == pytest.approx([P0, P0], abs=TOL_P)
    assert located(br, "death") == []
    assert sorted(c.eigenvalue for c in br.collisions) == pytest.approx(sorted([0.0, a2]), abs=1e-5)
    assert br.n_complex[0] == 0 and br.n_complex[-1] == 2
    assert_count_changes_only_at_collisions(problem, br, 0.0, 1.0)


def test_many_narrow_bubbles_all_found():
    """c(p) = 0.999 - sin(20 p) is negative only near the peaks of the sine: a birth and a
    death 4.5e-3 apart around every p = (pi/2 + 2 pi m) / 20 (7 in [0, 2]), steps of 0.05."""
    problem = blocks_family([(-0.3, lambda p: 0.999 - np.sin(20 * p), lambda p: -20 * np.cos(20 * p))])
    br = run(problem, 2, p_max=2.0, ds=0.05)
    theta = np.arcsin(0.999)
    births = [(theta + 2 * np.pi * m) / 20 for m in range(7)]
    deaths = [(np.pi - theta + 2 * np.pi * m) / 20 for m in range(7)]
    assert located(br, "death") == pytest.approx(deaths, abs=TOL_P)
    assert located(br, "birth") == pytest.approx(births, abs=TOL_P)
    assert_count_changes_only_at_collisions(problem, br, 0.0, 2.0, n_grid=20001)


def test_collision_located_through_a_fold():
    """u1^2 + p = 0 folds at p = 0; blocks with c1 = u1 - 0.3 and c2 = u1 + 0.2 give a birth at
    u1 = 0.3 (p = -0.09, before the fold) and a birth at u1 = -0.2 (p = -0.04, after it: p is
    decreasing there, kinds follow the branch direction)."""
    def A(u):
        return block_diag(pair_block(-0.5, u[0] - 0.3), pair_block(0.5, u[0] + 0.2))

    def G(u, p):
        return np.append(u[0] ** 2 + p, A(u) @ u[1:])

    def G_u(u, p):
        J = np.zeros((5, 5))
        J[0, 0] = 2 * u[0]
        J[1:, 1:] = A(u)
        J[2, 0], J[4, 0] = u[1], u[3]
        return J

    problem = FunctionProblem(G, G_u, lambda u, p: np.array([1.0, 0, 0, 0, 0]), A=lambda u, p: A(u))
    br = run(problem, 5, p_min=-1.0, p_max=1.0, ds=0.1, u0=np.array([1.0, 0, 0, 0, 0]))
    assert br.status.code == StopCode.TURNED_BACK and br.u[-1, 0] == pytest.approx(-1.0)
    assert [c.kind for c in br.collisions] == ["birth", "birth"]
    assert [c.p for c in br.collisions] == pytest.approx([-0.09, -0.04], abs=TOL_P)
    assert [c.u[0] for c in br.collisions] == pytest.approx([0.3, -0.2], abs=1e-9)


def test_stored_eigenvalues_equal_recomputed_ones_and_are_tracked():
    a = np.sqrt(2.0)
    problem = brusselator(a)
    br = run(problem, 2, p_min=0.0, p_max=7.0, ds=0.1, ds_max=0.5, u0=np.array([a, 0.0]))
    for k in range(len(br)):
        again = spectrum(problem, br.u[k], br.p[k])
        assert np.allclose(sort_spectrum(br.eigenvalues[k]), sort_spectrum(again), rtol=1e-12, atol=1e-12)
        assert br.n_complex[k] == count_complex_pairs(again)
    # tracked columns: each step moves every eigenvalue by no more than a re-sorted order would
    steps = np.abs(np.diff(br.eigenvalues, axis=0)).sum(axis=1)
    resorted = np.abs(np.diff(np.array([sort_spectrum(e) for e in br.eigenvalues]), axis=0)).sum(axis=1)
    assert np.all(steps <= resorted + 1e-12)


def test_collision_location_converges_as_the_step_shrinks():
    """Bubble family on the curved branch: for ds from 0.2 down to 0.0125 every run finds the
    same two collisions, all within 1e-10 of the analytic ones."""
    p1 = 0.41 + 1e-4 / np.e
    p2 = p1 + 1e-3
    problem = bubble_problem(p1, p2)
    locs = np.array([[c.p for c in run(problem, 3, ds=ds).collisions] for ds in 0.2 / 2 ** np.arange(5)])
    assert locs.shape == (5, 2)
    assert np.all(np.abs(locs - [p1, p2]) <= TOL_P)
    assert np.all(np.abs(np.diff(locs, axis=0)) <= 2 * TOL_P)


@pytest.mark.parametrize("ds", [0.1, 0.13])
def test_bubble_of_a_fast_eigenvalue_passing_a_cluster_is_found(ds):
    """The pair's D is a near-parabola touching zero; a three-sample quadratic cannot tell it
    from a crossing when the stencil straddles other encounters. The steps are 250x and 325x
    the bubble's width; both collisions are found and located to 1e-10."""
    problem, (p1, p2) = fast_eigenvalue_through_a_cluster()
    branch = run(problem, 4, 0.0, 0.4, ds=ds)
    assert located(branch, "birth") == pytest.approx([p1], abs=TOL_P)
    assert located(branch, "death") == pytest.approx([p2], abs=TOL_P)
    assert_count_changes_only_at_collisions(problem, branch, 0.0, 0.4)


class Bisecting(Fast):
    """An added detector: the fast verdicts, but each event bracketed by bisection down to
    tol_p (no Newton locator), so its collisions come from StepScan.interpolated."""

    name = "bisecting"

    def resolve(self, scan, idx, verdict):
        scan.split(idx, 0.5 * (scan.samples[idx].s + scan.samples[idx + 1].s))
        return True


def test_a_detector_added_by_one_registry_entry_finds_the_collisions(monkeypatch):
    """Adding a detector is one class and one DETECTORS entry (docs/continuation.md, Adding a
    detector): the scan drives it, and it brackets the bubble of a fast eigenvalue passing a
    cluster (steps 250 times its width) to tol_p, where the fast detection's Newton locator
    puts it."""
    monkeypatch.setitem(DETECTORS, Bisecting.name, Bisecting())
    problem, (p1, p2) = fast_eigenvalue_through_a_cluster()
    par = ContinuationParams(ds=0.1, ds_min=1e-9, ds_max=0.1, newton_tol=1e-12, p_min=0.0, p_max=0.4)
    branch = continuation(problem, np.zeros(4), 0.0, par, DetectionParams(mode=Bisecting.name))
    assert [c.kind for c in branch.collisions] == [Kind.BIRTH, Kind.DEATH]
    assert located(branch, "birth") == pytest.approx([p1], abs=TOL_P)
    assert located(branch, "death") == pytest.approx([p2], abs=TOL_P)
    assert all(c.resolved and c.bracket[1] - c.bracket[0] <= TOL_P for c in branch.collisions)
    with pytest.raises(ValueError, match="mode must be one of"):
        DetectionParams(mode="bisect")


def test_a_crowded_spectral_window_ends_the_run_at_its_last_certified_point():
    """A spectrum that raises WindowCrowded past p = 0.5 (at a step's end or a split sample)
    ends the run there with StopCode.WINDOW and the branch reached so far, its collisions
    kept, not an exception that loses the run."""
    from diskfriction.continuation import Options, problem_from_functions, solve_branch
    from diskfriction.continuation.branch import StopCode
    from diskfriction.continuation.spectra.window import WindowCrowded

    p1 = 0.21

    def A(u, p):
        if p > 0.5:
            raise WindowCrowded("the 2 eigenvalues nearest 0 all lie within 1 of it")
        return pair_block(-0.7, p1 - p)

    problem = problem_from_functions(lambda u, p: u - p, dG_du=lambda u, p: np.eye(1),
                                     dG_dp=lambda u, p: -np.ones(1), A=A)
    result = solve_branch(problem, [0.0], (0.0, 1.0), Options(workers=0))
    status = result.branch.status
    assert status.code is StopCode.WINDOW and "all lie within" in str(status)
    assert 0.4 < result.p[-1] <= 0.5 and status.p == result.p[-1]
    assert [c.kind for c in result.collisions] == ["birth"]
    assert result.collisions[0].p == pytest.approx(p1, abs=1e-10)
