"""Sign changes of a growth rate along tracked eigenvalues, located (bifurcations.crossing_steps,
locate_crossing): the onset and end of a damped oscillatory instability against their closed
form, and the Hopf points' locator unchanged."""
from __future__ import annotations

from functools import partial

import numpy as np
import pytest

from core_problems import TOL_P, blocks_family, run
from diskfriction.continuation.detection.bifurcations import crossing_steps, locate_crossing
from diskfriction.dynamics.damped_modes import damped_growth_rates

A = 1.0
"""Re lambda of the pair of J = [[a, 1], [c(p), a]] (core_problems.pair_block): lambda = a +- sqrt(c)."""


def c(p):
    """c(p) = (p - 1)^2 - 1: a complex pair a +- i sqrt(-c) on 0 < p < 2, Im lambda largest (1) at p = 1."""
    return (p - 1.0) ** 2 - 1.0


def two_masses():
    """Two unit masses (M = I) with the stiffness J(p) = [[a, 1], [c(p), a]]: the circulatory
    (non-symmetric) coupling of a frictional contact in its smallest form, and a stiff second
    block [[4, 1], [1, 4]] that stays real and stable."""
    return blocks_family([(A, c, lambda p: 2.0 * (p - 1.0)), (4.0, lambda p: 1.0, lambda p: 0.0)])


def damped_onsets_closed_form(eta):
    """The drag eta damps the pair lambda = a +- i b exactly while eta^2 a >= b^2 (s^2 + eta s +
    lambda = 0 has a root s = i w there: a = w^2, eta w = -b): with b^2 = -c(p) = 1 - (p - 1)^2
    the damped instability lasts from 1 - sqrt(1 - eta^2 a) to 1 + sqrt(1 - eta^2 a)."""
    half = np.sqrt(1.0 - eta * eta * A)
    return 1.0 - half, 1.0 + half


@pytest.mark.parametrize("eta", [0.5, 0.9])
def test_damped_instability_onset_and_end_located_to_closed_form(eta):
    problem = two_masses()
    branch = run(problem, 4, p_min=0.0, p_max=2.3, ds=0.07, ds_max=0.07)
    growth = partial(damped_growth_rates, eta=eta)
    steps = crossing_steps(branch.eigenvalues, growth)
    assert [rising for _, _, rising in steps] == [True, False]  # one pair: its two members once
    points = [locate_crossing(problem, branch.x[k], branch.x[k + 1], branch.eigenvalues[k, i],
                              branch.eigenvalues[k + 1, i], lambda lam: float(growth(np.array([lam]))[0]),
                              k, upper=False, kind="damped-hopf") for k, i, _ in steps]
    onset, end = damped_onsets_closed_form(eta)
    assert abs(points[0].p - onset) <= TOL_P and abs(points[1].p - end) <= TOL_P
    for point in points:  # on the boundary the exponent is s = i w: w^2 = Re lambda, eta w = Im lambda
        assert point.value.real == pytest.approx(A, abs=1e-9)
        assert abs(point.value.imag) == pytest.approx(eta * np.sqrt(A), abs=1e-8)
        assert damped_growth_rates(np.array([point.value]), eta)[0] == pytest.approx(0.0, abs=1e-8)


def test_a_drag_above_the_largest_b_over_sqrt_a_leaves_no_crossing():
    branch = run(two_masses(), 4, p_min=0.0, p_max=2.3, ds=0.07, ds_max=0.07)
    assert crossing_steps(branch.eigenvalues, partial(damped_growth_rates, eta=1.01)) == []


def test_without_drag_no_crossing_is_found_the_births_are_the_onsets():
    """eta = 0: the growth rate |Im sqrt(lambda)| is exactly 0 on the real eigenvalues lambda > 0
    and positive on the pair, so no sign change is clear: the onsets are the located births."""
    branch = run(two_masses(), 4, p_min=0.0, p_max=2.3, ds=0.07, ds_max=0.07)
    assert [c.kind for c in branch.collisions] == ["birth", "death"]
    assert crossing_steps(branch.eigenvalues, partial(damped_growth_rates, eta=0.0)) == []
