"""The generic continuation core on small problems with known answers.

Families G(u, p) = A(p) u with the equilibrium u = 0 have the spectrum of A(p) along the whole
branch; 2x2 blocks [[a, 1], [c(p), a]] have eigenvalues a +- sqrt(c(p)), so a pair is complex
exactly where c(p) < 0 and every collision is a root of c.
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from diskfriction.continuation import (ContinuationParams, DetectionParams, FunctionProblem, continuation,
                          count_complex_pairs)
from diskfriction.continuation.detection.bifurcations import locate_folds, locate_hopf
from diskfriction.continuation.branch import Stop, StopCode
from diskfriction.continuation.stepping.segment import refine_sign_change
from diskfriction.continuation.detection.detectors import DETECTORS, Kind
from diskfriction.continuation.detection.detectors.fast import Fast
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.continuation.spectra.tracking import sort_spectrum

TOL_P = 1e-10


def block_diag(*blocks) -> np.ndarray:
    """scipy.linalg.block_diag of float blocks, the same matrix without scipy's argument
    handling: 0.17 ms a call there, most of the time of the dense grids below (20 000 and more
    matrices each)."""
    blocks = [np.atleast_2d(np.asarray(b, dtype=float)) for b in blocks]
    out = np.zeros((sum(b.shape[0] for b in blocks), sum(b.shape[1] for b in blocks)))
    r = c = 0
    for b in blocks:
        out[r:r + b.shape[0], c:c + b.shape[1]] = b
        r, c = r + b.shape[0], c + b.shape[1]
    return out


def linear_family(A, dA):
    """G(u, p) = A(p) u: G_u = A(p), G_p = A'(p) u."""
    return FunctionProblem(G=lambda u, p: A(p) @ u, G_u=lambda u, p: A(p), G_p=lambda u, p: dA(p) @ u)


def pair_block(a, c):
    """[[a, 1], [c, a]]: eigenvalues a +- sqrt(c)."""
    return np.array([[a, 1.0], [c, a]])


def blocks_family(blocks):
    """Block-diagonal family from [(a, c, dc), ...], c(p) and dc(p) callables."""
    A = lambda p: block_diag(*[pair_block(a, c(p)) for a, c, _ in blocks])
    dA = lambda p: block_diag(*[np.array([[0.0, 0.0], [dc(p), 0.0]]) for _, _, dc in blocks])
    return linear_family(A, dA)


def run(problem, n, p_min=0.0, p_max=1.0, ds=0.05, ds_max=None, u0=None, direction=1):
    par = ContinuationParams(ds=ds, ds_min=1e-9, ds_max=ds if ds_max is None else ds_max,
                             newton_tol=1e-12, p_min=p_min, p_max=p_max, direction=direction)
    return continuation(problem, np.zeros(n) if u0 is None else u0, p_min if direction > 0 else p_max, par)


def spectrum(problem, u, p):
    """Every eigenvalue of the problem's stability matrix at (u, p) (DenseSpectra)."""
    return DenseSpectra().eigensystem(problem, u, p).values


def located(branch, kind):
    return sorted(c.p for c in branch.collisions if c.kind == kind)


def assert_count_changes_only_at_collisions(problem, branch, p_lo, p_hi, n_grid=4001):
    """On a dense grid plus points 1e-9 outside every bracket, the count of complex pairs
    (at u = 0) changes between neighbours by exactly births - deaths located in between
    (for a branch monotone in p; kinds follow the branch direction)."""
    extra = [q for c in branch.collisions for q in (c.bracket[0] - 1e-9, c.bracket[1] + 1e-9)]
    grid = np.unique(np.clip(np.concatenate([np.linspace(p_lo, p_hi, n_grid), extra]), p_lo, p_hi))
    n = branch.u.shape[1]
    counts = np.array([count_complex_pairs(spectrum(problem, np.zeros(n), q)) for q in grid])
    up = 1 if branch.p[-1] > branch.p[0] else -1
    sign = {"birth": up, "death": -up}
    for g0, g1, c0, c1 in zip(grid[:-1], grid[1:], counts[:-1], counts[1:]):
        inside = [c for c in branch.collisions if g0 < c.p <= g1]
        assert c1 - c0 == sum(sign[c.kind] for c in inside), (g0, g1, c0, c1, inside)
    for c in branch.collisions:  # the count changes across every bracket (by all it holds)
        lo, hi = c.bracket[0] - 1e-9, c.bracket[1] + 1e-9
        before = count_complex_pairs(spectrum(problem, np.zeros(n), lo))
        after = count_complex_pairs(spectrum(problem, np.zeros(n), hi))
        assert after - before == sum(sign[d.kind] for d in branch.collisions if lo < d.p < hi) != 0


# ---- folds and Hopf -------------------------------------------------------------------------

def test_fold_of_scalar_equation_is_passed_and_located():
    """G = u^2 + p from (u, p) = (1, -1): the branch turns at the fold (0, 0) and lands on
    p = -1 again at u = -1, the side it started from, short of p_max = 1: its status says it
    turned back (issue 23: it said "p_end"). Fold located to |x - x_fold| <= 1e-9, on the
    branch within the corrector's residual (|u^2 + p| <= 1e-12: with the bracket's points
    corrected to that residual, p carries it even where u = 0 exactly)."""
    problem = FunctionProblem(G=lambda u, p: np.array([u[0] ** 2 + p]), G_u=lambda u, p: np.array([[2 * u[0]]]),
                              G_p=lambda u, p: np.array([1.0]))
    br = run(problem, 1, p_min=-1.0, p_max=1.0, ds=0.1, ds_max=0.2, u0=np.array([1.0]))
    assert br.status.code == StopCode.TURNED_BACK and br.status.p == -1
    assert br.p[-1] == -1.0 and br.u[-1, 0] == pytest.approx(-1.0, abs=1e-10)
    assert np.all(np.abs(br.u[:, 0] ** 2 + br.p) <= 1e-12)
    folds = locate_folds(problem, br)
    assert len(folds) == 1
    assert np.hypot(folds[0].u[0], folds[0].p) <= 1e-9 and abs(folds[0].u[0] ** 2 + folds[0].p) <= 1e-12
    assert folds[0].bracket[0] <= folds[0].p <= folds[0].bracket[1]


def test_stop_at_fold_ends_the_run_before_p_turns_back():
    """The same fold with stop_at_fold: the step that passes the fold (p falling, the tangent
    pointing back in p) is cut where the tangent's p-component changes sign, bracketed to
    ds_min (step.before_fold), so the run ends (Stop "fold", located on the step)
    within ds_min of the fold (u <= 1e-9, |p| <= 1e-12, the residual tolerance) in 10 points
    (halving the step until below ds_min took 22), and every point has u > 0 (the branch
    never went round)."""
    problem = FunctionProblem(G=lambda u, p: np.array([u[0] ** 2 + p]), G_u=lambda u, p: np.array([[2 * u[0]]]),
                              G_p=lambda u, p: np.array([1.0]))
    par = ContinuationParams(ds=0.1, ds_min=1e-9, ds_max=0.2, newton_tol=1e-12, p_min=-1.0,
                             p_max=1.0, stop_at_fold=True)
    br = continuation(problem, np.array([1.0]), -1.0, par)
    assert br.status.code == StopCode.FOLD and br.status.p == br.p[-1] and "located" in str(br.status)
    assert np.all(np.diff(br.p) > 0) and np.all(br.u[:, 0] > 0)
    assert abs(br.p[-1]) <= 1e-12 and br.u[-1, 0] <= 1e-9 and len(br.p) <= 12


def brusselator(a):
    """x' = a - (b + 1) x + x^2 y, y' = b x - x^2 y with p = b; steady state (a, b / a);
    Jacobian [[b - 1, a^2], [-b, -a^2]]: Hopf at b = 1 + a^2, complex pair for
    (a - 1)^2 < b < (a + 1)^2."""
    def G(u, b):
        x, y = u
        return np.array([a - (b + 1) * x + x * x * y, b * x - x * x * y])

    def J(u, b):
        x, y = u
        return np.array([[-(b + 1) + 2 * x * y, x * x], [b - 2 * x * y, -x * x]])

    return FunctionProblem(G, J, lambda u, b: np.array([-u[0], u[0]]))


def test_brusselator_hopf_and_collisions_match_analytic():
    """a = sqrt(2): Hopf at b = 3 with omega = a; pair born at (a-1)^2, dies at (a+1)^2."""
    a = np.sqrt(2.0)
    problem = brusselator(a)
    br = run(problem, 2, p_min=0.0, p_max=7.0, ds=0.1, ds_max=0.5, u0=np.array([a, 0.0]))
    assert br.status.reached and br.p[-1] == 7.0
    assert np.allclose(br.u[:, 1], br.p / a, atol=1e-10)
    hopf = locate_hopf(problem, br)
    assert len(hopf) == 1
    assert abs(hopf[0].p - (1 + a * a)) <= TOL_P and abs(hopf[0].value - 1j * a) <= 1e-8
    assert located(br, "birth") == pytest.approx([(a - 1) ** 2], abs=TOL_P)
    assert located(br, "death") == pytest.approx([(a + 1) ** 2], abs=TOL_P)
    for c in br.collisions:  # double eigenvalue -sqrt(det) = -a at birth, +a at death
        assert c.eigenvalue == pytest.approx(-a if c.kind == "birth" else a, abs=1e-6)


# ---- collisions -----------------------------------------------------------------------------

P0 = 1 / np.pi


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


def bubble_problem(p1, p2):
    """[[a, 1], [c, a]] with c = (p - p1)(p - p2) e^p (complex only on (p1, p2)), plus a third
    coordinate u3 = sin(3 p) that makes the branch curved, so arclength is not linear in p."""
    a = -0.7

    def c(p):
        return (p - p1) * (p - p2) * np.exp(p)

    def dc(p):
        return ((2 * p - p1 - p2) + (p - p1) * (p - p2)) * np.exp(p)

    def A(p):
        return block_diag(pair_block(a, c(p)), [[1.0]])

    def G(u, p):
        return np.append(pair_block(a, c(p)) @ u[:2], u[2] - np.sin(3 * p))

    def G_p(u, p):
        return np.array([0.0, dc(p) * u[0], -3 * np.cos(3 * p)])

    return FunctionProblem(G, lambda u, p: A(p), G_p)


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


# ---- invariants -----------------------------------------------------------------------------

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


def test_commit_hook_sees_every_accepted_step_after_detection():
    calls = []

    class Recording(FunctionProblem):
        def commit(self, u_old, p_old, u_new, p_new):
            calls.append((p_old, p_new))

    base = blocks_family([(-0.7, lambda p: p - P0, lambda p: 1.0)])
    problem = Recording(base.G, base.G_u, base.G_p)
    br = run(problem, 2, ds=0.07, ds_max=0.1)
    assert calls == list(zip(br.p[:-1], br.p[1:]))


def test_commit_that_changes_the_state_is_followed_by_a_fixed_p_correction():
    """G = u - p - h with a 'history' h raised by 1e-3 at every commit (which returns True):
    every stored point is an equilibrium of the state after its own commit."""
    class Stateful(FunctionProblem):
        h = 0.0

        def commit(self, u_old, p_old, u_new, p_new):
            type(self).h += 1e-3
            return True

    problem = Stateful(lambda u, p: u - p - Stateful.h, lambda u, p: np.eye(1), lambda u, p: -np.ones(1))
    seen = []
    par = ContinuationParams(ds=0.1, ds_max=0.1, p_min=0.0, p_max=1.0, newton_tol=1e-12)
    br = continuation(problem, np.zeros(1), 0.0, par, callback=lambda k, p, u, ev: seen.append(k))
    assert seen == list(range(len(br)))
    assert np.allclose(br.u[:, 0] - br.p, 1e-3 * np.arange(len(br)), atol=1e-12)
    assert np.all(br.residual <= 1e-12)


def test_parameters_are_validated_at_the_door():
    with pytest.raises(ValueError):
        ContinuationParams(ds=1.0, ds_max=0.1)
    with pytest.raises(ValueError):
        ContinuationParams(p_min=1.0, p_max=0.0)
    with pytest.raises(ValueError):
        DetectionParams(rho=1.5)
    problem = blocks_family([(-0.7, lambda p: p - P0, lambda p: 1.0)])
    with pytest.raises(ValueError):
        continuation(problem, np.zeros(2), 1.0, ContinuationParams(p_min=0.0, p_max=1.0))


def fast_eigenvalue_through_a_cluster(v=10.0, c=1e-3):
    """A fast eigenvalue f(p) = v p sweeps past slow ones at 1, 2 and 3: an exact crossing
    with 1 (no coupling), a narrow bubble with 2 (skew coupling c: complex while
    |f - 2| < 2c, width ~4c / v) and an avoided crossing with 3 (symmetric coupling c).
    The coupled 3x3 block has det(lambda - A) = (lambda - f)(lambda - 2)(lambda - 3) - c^2; the
    collisions are the roots of that cubic's discriminant, found here by brentq."""
    def A(p):
        M = np.diag([v * p, 1.0, 2.0, 3.0])
        M[0, 2], M[2, 0] = c, -c
        M[0, 3] = M[3, 0] = c
        return M

    def discriminant(p):
        f = v * p
        b, k, d = -(f + 5.0), 5.0 * f + 6.0, -(6.0 * f + c * c)
        return 18 * b * k * d - 4 * b**3 * d + b * b * k * k - 4 * k**3 - 27 * d * d

    dA = lambda p: np.diag([v, 0.0, 0.0, 0.0])
    exact = tuple(brentq(discriminant, (2 + sign * c) / v, (2 + sign * 3 * c) / v, xtol=1e-15)
                  for sign in (-1, 1))
    return linear_family(A, dA), exact


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


def test_a_stop_prints_its_status_line_and_says_its_reason_without_the_location():
    """Branch.status is a Stop; its line (MESSAGES) is the text the status had as a string,
    and sentence() is what stop_reason parsed back out of it by regex before."""
    failed = Stop(StopCode.DS_MIN, "corrector failed (residual 1.63e-11)", 5.0997512345678)
    assert str(failed) == "ds_min: corrector failed (residual 1.63e-11) at p=5.09975123457"
    assert failed.sentence(7) == "corrector failed (residual 1.63e-11)" and not failed.reached
    folded = Stop(StopCode.TURNED_BACK, "the branch folded and left the span on its starting side", -1.0)
    assert str(folded) == "turned back: the branch folded and left the span on its starting side at p=-1"
    assert str(Stop(StopCode.COMMIT, "no equilibrium after the commit", 0.5)) == \
        "commit: no equilibrium after the commit at p=0.5"
    assert str(Stop(StopCode.REACHED)) == "p_end" and Stop(StopCode.REACHED).sentence(3) == "reached"
    assert Stop(StopCode.MAX_STEPS).sentence(12) == "the run stopped after 12 points"


def test_a_run_cut_short_by_max_steps_says_so():
    """The status of a run that used up its steps is MAX_STEPS, not REACHED."""
    problem, _ = fast_eigenvalue_through_a_cluster()
    branch = continuation(problem, np.zeros(4), 0.0, ContinuationParams(ds=0.01, ds_max=0.01, max_steps=3,
                                                                      p_max=0.4))
    assert branch.status == Stop(StopCode.MAX_STEPS) and len(branch) == 4 and str(branch.status) == "max_steps"


class Bisecting(Fast):
    """An added detector: the fast verdicts, but each event bracketed by bisection down to
    tol_p (no Newton locator), so its collisions come from StepScan.interpolated."""

    name = "bisecting"

    def resolve(self, scan, idx, verdict):
        scan.split(idx, 0.5 * (scan.samples[idx].s + scan.samples[idx + 1].s))
        return True


def test_a_detector_added_by_one_registry_entry_finds_the_collisions(monkeypatch):
    """Adding a detector is one class and one DETECTORS entry (docs/continuation.md): the
    scan drives it, and it brackets the bubble of a fast eigenvalue passing a cluster (steps
    250 times its width) to tol_p, where the fast detection's Newton locator puts it."""
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


def test_sparse_factorization_names_an_empty_row_or_column():
    """A sparse matrix with a row or column of no nonzero value (an explicitly stored zero
    included) is refused before SuperLU sees it, saying which; a full one factorizes."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import SingularMatrix, factorize

    full = np.array([[2.0, 1.0, 0.0], [0.0, 3.0, 1.0], [1.0, 0.0, 4.0]])
    assert np.allclose(factorize(sp.csc_array(full)).solve(np.ones(3)), np.linalg.solve(full, np.ones(3)))
    no_column = full.copy()
    no_column[:, 1] = 0.0
    with pytest.raises(SingularMatrix, match="empty column"):
        factorize(sp.csc_array(no_column))
    stored_zero = sp.csc_array(full)
    stored_zero.data[stored_zero.indices == 2] = 0.0  # row 2 stored, all zero
    with pytest.raises(SingularMatrix, match="empty row"):
        factorize(stored_zero)


def test_same_matrix_compares_values_whatever_the_pattern_stores():
    """linalg.same_matrix: a sparse matrix with an explicitly stored zero is the same as one
    without it; one value off by a rounding unit, another shape, or dense against sparse is
    not the same matrix."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import same_matrix

    full = np.array([[2.0, 1.0, 0.0], [0.0, 3.0, 1.0], [1.0, 0.0, 4.0]])
    stored = sp.csr_array((np.array([2.0, 1.0, 0.0, 3.0, 1.0, 1.0, 4.0]),
                           np.array([0, 1, 2, 1, 2, 0, 2]), np.array([0, 3, 5, 7])), shape=(3, 3))
    assert same_matrix(sp.csr_array(full), stored) and same_matrix(full, full.copy())
    off = full.copy()
    off[1, 1] = np.nextafter(3.0, 4.0)
    assert not same_matrix(sp.csr_array(full), sp.csr_array(off)) and not same_matrix(full, off)
    assert not same_matrix(full, full[:2]) and not same_matrix(full, sp.csr_array(full))


def test_segment_points_start_from_the_hermite_prediction():
    """On the circle u^2 + p^2 = 1 the point inside a step is predicted from the ends and their
    tangents to O(h^4) (the straight line: O(h^2)), lies on the hyperplane at s, and the
    corrected point is the branch point there (to rounding); a point solved later is predicted
    from the nearest solved points, so it starts closer still."""
    from diskfriction.continuation.stepping.newton import tangent
    from diskfriction.continuation.stepping.segment import Segment

    problem = FunctionProblem(G=lambda u, p: np.array([u[0] ** 2 + p ** 2 - 1.0]),
                              G_u=lambda u, p: np.array([[2.0 * u[0]]]), G_p=lambda u, p: np.array([2.0 * p]))

    def on_circle(angle):
        return np.array([np.cos(angle), np.sin(angle)])

    def segment(h, tangents=True):
        x_a, x_b = on_circle(0.3), on_circle(0.3 + h)
        t_a = tangent(problem, x_a, on_circle(0.3 + np.pi / 2))
        t_b = tangent(problem, x_b, t_a)
        return Segment(problem, x_a, x_b, 1e-14, 8, *((t_a, t_b) if tangents else (None, None)))

    def error(seg, s):  # distance of the prediction from the branch point on its hyperplane
        return np.linalg.norm(seg.predicted(s) - seg.point(s))

    for h in (0.2, 0.1):
        seg = segment(h)
        x = seg.point(0.37)
        assert abs(np.linalg.norm(x) - 1.0) < 1e-14
        assert abs(seg.sigma @ (seg.predicted(0.37) - seg.secant_point(0.37))) < 1e-15
    hermite = [error(segment(h), 0.37) for h in (0.2, 0.1)]
    line = [error(segment(h, tangents=False), 0.37) for h in (0.2, 0.1)]
    assert 12.0 < hermite[0] / hermite[1] < 20.0  # O(h^4): 16
    assert 3.0 < line[0] / line[1] < 5.0  # O(h^2): 4
    assert hermite[1] < 1e-2 * line[1]
    exact = segment(0.2).point(0.5)
    far = np.linalg.norm(segment(0.2).predicted(0.5) - exact)
    seg = segment(0.2)
    seg.point(0.499), seg.point(0.501)  # a bracket's points: no tangents, the line between them
    assert np.linalg.norm(seg.predicted(0.5) - exact) < 1e-2 * far


def test_stop_at_fold_sees_a_step_round_an_s_through_its_event():
    """p = u^3 - eps u is an S with folds at u = -+sqrt(eps / 3). The tracked matrix here is not
    dG/du (A = 1, as a packing's M^-1 J in a window may show no eigenvalue crossing 0), so only
    p and the tangent tell a fold. A long step from u = -0.01 lands on the upper branch (p and
    the tangent forward at both ends) and its first event (u = 0) lies on the middle branch,
    where p runs back: the step is halved like any step past a fold, and the run ends at the
    first fold (within ds_min), not at the event on the unstable branch."""
    from dataclasses import dataclass

    eps = 1e-6

    @dataclass(frozen=True)
    class WithEvent(FunctionProblem):
        def event_functions(self, u, p):
            return np.array([u[0]])

    problem = WithEvent(G=lambda u, p: np.array([u[0] ** 3 - eps * u[0] - p]),
                        G_u=lambda u, p: np.array([[3 * u[0] ** 2 - eps]]), G_p=lambda u, p: np.array([-1.0]),
                        A=lambda u, p: np.array([[1.0]]))
    par = ContinuationParams(ds=0.02, ds_min=1e-12, ds_max=0.02, newton_tol=1e-15, p_min=-1.0, p_max=1.0,
                             stop_at_fold=True)
    br = continuation(problem, np.array([-0.01]), -1e-6 + 1e-8, par)
    fold_u = -np.sqrt(eps / 3)
    assert br.status.code == StopCode.FOLD
    assert np.all(np.diff(br.p) >= 0) and np.all(br.u[:, 0] < fold_u)  # p is flat to rounding there
    assert abs(br.p[-1] - (fold_u ** 3 - eps * fold_u)) < 1e-12


@pytest.mark.parametrize("f, root, most", [(lambda s: np.exp(4.0 * s) - 2.0, np.log(2.0) / 4.0, 10),
                                           (lambda s: (s - 0.3) ** 3 + 0.05 * (s - 0.3), 0.3, 15)],
                         ids=["exp", "cubic"])
def test_a_sign_change_is_bracketed_to_1e_12_in_few_evaluations(f, root, most):
    """refine_sign_change on [0, 1]: the root stays inside a bracket shrunk to 1e-12, in at most
    10 (exp(4s) - 2) and 15 ((s - 0.3)^3 + 0.05 (s - 0.3)) evaluations, inverse quadratic
    interpolation against Illinois regula falsi's 23 and 20; with tol = 2.5e-13 (points kept
    that far from the ends) in no more."""
    for tol in (0.0, 2.5e-13):
        calls = []
        a, b = refine_sign_change(lambda s: calls.append(s) or f(s), 0.0, f(0.0), 1.0, f(1.0),
                                  lambda a, b: b - a <= 1e-12, tol=tol)
        assert a - 1e-16 <= root <= b + 1e-16 and b - a <= 1e-12 and len(calls) <= most


def test_segment_points_by_the_chord_method_match_newtons():
    """A segment with chord=True solves its later points with the factorization kept from the
    first (newton.chord_newton, no new LU), to the same points as Newton's within the
    tolerance; chord_newton gives up (None) with a factorization from too far away, where
    the Segment falls back to Newton."""
    from diskfriction.continuation.linalg.solves import factorize
    from diskfriction.continuation.stepping.newton import bordered_matrix, chord_newton
    from diskfriction.continuation.stepping.segment import Segment

    # G(u, p) = (u0^3 + u0 - p, u1 - sin(u0)): a curved branch u0(p)
    problem = FunctionProblem(G=lambda u, p: np.array([u[0] ** 3 + u[0] - p, u[1] - np.sin(u[0])]),
                              G_u=lambda u, p: np.array([[3 * u[0] ** 2 + 1, 0.0], [-np.cos(u[0]), 1.0]]),
                              G_p=lambda u, p: np.array([-1.0, 0.0]))

    def on_branch(u0):
        return np.array([u0, np.sin(u0), u0 ** 3 + u0])

    x_a, x_b = on_branch(0.2), on_branch(0.6)
    factorized = []
    original = factorize
    with pytest.MonkeyPatch.context() as mp:
        import diskfriction.continuation.linalg.solves as solves
        mp.setattr(solves, "factorize", lambda *a: factorized.append(1) or original(*a))
        chord = Segment(problem, x_a, x_b, 1e-12, 20, chord=True)
        plain = Segment(problem, x_a, x_b, 1e-12, 20)
        first = chord.point(0.5)
        after_first = len(factorized)
        points = [chord.point(s) for s in (0.499, 0.5015, 0.4995)]
        assert len(factorized) == after_first  # the kept factorization served them all
        for s, x in zip((0.499, 0.5015, 0.4995), points):
            assert np.abs(problem.residual(x[:-1], x[-1])).max() <= 1e-12
            assert np.allclose(x, plain.point(s), rtol=0.0, atol=1e-11)
    assert np.allclose(first, plain.point(0.5), rtol=0.0, atol=1e-11)
    sigma = chord.sigma
    far = factorize(bordered_matrix(problem, on_branch(3.0), sigma))
    target = x_a + 0.5 * (x_b - x_a)
    assert chord_newton(problem, target, sigma, 1e-12, far, target) is None
    near = factorize(bordered_matrix(problem, first, sigma))
    assert chord_newton(problem, target, sigma, 1e-12, near, target).converged


def test_tangents_refined_on_a_nearby_factorization_match_fresh_ones(monkeypatch):
    """newton.tangent with near = (an LU of the bordered matrix at a point nearby, its border):
    on a sparse problem the tangent is refined on it, with the border changed by
    Sherman-Morrison, without a factorization, and equals a fresh one's to 1e-14; an LU from
    far away (or a dense one) falls back to a factorization, with the same tangent."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg import solves as linalg
    from diskfriction.continuation.stepping.newton import bordered_matrix, tangent

    problem = FunctionProblem(G=lambda u, p: np.array([u[0] ** 3 + u[0] - p, u[1] - np.sin(u[0])]),
                              G_u=lambda u, p: sp.csr_array([[3 * u[0] ** 2 + 1, 0.0], [-np.cos(u[0]), 1.0]]),
                              G_p=lambda u, p: np.array([-1.0, 0.0]))

    def on_branch(u0):
        return np.array([u0, np.sin(u0), u0 ** 3 + u0])

    x, sigma = on_branch(0.5), np.array([0.6, 0.0, 0.8])
    fresh = tangent(problem, x, sigma)
    previous = fresh + np.array([0.01, -0.02, 0.0])
    fresh_previous = tangent(problem, x, previous)
    factorized, original = [], linalg.factorize
    monkeypatch.setattr(linalg, "factorize", lambda *a: factorized.append(1) or original(*a))
    near = (original(bordered_matrix(problem, on_branch(0.5 + 1e-7), sigma)), sigma)
    for border, expected in ((sigma, fresh), (previous, fresh_previous)):
        assert np.allclose(tangent(problem, x, border, near), expected, rtol=0.0, atol=1e-14)
    assert factorized == []
    far = (original(bordered_matrix(problem, on_branch(3.0), sigma)), sigma)
    assert np.allclose(tangent(problem, x, sigma, far), fresh, rtol=0.0, atol=1e-14)
    dense = (original(bordered_matrix(problem, on_branch(0.5 + 1e-7), sigma).toarray()), sigma)
    assert np.allclose(tangent(problem, x, sigma, dense), fresh, rtol=0.0, atol=1e-14)
    assert len(factorized) == 2


def test_solve_near_refines_to_a_fresh_solve_or_gives_up():
    """linalg.solve_near on the LU of a matrix 1e-8 away reaches the fresh solve to 1e-13 in
    a few corrections, for M and for M^T; on one 10 % away it gives up (None) after one."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import factorize, solve_near

    rng = np.random.default_rng(7)
    M = sp.random_array((60, 60), density=0.1, random_state=rng) + 4.0 * sp.eye_array(60)
    M = sp.csr_array(M)
    r = rng.standard_normal(60)
    exact, exact_t = np.linalg.solve(M.toarray(), r), np.linalg.solve(M.toarray().T, r)
    E = sp.random_array((60, 60), density=0.1, random_state=rng)
    near = factorize(M + 1e-8 * E)
    assert np.allclose(solve_near(near, lambda y: M @ y, r), exact, rtol=0.0, atol=1e-13)
    assert np.allclose(solve_near(near, lambda y: M.T @ y, r, transpose=True), exact_t, rtol=0.0, atol=1e-13)
    far = factorize(M + 0.4 * E)
    assert solve_near(far, lambda y: M @ y, r) is None


def test_bordered_sparse_matrix_is_canonical_and_keeps_stored_zeros():
    """linalg.bordered of a sparse K (CSR or CSC, with duplicate entries and a stored zero):
    [[K, c], [b^T, d]] in CSC with sorted row indices, duplicates summed, the stored zero and
    every border entry kept (the pattern depends on K's pattern alone)."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import bordered

    rows, cols = np.array([0, 2, 2, 1, 0, 3, 1]), np.array([1, 0, 0, 3, 1, 2, 1])
    values = np.array([1.0, 2.0, 3.0, 0.0, 4.0, 5.0, 6.0])
    c, b = np.array([1.0, 0.0, 2.0, 3.0]), np.array([0.5, 0.0, -1.0, 2.0])
    expected = np.zeros((5, 5))
    np.add.at(expected, (rows, cols), values)
    expected[:4, 4], expected[4, :4], expected[4, 4] = c, b, 7.0
    order = np.lexsort((cols, rows))  # CSR arrays as given, the duplicates (2, 0) unsummed
    raw = sp.csr_array((values[order], cols[order], np.searchsorted(rows[order], np.arange(5))),
                       shape=(4, 4))
    assert raw.nnz == 7
    for K in (raw, sp.coo_array((values, (rows, cols)), shape=(4, 4)).asformat("csc")):
        M = bordered(K, c, b, 7.0)
        assert M.format == "csc" and np.array_equal(M.toarray(), expected)
        for j in range(5):
            column = M.indices[M.indptr[j]:M.indptr[j + 1]]
            assert np.all(np.diff(column) > 0)
        assert M.nnz == 5 + 4 + 5  # K's 5 positions (the stored zero too), b's 4, [c; d]


def test_heap_kept_reuses_freed_memory():
    """Inside linalg.heap_kept (the continuation runs in it) a large array freed and allocated
    again reuses the process's memory: no page faults, where glibc's default unmaps it and the
    kernel hands out fresh (zeroed) pages; nested contexts restore the default only at the
    outermost exit."""
    import resource

    from diskfriction.continuation.linalg import solves as linalg

    if linalg._glibc() is None:
        pytest.skip("the C library is not glibc: heap_kept changes nothing")

    def faults_of_a_second_allocation() -> int:
        a = np.ones(8 << 20)  # 64 MB, above glibc's largest mmap threshold (32 MiB)
        del a
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        a = np.ones(8 << 20)
        del a
        return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

    with linalg.heap_kept():
        with linalg.heap_kept():
            kept = faults_of_a_second_allocation()
        assert linalg._kept[0] == 1
    assert linalg._kept[0] == 0
    default = faults_of_a_second_allocation()
    assert kept < 16 <= default, (kept, default)


def test_spilled_files_are_reused_in_place_but_never_under_a_live_mapping():
    """Inside spill.files_kept (the continuation runs in it) the file of a spilled array whose
    views are all gone is overwritten by the next spill (the same file, new values), while a
    mapping still alive keeps its values; a file still mapped when the process forks is closed,
    not reused, so the child's inherited view keeps its values while the parent spills on;
    leaving the context closes the idle files, and outside it nothing is kept."""
    import os

    from diskfriction.continuation.detection import spill

    if not hasattr(os, "fork"):
        pytest.skip("no fork on this platform")
    a = np.arange(24.0).reshape(4, 6) * (1 + 1j)
    with spill.files_kept():
        x = spill.on_disk(a)
        y = spill.on_disk(2 * a)
        view = x[:, 2]
        del x
        assert spill._idle == []  # a view keeps the mapping
        del view
        assert len(spill._idle) == 1
        idle = spill._idle[0]
        z = spill.on_disk(3 * a)  # into x's file
        assert spill._idle == [] and np.array_equal(z, 3 * a) and np.array_equal(y, 2 * a)
        del z
        assert spill._idle == [idle]

        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child holds y's inherited mapping while the parent spills over
            os.close(write)
            os.read(read, 1)
            os._exit(0 if np.array_equal(y, 2 * a) and spill._idle == [] else 1)
        os.close(read)
        del y  # mapped before the fork: closed, not kept
        assert len(spill._idle) == 1
        w = [spill.on_disk(k * a) for k in (5, 6)]
        os.write(write, b"x")
        os.close(write)
        assert os.waitpid(pid, 0)[1] == 0
        assert np.array_equal(w[0], 5 * a) and np.array_equal(w[1], 6 * a)
        del w
        assert len(spill._idle) == 2
        u = spill.on_disk(np.arange(5.0))  # an idle file of another size, cut to this one
        assert np.array_equal(u, np.arange(5.0)) and len(spill._idle) == 1
    assert spill._idle == [] and spill._kept[0] == 0
    x = spill.on_disk(a)
    del x
    assert spill._idle == []
