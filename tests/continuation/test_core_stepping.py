"""Stepping along a branch (continuation/stepping/): commits and the state they change, the
checks at the door, a run's status, the points inside a step (Hermite prediction, chord
method), sign changes bracketed, and tangents refined on a nearby factorization."""
from __future__ import annotations

import numpy as np
import pytest
from core_problems import P0, blocks_family, fast_eigenvalue_through_a_cluster, run

from diskfriction.continuation import ContinuationParams, DetectionParams, FunctionProblem, continuation
from diskfriction.continuation.branch import Stop, StopCode
from diskfriction.continuation.stepping.segment import refine_sign_change


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


def test_a_stop_prints_its_status_line_and_says_its_reason_without_the_location():
    """Branch.status is a Stop: str() is its status line (MESSAGES: the code, the reason and
    where the run ended), sentence() the reason alone, without the location."""
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
