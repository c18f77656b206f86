"""The exponents of M q'' + C q' + K q = 0 (dynamics/quadratic_modes.py): the drag C = eta M gives
damped_modes' exponents, C = 0 gives +-sqrt(-lambda), every exponent makes s^2 M + s C + K
singular, one degree of freedom has its closed form, and the rigid-body zeros are dropped by
count."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp

from diskfriction.dynamics.damped_modes import damped_exponents
from diskfriction.dynamics.quadratic_modes import largest_growth, quadratic_exponents


def system(n: int, seed: int):
    """(diag(M), C, K): a nonsymmetric K whose antisymmetric part makes complex pairs (as friction
    does) and a symmetric positive semidefinite C of rank n / 2 (as dashpots on few contacts)."""
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    W = rng.standard_normal((n, n))
    B = rng.standard_normal((n, n // 2))
    return rng.uniform(0.5, 2.0, n), A @ A.T + n * np.eye(n) + 2.0 * (W - W.T), 0.3 * B @ B.T


def matched_distance(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| over a one-to-one matching (sorting complex numbers reorders them on
    rounding)."""
    rows, cols = scipy.optimize.linear_sum_assignment(np.abs(a[:, None] - b[None, :]))
    return float(np.abs(a[rows] - b[cols]).max())


@pytest.mark.parametrize("eta", [0.3, 2.0, 40.0])
def test_a_drag_on_every_dof_gives_the_damped_exponents(eta):
    mass, K, _ = system(14, 1)
    lam = scipy.linalg.eigvals(K / mass[:, None])
    assert np.abs(lam.imag).max() > 1.0  # complex pairs to test
    expected = damped_exponents(lam, eta).ravel()
    ours = quadratic_exponents(mass, eta * np.diag(mass), K)
    assert ours.size == 2 * K.shape[0]
    assert matched_distance(ours, expected) <= 1e-10 * np.abs(expected).max()
    assert np.all(np.diff(ours.real) <= 0)  # in decreasing real part


def test_without_damping_the_exponents_are_plus_minus_sqrt_of_minus_lambda():
    mass, K, _ = system(12, 2)
    lam = scipy.linalg.eigvals(K / mass[:, None])
    root = np.sqrt(-lam.astype(complex))
    ours = quadratic_exponents(mass, np.zeros_like(K), sp.csr_array(K))
    assert matched_distance(ours, np.concatenate([root, -root])) <= 1e-10 * np.abs(root).max()


@pytest.mark.parametrize("full_mass", [False, True])
def test_every_exponent_makes_the_quadratic_pencil_singular(full_mass):
    """s^2 M + s C + K has a null vector at every exponent: its smallest singular value is at the
    rounding of its largest, while at points off the spectrum it is not; M as a matrix (a
    symmetric positive definite one, the generalized form) or as a diagonal."""
    mass, K, C = system(10, 3)
    rng = np.random.default_rng(4)
    if full_mass:
        G = rng.standard_normal((10, 10))
        M = G @ G.T / 10 + np.diag(mass)
    else:
        M = np.diag(mass)
    exponents = quadratic_exponents(M if full_mass else mass, sp.csr_array(C), K)
    assert exponents.size == 20

    def smallest_over_largest(s):
        sv = np.linalg.svd(s * s * M + s * C + K, compute_uv=False)
        return sv[-1] / sv[0]

    assert max(smallest_over_largest(s) for s in exponents) <= 1e-12
    off = exponents + 0.1 * np.abs(exponents).min()
    assert min(smallest_over_largest(s) for s in off) > 1e-6


def test_one_degree_of_freedom_is_its_closed_form():
    m, c, k = 2.0, 0.7, 5.0
    s = quadratic_exponents(np.array([m]), np.array([[c]]), np.array([[k]]))
    root = np.sqrt(complex(c * c - 4 * m * k))
    assert s == pytest.approx(np.array([(-c + root) / (2 * m), (-c - root) / (2 * m)]), rel=1e-14)
    overdamped = quadratic_exponents(np.array([m]), np.array([[10.0]]), np.array([[k]]))
    root = np.sqrt(100.0 - 4 * m * k)
    assert overdamped.real == pytest.approx([(-10.0 + root) / (2 * m), (-10.0 - root) / (2 * m)],
                                            rel=1e-14)
    assert np.all(overdamped.imag == 0)


def test_the_rigid_body_zeros_are_dropped_by_count():
    """A chain of masses on springs with dashpots between neighbours: its translation (K T = 0,
    C T = 0) is a double zero exponent that rounding splits; without it every mode decays, at the
    slowest rate of the system without its translation, found from the relative coordinates."""
    n = 8
    rng = np.random.default_rng(5)
    mass = rng.uniform(0.5, 2.0, n)
    D = np.diff(np.eye(n), axis=0)  # (n - 1, n): x_{k+1} - x_k
    K = D.T @ np.diag(rng.uniform(1e3, 2e3, n - 1)) @ D
    C = D.T @ np.diag(rng.uniform(0.1, 0.2, n - 1)) @ D
    exponents = quadratic_exponents(mass, C, K)
    assert np.sort(np.abs(exponents))[1] <= 1e-6 * np.abs(exponents).max()
    # relative coordinates z = x_k - x_0: z'' = P M^-1 (-C - K) E z', P = [-1 | I], E = [0; I]
    P = np.hstack([-np.ones((n - 1, 1)), np.eye(n - 1)])
    E = np.eye(n)[:, 1:]
    reduced = quadratic_exponents(np.ones(n - 1), P @ (C / mass[:, None]) @ E,
                                  P @ (K / mass[:, None]) @ E)
    assert largest_growth(exponents, rigid=1) == pytest.approx(largest_growth(reduced), rel=1e-8)
    assert largest_growth(reduced) < 0
