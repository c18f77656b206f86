"""The damped linearization's exponents (dynamics/damped_modes.py) against the quadratic
eigenproblem M s^2 + eta M s + J = 0 solved directly, at eta = 0 the undamped growth rates, and
the critical damping against where the growth rate changes sign."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize

from diskfriction.dynamics.damped_modes import critical_damping, damped_exponents, damped_growth_rates
from diskfriction.models.packing.dynamics import fastest_pair


def nonsymmetric_system(n: int, seed: int):
    """(M diagonal, J): a stiffness with a symmetric part of positive spectrum and an
    antisymmetric part that makes complex pairs (as friction does)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    K = A @ A.T + n * np.eye(n)
    W = rng.standard_normal((n, n))
    return np.diag(rng.uniform(0.5, 2.0, n)), K + 2.0 * (W - W.T)


@pytest.mark.parametrize("eta", [0.0, 0.3, 2.0])
def test_the_exponents_are_the_quadratic_eigenproblems(eta):
    M, J = nonsymmetric_system(12, 1)
    n = J.shape[0]
    # the companion form of M s^2 + eta M s + J = 0: [[0, I], [-M^-1 J, -eta I]]
    companion = np.block([[np.zeros((n, n)), np.eye(n)],
                          [-np.linalg.solve(M, J), -eta * np.eye(n)]])
    direct = scipy.linalg.eigvals(companion)
    lam = scipy.linalg.eigvals(np.linalg.solve(M, J))
    ours = damped_exponents(lam, eta).ravel()
    assert np.abs(lam.imag).max() > 1.0  # complex pairs to test
    # matched one to one (sorting complex numbers reorders them on rounding)
    rows, cols = scipy.optimize.linear_sum_assignment(np.abs(ours[:, None] - direct[None, :]))
    assert np.abs(ours[rows] - direct[cols]).max() <= 1e-9 * np.abs(direct).max()


def test_without_damping_the_growth_rates_are_the_undamped_analysis():
    M, J = nonsymmetric_system(10, 2)
    lam = scipy.linalg.eigvals(np.linalg.solve(M, J))
    rates = damped_growth_rates(lam, 0.0)
    assert np.allclose(rates, np.abs(np.sqrt(lam).imag), rtol=1e-12, atol=1e-12)
    assert rates.max() == pytest.approx(fastest_pair(lam)[1], rel=1e-12)
    assert rates.max() > 0


def test_the_critical_damping_is_where_the_last_pair_stops_growing():
    M, J = nonsymmetric_system(10, 3)
    lam = scipy.linalg.eigvals(np.linalg.solve(M, J))
    eta_c = critical_damping(lam)
    assert 0 < eta_c < np.inf
    assert damped_growth_rates(lam, 0.999 * eta_c).max() > 0
    assert damped_growth_rates(lam, 1.001 * eta_c).max() < 0
    # the pair that sets it is marginal there: one exponent on the imaginary axis
    assert abs(damped_growth_rates(lam, eta_c).max()) < 1e-9 * eta_c


def test_critical_damping_of_real_and_statically_unstable_spectra():
    assert critical_damping(np.array([1.0, 4.0, 0.0])) == 0.0  # no pair: nothing to damp
    assert critical_damping(np.array([1.0 + 2.0j, 1.0 - 2.0j])) == pytest.approx(2.0)
    assert critical_damping(np.array([-1.0 + 2.0j, -1.0 - 2.0j])) == np.inf
    # a real negative eigenvalue grows at any drag, though it is no pair
    assert damped_growth_rates(np.array([-4.0]), 10.0)[0] > 0
