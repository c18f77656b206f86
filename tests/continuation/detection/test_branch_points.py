"""Simple branch points (issue 27 item 1): located where a second branch crosses, told from
folds, and switch_branch onto the second branch; Lorenz's pitchfork is in tests/test_gallery.py."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation import Options, problem_from_functions, solve_branch, switch_branch

TRANSCRITICAL = problem_from_functions(lambda u, p: u * (p - u), dG_du=lambda u, p: np.diag(p - 2 * u),
                                       dG_dp=lambda u, p: u)
"""u' = u (p - u): the branches u = 0 and u = p exchange stability at (0, 0)."""


def test_a_transcritical_crossing_is_a_branch_point_and_the_switch_lands_on_u_equal_p():
    result = solve_branch(TRANSCRITICAL, [0.0], (-1.0, 1.0), Options(ds_max=0.1))
    (point,) = result.branch_points
    assert abs(point.p) <= 1e-12 and not result.folds
    for p_stop in (1.0, -1.0):  # the second branch, toward either end of the span
        new = switch_branch(TRANSCRITICAL, result, 0, p_stop, Options(ds_max=0.1))
        assert new.success and new.p[-1] == p_stop
        assert np.abs(new.u[:, 0] - new.p).max() <= 1e-12 and not new.branch_points


def test_a_fold_is_no_branch_point():
    """u^2 + p = 0 turns back at p = 0: a fold, and the bordered determinant keeps its sign."""
    problem = problem_from_functions(lambda u, p: u * u + p, dG_du=lambda u, p: np.diag(2 * u),
                                     dG_dp=lambda u, p: np.ones(1))
    result = solve_branch(problem, [-1.0], (-1.0, 0.5), Options(ds_max=0.05))
    (fold,) = result.folds
    assert abs(fold.p) <= 1e-12 and result.branch_points == ()


def test_switch_branch_refuses_a_point_it_does_not_have():
    result = solve_branch(TRANSCRITICAL, [0.0], (-1.0, 1.0), Options(ds_max=0.1))
    with pytest.raises(ValueError, match="branch point 1 asked for; the branch has 1"):
        switch_branch(TRANSCRITICAL, result, 1, 1.0)
    with pytest.raises(ValueError, match="side must be 1 or -1"):
        switch_branch(TRANSCRITICAL, result, 0, 1.0, side=2)
