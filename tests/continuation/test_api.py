"""The public front end (continuation/api.py): problems from callables and from sympy, missing
derivatives by differences, validation at the door, and the result object."""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import sympy as sp

from diskfriction.continuation import (DerivativeWarning, Options, ProblemError, check_problem,
                                       problem_from_functions, problem_from_sympy, solve_branch)
from diskfriction.continuation.stepping.differences import ParameterDerivative, StateDerivative

from gallery import load_example


def exact_derivatives(u, p):
    """f(u, p) = (sin(u0) u1 + p u0^2, exp(p u1) - u0) and its exact dG/du, dG/dp."""
    f = np.array([np.sin(u[0]) * u[1] + p * u[0] ** 2, np.exp(p * u[1]) - u[0]])
    J = np.array([[np.cos(u[0]) * u[1] + 2 * p * u[0], np.sin(u[0])], [-1.0, p * np.exp(p * u[1])]])
    return f, J, np.array([u[0] ** 2, u[1] * np.exp(p * u[1])])


@pytest.mark.parametrize("method, tol", [("central", 1e-12), ("complex-step", 1e-15)])
def test_differences_match_exact_derivatives_to_their_stated_accuracy(method, tol):
    """Fourth-order central differences: ~eps^(4/5) = 3e-13 relative; complex step: rounding."""
    G = lambda u, p: exact_derivatives(u, p)[0]  # noqa: E731
    rng = np.random.default_rng(3)
    for _ in range(5):
        u, p = rng.uniform(-1.5, 1.5, 2), float(rng.uniform(-1, 1))
        _, J, G_p = exact_derivatives(u, p)
        assert np.max(np.abs(StateDerivative(G, method)(u, p) - J)) <= tol * np.max(np.abs(J))
        assert np.max(np.abs(ParameterDerivative(G, method)(u, p) - G_p)) <= tol * max(1.0, np.max(np.abs(G_p)))


@pytest.mark.parametrize("method", ["central", "complex-step"])
def test_problem_without_derivatives_reaches_the_same_collisions_folds_and_hopf_points(method):
    """FitzHugh-Nagumo (examples/fitzhugh_nagumo.py), its tracked matrix the Jacobian: given
    without dG/du and dG/dp (one DerivativeWarning), the same 4 collisions, 2 folds and 2 Hopf
    points as with them, within the documented accuracy (1e-12 relative, all are O(1))."""
    fhn = load_example("fitzhugh_nagumo")
    exact = fhn.fitzhugh_nagumo().solve()
    with pytest.warns(DerivativeWarning, match=f"dG/du and dG/dp not given: computed by {method}"):
        problem = problem_from_functions(fhn.G, differences=method)
    spec = fhn.fitzhugh_nagumo()
    differenced = solve_branch(problem, spec.start(spec.p_span[0]), spec.p_span)
    assert differenced.success and not differenced.warnings
    assert [c.kind for c in differenced.collisions] == [c.kind for c in exact.collisions]
    assert len(exact.collisions) == 4 and len(exact.folds) == 2 and len(exact.hopf) == 2
    for mine, theirs in ((differenced.collisions, exact.collisions), (differenced.folds, exact.folds),
                         (differenced.hopf, exact.hopf)):
        assert [x.p for x in mine] == pytest.approx([x.p for x in theirs], abs=1e-12)


def test_complex_step_is_refused_for_a_function_that_drops_the_imaginary_part():
    """abs() is not complex-analytic: the complex step would silently give a wrong dG/du."""
    G = lambda u, p: np.array([abs(u[0]) + p * u[1], u[1] - 1.0])  # noqa: E731
    with pytest.warns(DerivativeWarning):
        problem = problem_from_functions(G, differences="complex-step")
    with pytest.raises(ProblemError, match="complex step"):
        check_problem(problem, np.array([-0.5, 1.0]), 0.3)


@pytest.mark.parametrize("G, dG_du, A, message", [
    (lambda u, p: np.zeros(3), None, None, r"G\(u, p\) returned shape \(3,\), expected \(2,\)"),
    (lambda u, p: u, lambda u, p: np.eye(3), None, r"dG/du returned shape \(3, 3\), expected \(2, 2\)"),
    (lambda u, p: u, lambda u, p: np.eye(2), lambda u, p: np.ones((2, 3)), r"tracked matrix A returned shape \(2, 3\), expected square"),
    (lambda u, p: u / 0.0, lambda u, p: np.eye(2), None, "G\\(u, p\\) returned non-finite values"),
    (lambda u, p: u[5], lambda u, p: np.eye(2), None, "G\\(u, p\\) raised IndexError at p = 0"),
])
def test_check_problem_names_what_is_wrong_in_one_line(G, dG_du, A, message):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        problem = problem_from_functions(G, dG_du=dG_du, dG_dp=lambda u, p: np.zeros(2), A=A)
        with pytest.raises(ProblemError, match=message) as info:
            check_problem(problem, np.array([1.0, 0.0]), 0.0)
    assert "\n" not in str(info.value) and info.value.exit_code == 2


def test_span_and_options_are_validated_at_the_door():
    problem = problem_from_functions(lambda u, p: u - p, dG_du=lambda u, p: np.eye(1),
                                     dG_dp=lambda u, p: -np.ones(1))
    for span in [(1.0, 1.0), (0.0, np.inf), "ab", (0.0,)]:
        with pytest.raises(ValueError, match="p_span"):
            solve_branch(problem, np.zeros(1), span)
    for bad in [dict(ds_max=0.0), dict(ds=-1.0), dict(newton_tol=np.nan), dict(special_points=("cusp",))]:
        with pytest.raises(ValueError):
            Options(**bad)
    with pytest.raises(ProblemError, match="u0 must be a non-empty 1-D array"):
        solve_branch(problem, np.zeros((1, 1)), (0.0, 1.0))


def test_a_reversed_span_follows_the_branch_downwards_with_kinds_reversed():
    """Ziegler from P = 6 down to 0: going down, the complex window (7/2 -+ sqrt 2) k/l is
    entered at 7/2 + sqrt 2 (a birth in the branch's direction) and left at 7/2 - sqrt 2."""
    spec = load_example("ziegler").problem
    down = spec.solve((6.0, 0.0))
    assert down.success and down.p[0] == 6.0 and down.p[-1] == 0.0
    assert [(c.kind, c.p) for c in down.collisions] == [
        ("birth", pytest.approx(3.5 + np.sqrt(2), abs=1e-10)),
        ("death", pytest.approx(3.5 - np.sqrt(2), abs=1e-10))]


def test_sympy_kernels_equal_the_expressions_and_one_module_serves_every_constant(tmp_path, monkeypatch):
    """A problem with a constant named like a Python keyword: the generated functions equal
    sympy's lambdified expressions at random points; other constant values reuse the cached
    module (one file, with its hash in the header); a symbol without a value is refused."""
    monkeypatch.setenv("DISKFRICTION_CACHE", str(tmp_path))
    x, y, p, lam = sp.symbols("x y p lambda")
    G = [sp.sin(x) * y - p * lam, x**2 + sp.exp(y) / lam - p]
    A = sp.Matrix([[x, lam * y], [p, sp.sqrt(1 + x**2)]])
    exact = [sp.lambdify((x, y, p, lam), e) for e in
             (sp.Matrix(G), sp.Matrix(G).jacobian([x, y]), sp.Matrix(G).diff(p), A)]
    rng = np.random.default_rng(0)
    for value in (2.0, 3.5):
        problem = problem_from_sympy(G, [x, y], p, A=A, values={lam: value})
        for _ in range(3):
            u, q = rng.uniform(-1, 1, 2), float(rng.uniform(-1, 1))
            got = (problem.residual(u, q), problem.jacobian(u, q), problem.dG_dp(u, q),
                   problem.stability_matrix(u, q))
            for mine, f in zip(got, exact):
                assert np.allclose(mine, np.array(f(*u, q, value), dtype=float).reshape(mine.shape),
                                   rtol=1e-14, atol=1e-14)
    modules = list((tmp_path / "kernels").glob("problem_*.py"))
    assert len(modules) == 1 and "hash: " + modules[0].stem.split("_")[1] in modules[0].read_text()
    with pytest.raises(ValueError, match="no value given for the symbols lambda"):
        problem_from_sympy(G, [x, y], p)


@pytest.mark.parametrize("hook", ["eigensystem", "stability_blocks", "widen_window"])
def test_a_problem_defining_a_removed_hook_is_refused_in_one_line(hook):
    """A subclass written for the hooks Problem had (the core no longer calls them) would have
    them silently ignored: check_problem names the hook and what does its work now."""
    base = problem_from_functions(lambda u, p: u - p, A=lambda u, p: np.eye(1))
    Old = type("Old", (type(base),), {hook: lambda self, *args: None})
    old = Old.__new__(Old)
    old.__dict__.update(base.__dict__)
    with pytest.raises(ProblemError, match=rf"^Old\.{hook}: a Problem no longer has this hook.*docs/api\.md\)$"):
        check_problem(old, np.array([0.0]), 0.0)
    check_problem(base, np.array([0.0]), 0.0)  # the same problem without the hook passes
