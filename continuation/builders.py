"""Problems from plain callables or sympy expressions, and the checks a problem passes at the
door of solve_branch (api.py, the front end).

problem_from_functions(G, dG_du=..., dG_dp=..., A=...) builds a FunctionProblem from callables
of (u, p), the missing derivatives by differences (differences.py); problem_from_sympy(G, u, p,
A=...) from sympy expressions, compiled to cached numba kernels (symbolic/problems.py).
check_problem evaluates a problem once at the start and says in one line (ProblemError) what is
wrong with it: a function that raises, a shape, a non-finite value.
"""
from __future__ import annotations

import math
from typing import Callable, Mapping, Optional, Sequence

import numpy as np
import scipy.sparse as sp

from diskfriction.continuation.problem import FunctionProblem, Problem
from diskfriction.continuation.stepping.differences import (METHODS, ParameterDerivative, StateDerivative, check_complex_step,
                                                            warn_differences)
from diskfriction.errors import OneLineError

Array = np.ndarray
Function = Callable[[Array, float], Array]


class ProblemError(OneLineError):
    """A problem that cannot be continued as given (a function fails, returns the wrong shape
    or non-finite values at the start): one line naming what is wrong, exit code 2."""

    exit_code = 2


def problem_from_functions(G: Function, *, dG_du: Optional[Function] = None,
                           dG_dp: Optional[Function] = None, A: Optional[Function] = None,
                           differences: str = "central") -> FunctionProblem:
    """The problem G(u, p) = 0 from plain callables of (u, p): u a float array (n,), p a float.

    G -> (n,); dG_du -> (n, n); dG_dp -> (n,); A -> (m, m), the matrix whose spectrum is
    tracked (e.g. M^-1 K(p) for M u'' + K(p) u = 0; default dG/du). A missing dG_du or dG_dp
    is computed by `differences` ("central" or "complex-step", continuation/stepping/differences.py)
    and a DerivativeWarning states its accuracy."""
    if differences not in METHODS:
        raise ValueError(f"differences must be one of {METHODS}, got {differences!r}")
    missing = [name for name, f in (("dG/du", dG_du), ("dG/dp", dG_dp)) if f is None]
    warn_differences(missing, differences)
    return FunctionProblem(G, dG_du or StateDerivative(G, differences),
                           dG_dp or ParameterDerivative(G, differences), A)


def problem_from_sympy(G: Sequence, u: Sequence, p, *, A=None,
                       values: Optional[Mapping] = None) -> FunctionProblem:
    """The problem G(u, p) = 0 from sympy expressions: G a sequence of n expressions in the
    symbols u (n of them), p and the constants given in `values` ({symbol: number}); A an
    m x m sympy Matrix of the tracked matrix (default dG/du). dG/du and dG/dp are derived
    exactly; every function is printed after cse as a numba kernel of a module cached by the
    hash of the expressions (symbolic/problems.py), so the second run compiles nothing."""
    from diskfriction.symbolic.problems import compile_problem

    kernels = compile_problem(G, u, p, A, values or {})
    return FunctionProblem(kernels.residual, kernels.jacobian, kernels.dG_dp, kernels.stability)


def span_of(p_span) -> tuple[float, float]:
    """(p_start, p_stop): two finite, different numbers."""
    try:
        a, b = (float(v) for v in p_span)
    except (TypeError, ValueError):
        raise ValueError(f"p_span must be two numbers (p_start, p_stop), got {p_span!r}") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a == b:
        raise ValueError(f"p_span must be two finite, different numbers, got {p_span!r}")
    return a, b


def evaluated(what: str, call: Callable[[], object], p: float):
    """call(), or a ProblemError naming `what` and the exception it raised."""
    try:
        return call()
    except Exception as error:  # noqa: BLE001 - the user's code may raise anything
        line = (str(error).splitlines() or [""])[0]
        raise ProblemError(f"{what} raised {type(error).__name__} at p = {p:g}: {line}") from None


def _check_matrix(what: str, M, rows: int) -> None:
    """A square (rows x rows; any size if rows < 0) dense or sparse matrix of finite numbers."""
    shape = tuple(np.shape(M))
    if len(shape) != 2 or shape[0] != shape[1] or (rows >= 0 and shape[0] != rows):
        need = f"({rows}, {rows})" if rows >= 0 else "square"
        raise ProblemError(f"{what} returned shape {shape}, expected {need}")
    if not np.all(np.isfinite(M.data if sp.issparse(M) else np.asarray(M))):
        raise ProblemError(f"{what} returned non-finite values")


REMOVED_HOOKS = {
    "eigensystem": "Options(eigensolver=DenseSpectra() | RefinedSpectra() | SpectralWindow(...))",
    "spectrum": "Options(eigensolver=...)",
    "dense_spectra": "Options(eigensolver=DenseSpectra(device))",
    "widen_window": "Options(eigensolver=SpectralWindow(lo, hi, ...)); solve_in_runs widens a crowded one",
    "stability_blocks": "stability_structure(u, p) -> StructuredMatrix(A, block_size=...)",
    "spectrum_matrix": "stability_structure(u, p) -> a StructuredMatrix subclass whose spectrum_matrix property gives it",
    "deflated": "stability_structure(u, p) -> StructuredMatrix(A, deflated=...)",
    "factor_options": "Options(linear_solver=LinearSolver(ordering))",
}
"""Hooks a Problem no longer has, and what does their work now (docs/api.md): a subclass that
still defines one is refused, since the core would silently ignore it."""


def check_problem(problem: Problem, u0, p: float) -> Array:
    """u0 as a float array, after checking the problem at (u0, p): no hook the core no longer
    calls (REMOVED_HOOKS), G -> (n,), dG/du -> (n, n), dG/dp -> (n,), the tracked matrix
    square, all finite, n = u0.size, and derivatives by the complex step valid for G
    (differences.check_complex_step). Else a ProblemError."""
    for name, instead in REMOVED_HOOKS.items():
        if any(name in vars(cls) for cls in type(problem).__mro__ if cls is not Problem):
            raise ProblemError(f"{type(problem).__name__}.{name}: a Problem no longer has this hook "
                               f"and the core would ignore it; use {instead} (docs/api.md)")
    try:
        u0 = np.asarray(u0, dtype=float)
    except (TypeError, ValueError):
        raise ProblemError(f"u0 is not an array of numbers (got {type(u0).__name__})") from None
    if u0.ndim != 1 or u0.size == 0 or not np.all(np.isfinite(u0)):
        raise ProblemError(f"u0 must be a non-empty 1-D array of finite numbers (got shape {u0.shape})")
    n = u0.size
    for what, f, shape in (("G(u, p)", problem.residual, (n,)), ("dG/dp", problem.dG_dp, (n,))):
        value = np.asarray(evaluated(what, lambda: f(u0, p), p))
        if value.shape != shape:
            raise ProblemError(f"{what} returned shape {value.shape}, expected {shape} (u0 has {n} entries)")
        if not np.all(np.isfinite(value)):
            raise ProblemError(f"{what} returned non-finite values at p = {p:g}")
    _check_matrix("dG/du", evaluated("dG/du", lambda: problem.jacobian(u0, p), p), n)
    A = evaluated("the tracked matrix A", lambda: problem.stability_matrix(u0, p), p)
    _check_matrix("the tracked matrix A", A, -1)
    differenced = (getattr(problem, "G_u", None), getattr(problem, "G_p", None))
    if any(isinstance(f, (StateDerivative, ParameterDerivative)) and f.method == "complex-step"
           for f in differenced):
        try:
            check_complex_step(problem.G, u0, p)
        except ValueError as error:
            raise ProblemError(str(error)) from None
    return u0
