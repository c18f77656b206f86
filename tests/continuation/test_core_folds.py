"""The continuation core at folds and Hopf points, on problems with known answers: a fold
passed and located, a run that stops at a fold, and the Brusselator's Hopf point and collisions
(tests/core_problems.py)."""
from __future__ import annotations

import numpy as np
import pytest
from core_problems import TOL_P, brusselator, located, run

from diskfriction.continuation import ContinuationParams, FunctionProblem, continuation
from diskfriction.continuation.branch import StopCode
from diskfriction.continuation.detection.bifurcations import locate_folds, locate_hopf


def test_fold_of_scalar_equation_is_passed_and_located():
    """G = u^2 + p from (u, p) = (1, -1): the branch turns at the fold (0, 0) and lands on
    p = -1 again at u = -1, the side it started from, short of p_max = 1: its status says it
    turned back, not that it reached p_end. Fold located to |x - x_fold| <= 1e-9, on the
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
