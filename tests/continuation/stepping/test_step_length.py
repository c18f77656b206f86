"""solve_branch on discretised problems (issue 27 items 3-4): steps in the weighted arclength
(theta / n)|du|^2 + dp^2, so that the step count does not grow with n, and a residual at the
rounding of G's terms converged (Bratu's u'' + lambda e^u, entries 1/h^2)."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import fsolve

from diskfriction.continuation import Options, problem_from_functions, solve_branch
from diskfriction.continuation.branch import StopCode
from gallery import load_example


def line(n: int):
    """u = p on n unknowns: a straight branch."""
    return problem_from_functions(lambda u, p: u - p, dG_du=lambda u, p: sp.eye(n, format="csr"),
                                  dG_dp=lambda u, p: -np.ones(n))


@pytest.mark.slow
def test_a_straight_branch_takes_as_many_steps_on_any_mesh():
    # n = 10 and 40 suffice (a mesh 4x finer, as 20 and 80 were): 74 weighted steps on both,
    # 169 and 324 Euclidean ones (ratio 1.92; 233 and 453 at 20, 80), and n = 80 alone took 2.3 s
    weighted = [len(solve_branch(line(n), np.zeros(n), (0.0, 1.0)).p) for n in (10, 40)]
    euclidean = [len(solve_branch(line(n), np.zeros(n), (0.0, 1.0), Options(theta=None)).p)
                 for n in (10, 40)]
    assert weighted[0] == weighted[1] <= 80  # |dx| = sqrt(2) dp: about 50 sqrt(2) steps
    assert euclidean[1] > 1.8 * euclidean[0]  # ~ sqrt(n)


@pytest.mark.slow
def test_bratu_fold_is_located_though_g_rounds_above_the_tolerance():
    """examples/bratu.py, n = 50: terms of G up to 3e3 |u| round to ~1e-12, where the fold's
    locator asks 1e-12; the fold against an independent solve of G = 0, J v = 0, |v| = 1."""
    n = 50
    spec = load_example("bratu").bratu(n)
    G, J = spec.problem.G, spec.problem.G_u
    result = solve_branch(spec.problem, spec.u0, spec.p_span, spec.options)
    assert result.warnings == () and result.p[-1] <= 0.01 < 3.5 < result.p.max()  # and back
    (fold,) = result.folds

    def extended(z):
        u, v, lam = z[:n], z[n:2 * n], z[-1]
        return np.concatenate([G(u, lam), J(u, lam) @ v, [v @ v - 1.0]])

    v0 = np.sin(np.pi * np.arange(1, n + 1) / (n + 1))
    z = fsolve(extended, np.concatenate([fold.u, v0 / np.linalg.norm(v0), [fold.p]]), xtol=1e-14)
    assert np.abs(extended(z)).max() <= 1e-8 and 3.5 < z[-1] < 3.52
    assert fold.p == pytest.approx(z[-1], abs=1e-10)


@pytest.mark.slow
def test_a_problem_without_rounding_says_when_its_tolerance_is_below_g_s_rounding():
    """The same Bratu problem with rounding 0 (a Problem subclass's default): newton_tol is
    relative to G's size at the start (lambda = 0.01: max|G| <= 1e-12), which G's terms of 3e3
    |u| near the fold round above; the corrector stalls there, and the run's status says the
    residual is at G's rounding. With newton_tol absolute (residual_scale 1) the branch passes
    the fold and the fold's locator (1e-12) stalls instead, and its warning says so."""
    from diskfriction.continuation.problem import FunctionProblem

    class Absolute(FunctionProblem):
        rounding = 0.0

    spec = load_example("bratu").bratu(50)
    f = spec.problem
    result = solve_branch(Absolute(f.G, f.G_u, f.G_p), spec.u0, spec.p_span, spec.options)
    assert result.folds == () and result.branch.status.code is StopCode.DS_MIN
    assert "at the rounding of G's terms there" in result.message
    absolute = replace(spec.options, residual_scale=1.0, p_scale=1.0)
    result = solve_branch(Absolute(f.G, f.G_u, f.G_p), spec.u0, spec.p_span, absolute)
    assert result.folds == () and len(result.warnings) == 1
    assert "at the rounding of G's terms there" in result.warnings[0]
