"""solve_branch in any units (issue 60 item 16): the same problem with G or p in other units
takes the same steps and locates the same points: newton_tol relative to the size of G at the
start (Options.residual_scale, at most 1), steps in p relative to Options.p_scale (the span),
tolerances in p relative to it where it is below 1 and no finer than p resolves where p is
large."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import fsolve

from diskfriction.continuation import Options, ProblemError, problem_from_functions, solve_branch

N = 20
"""Interior points of the Bratu mesh: h = 1 / 21, terms of G up to 4 |u| / h^2 ~ 2e3 |u|."""
SPAN = (0.01, 4.0)
"""lambda from 0.01 over the fold (3.5) and back to 0.01."""


def laplacian(n: int):
    return sp.diags([np.ones(n - 1), -2.0 * np.ones(n), np.ones(n - 1)], [-1, 0, 1],
                    format="csr") * (n + 1) ** 2


def bratu(g_unit: float = 1.0, p_unit: float = 1.0, n: int = N):
    """Bratu's u'' + lambda e^u = 0 on n points with G in units g_unit and the parameter
    P = p_unit lambda: G(u, P) = g_unit (L u + (P / p_unit) e^u)."""
    L = laplacian(n)
    return problem_from_functions(
        lambda u, P: g_unit * (L @ u + (P / p_unit) * np.exp(u)),
        dG_du=lambda u, P: (g_unit * (L + sp.diags((P / p_unit) * np.exp(u)))).tocsr(),
        dG_dp=lambda u, P: (g_unit / p_unit) * np.exp(u))


def solved(g_unit: float = 1.0, p_unit: float = 1.0, **options):
    span = (SPAN[0] * p_unit, SPAN[1] * p_unit)
    options = {"special_points": ("fold",), "max_steps": 1000} | options
    return solve_branch(bratu(g_unit, p_unit), np.zeros(N), span, Options(**options))


@pytest.fixture(scope="module")
def reference():
    """The run in the problem's own units, and its fold checked against an independent solve
    of G = 0, G_u v = 0, |v| = 1."""
    result = solved()
    (fold,) = result.folds
    L = laplacian(N)

    def extended(z):
        u, v, lam = z[:N], z[N:2 * N], z[-1]
        J = L + sp.diags(lam * np.exp(u))
        return np.concatenate([L @ u + lam * np.exp(u), J @ v, [v @ v - 1.0]])

    v0 = np.sin(np.pi * np.arange(1, N + 1) / (N + 1))
    z = fsolve(extended, np.concatenate([fold.u, v0 / np.linalg.norm(v0), [fold.p]]), xtol=1e-14)
    assert np.abs(extended(z)).max() <= 1e-8 and 3.4 < z[-1] < 3.6
    assert fold.p == pytest.approx(z[-1], rel=1e-10)
    return result


@pytest.mark.parametrize("g_unit, p_unit", [(1e-10, 1.0), (1.0, 1e4), (1.0, 1e6), (1.0, 1e-6),
                                            (1e8, 1e-6)],
                         ids=["G 1e-10", "p 1e4", "p 1e6", "p 1e-6", "G 1e8, p 1e-6"])
@pytest.mark.slow
def test_bratu_in_other_units_takes_the_same_steps_to_the_same_fold(reference, g_unit, p_unit):
    """G scaled by 1e-10 put the fold 1.7e-3 off; p in units 1e4 and 1e6 times larger stopped
    at the fold (ds_min) with none reported; 1e-6 times ran out of steps before it."""
    result = solved(g_unit, p_unit)
    assert result.branch.status.code == reference.branch.status.code and result.warnings == ()
    assert result.branch.status.p / p_unit == pytest.approx(reference.branch.status.p, rel=1e-12)
    assert len(result.p) == len(reference.p)
    assert result.p_scale == pytest.approx(reference.p_scale * p_unit, rel=1e-15)
    assert result.residual_scale == pytest.approx(min(1.0, reference.residual_scale * g_unit),
                                                  rel=1e-12)
    (fold,) = result.folds
    assert fold.p / p_unit == pytest.approx(reference.folds[0].p, rel=1e-9)
    assert np.allclose(fold.u, reference.folds[0].u, rtol=1e-7, atol=1e-9)
    assert np.allclose(result.p / p_unit, reference.p, rtol=1e-7, atol=0.0)
    assert np.abs(result.branch.residual / g_unit).max() <= 10 * reference.branch.residual.max()


def ziegler(p_unit: float):
    """Ziegler's pendulum (docs/api.md) with the follower force P in units p_unit times k/l."""
    M = np.array([[3.0, 1.0], [1.0, 1.0]])

    def K(P):
        return np.array([[2.0 - P / p_unit, P / p_unit - 1.0], [-1.0, 1.0]])

    return problem_from_functions(
        lambda u, P: K(P) @ u, dG_du=lambda u, P: K(P),
        dG_dp=lambda u, P: np.array([[-1.0, 1.0], [0.0, 0.0]]) @ u / p_unit,
        A=lambda u, P: np.linalg.solve(M, K(P)))


@pytest.mark.parametrize("p_unit", [1e-6, 1.0, 1e4, 1e6, 1e10])
def test_ziegler_s_collisions_in_any_units_of_the_force(p_unit):
    """The collisions at 7/2 -+ sqrt 2 in any units of P: with tol_p = 1e-10 absolute, P in
    units 1e4 times larger took 90 locator warnings, 1e6 and 1e10 times ended the run ("the
    branch jumps": the locator's |dp| <= 1e-12 is below what p resolves at 2e6)."""
    result = solve_branch(ziegler(p_unit), np.zeros(2), (0.0, 6.0 * p_unit),
                          Options(ds_max=0.2 * p_unit, special_points=("fold",)))
    assert result.success and result.warnings == () and len(result.p) == 33
    exact = [3.5 - np.sqrt(2.0), 3.5 + np.sqrt(2.0)]
    assert [c.kind for c in result.collisions] == ["birth", "death"]
    assert [c.p / p_unit for c in result.collisions] == pytest.approx(exact, rel=1e-14)


def test_given_scales_are_used_as_given():
    """residual_scale = p_scale = 1: newton_tol in the units of G, steps in the Euclidean
    (theta / n) |du|^2 + dp^2 of the problem's own units (the disk sweeps' and shears')."""
    result = solved(p_unit=1e-6, residual_scale=1.0, p_scale=1.0, max_steps=50)
    assert result.residual_scale == 1.0 and result.p_scale == 1.0
    assert result.message == "max_steps" and not result.folds  # p in 1e-6 units crawls


def test_a_start_where_g_has_no_size_says_which_option_to_set():
    """dG/du and dG/dp both 0 at the start: no size of G to measure newton_tol against."""
    flat = problem_from_functions(lambda u, p: u ** 2 - p ** 2, dG_du=lambda u, p: np.diag(2 * u),
                                  dG_dp=lambda u, p: -2 * p * np.ones(1))
    with pytest.raises(ProblemError) as error:
        solve_branch(flat, np.zeros(1), (0.0, 1.0))
    line = str(error.value)
    assert "\n" not in line and "Options(residual_scale=...)" in line


@pytest.mark.parametrize("name", ["p_scale", "residual_scale"])
@pytest.mark.parametrize("value", [0.0, -1.0, float("nan"), float("inf")])
def test_scales_must_be_positive_numbers(name, value):
    with pytest.raises(ValueError, match=f"{name} must be a finite number > 0"):
        Options(**{name: value})
