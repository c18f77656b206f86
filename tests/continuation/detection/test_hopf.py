"""Hopf points only where a complex pair crosses the imaginary axis (issue 27 item 2): no
sign change of a real part within rounding of zero counts, and a conservative spectrum
(symmetric under lambda -> -lambda) has none. Ziegler's double pendulum written as first order,
undamped (conservative) and damped (Ziegler's paradox: flutter at 1.464, not 2.086), against
an independent root of max Re lambda."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from diskfriction.continuation import Options, problem_from_functions, solve_branch
from diskfriction.continuation.detection.bifurcations import CONSERVATIVE, conservative, hopf_steps

M_INV = np.linalg.inv(np.array([[3.0, 1.0], [1.0, 1.0]]))
SPAN = (0.0, 6.0)


def first_order(c: float):
    """u' = A(P) u, u = (theta, theta'), damping c [[2, -1], [-1, 1]] (dashpots at the springs);
    k = l = m = 1 (examples/ziegler.py)."""
    C = c * np.array([[2.0, -1.0], [-1.0, 1.0]])

    def A(u, P):
        K = np.array([[2.0 - P, P - 1.0], [-1.0, 1.0]])
        return np.block([[np.zeros((2, 2)), np.eye(2)], [-M_INV @ K, -M_INV @ C]])

    problem = problem_from_functions(lambda u, P: A(u, P) @ u, dG_du=A,
                                     dG_dp=lambda u, P: np.zeros(4), A=A)
    return problem, A


def run(c: float):
    problem, A = first_order(c)
    return solve_branch(problem, np.zeros(4), SPAN, Options(ds_max=0.2, special_points=("hopf",))), A


def test_an_undamped_pendulum_as_first_order_has_no_hopf_point_and_says_why():
    result, _ = run(0.0)
    assert result.success and result.hopf == ()  # the old test found 12, from rounding
    assert conservative(result.branch.eigenvalues) and CONSERVATIVE in result.warnings
    assert hopf_steps(result.branch.eigenvalues) == []  # rounding alone crosses nothing


@pytest.mark.parametrize("c", [0.1, 1e-4])
def test_a_damped_pendulum_flutters_at_its_one_hopf_point(c):
    result, A = run(c)
    growth = lambda P: float(np.linalg.eigvals(A(None, P)).real.max())  # noqa: E731
    grid = np.linspace(*SPAN, 601)
    values = [growth(P) for P in grid]
    exact = [brentq(growth, a, b, xtol=1e-14) for a, b, fa, fb in
             zip(grid, grid[1:], values, values[1:]) if fa * fb < 0]
    assert len(exact) == 1 and 1.46 < exact[0] < 1.47  # Ziegler's paradox, not 7/2 - sqrt 2
    assert [s.p for s in result.hopf] == pytest.approx(exact, abs=1e-10)
    assert not conservative(result.branch.eigenvalues) and CONSERVATIVE not in result.warnings


def test_a_crossing_counts_once_whatever_rounding_does_near_zero():
    """One pair whose real part goes -1, -1e-17, +1e-17, -1e-17, 2 (scale 10): one crossing,
    located on the first step where Re changes sign; a pair whose real part only flips within
    rounding of zero crosses nothing; a pair that turns real in between crosses nothing."""
    re = np.array([-1.0, -1e-17, 1e-17, -1e-17, 2.0])
    crossing = re + 10j
    flipping = np.array([1e-17, -1e-17, 1e-17, -1e-17, 1e-17]) + 10j
    broken = np.where(np.arange(5) == 2, re, crossing)  # real at the middle point
    for column, steps in ((crossing, [(1, 0)]), (flipping, []), (broken, [])):
        eigenvalues = np.stack([column, column.conj()], axis=1)
        assert hopf_steps(eigenvalues) == steps
