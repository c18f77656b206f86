"""Dashpots on a packing's contacts (models/packing/contact_damping.py): C is symmetric, positive
semidefinite and misses translations and rolling; -C v is the dashpots' forces and torques
evaluated contact by contact from the velocities of the contact points; an isolated pair relaxes
at the documented rates; in the tracked spectrum's coordinates the drag eta M gives
damped_modes' exponents, and a small contact damping moves each undamped exponent by its
first-order shift."""
from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.linalg
import scipy.optimize
import scipy.sparse as sp
from sheared_packing import SCENE, problem_at_start

from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.dynamics.damped_modes import damped_exponents
from diskfriction.models.packing.contact_damping import (
    TANGENTIAL_RATIO, ContactDamping, damped_spectrum, damping_matrix, problem_damping,
    reduced_exponents)

RATE = 0.1 * SCENE.omega_0


def charged(packing, matrix: str = SCENE.matrix):
    """The shared packing's problem at its start with a charged history (xi != 0, set before any
    evaluation, as test_packing_equilibria does): J nonsymmetric."""
    problem = problem_at_start(packing, matrix)
    rng = np.random.default_rng(0)
    problem.xi_c = rng.uniform(-0.5, 0.5, problem.xi_c.size) * 1e-4
    return problem


def matched_distance(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| over a one-to-one matching."""
    rows, cols = scipy.optimize.linear_sum_assignment(np.abs(a[:, None] - b[None, :]))
    return float(np.abs(a[rows] - b[cols]).max())


def cross(a: np.ndarray, b: np.ndarray) -> float:
    """The z component of a x b for vectors of the plane."""
    return float(a[0] * b[1] - a[1] * b[0])


def dashpot_forces(network, q, rows, gamma, mass, v, tangential, rate, ratio):
    """The generalized forces [force; torque] of the dashpots on the overlapping rows at velocity
    v, contact by contact: the velocities of the material points of both disks at the contact
    (on the line of centres, at R_i and R_j from them), the force on i opposing their relative
    velocity's normal part (c_n) and tangential part (c_t), -that on j, each applied at its
    disk's contact point; c = rate m_i m_j / (m_i + m_j), c_t = ratio c_n."""
    N, L, radii = network.N, network.L, network.radii
    F = np.zeros(3 * N)
    for (i, j, cx, cy), slip in zip(rows, tangential):
        centre_i = np.array([q[i], q[N + i]])
        centre_j = np.array([q[j] + cx * L + cy * gamma * L, q[N + j] + cy * L])
        d = centre_i - centre_j
        if np.linalg.norm(d) >= radii[i] + radii[j]:
            continue
        n = d / np.linalg.norm(d)
        arm_i, arm_j = -radii[i] * n, radii[j] * n  # from each centre to its contact point
        spin = lambda omega, arm: omega * np.array([-arm[1], arm[0]])  # omega z x arm
        point_i = np.array([v[i], v[N + i]]) + spin(v[2 * N + i], arm_i)
        point_j = np.array([v[j], v[N + j]]) + spin(v[2 * N + j], arm_j)
        relative = point_i - point_j
        c_n = rate * mass[i] * mass[j] / (mass[i] + mass[j])
        c_t = ratio * c_n if slip else 0.0
        normal = np.dot(n, relative)
        force = -c_n * normal * n - c_t * (relative - normal * n)
        F[[i, N + i, 2 * N + i]] += force[0], force[1], cross(arm_i, force)
        F[[j, N + j, 2 * N + j]] += -force[0], -force[1], cross(arm_j, -force)
    return F


def test_the_damping_matrix_is_symmetric_semidefinite_and_misses_translations(packing):
    problem = charged(packing)
    q = problem.q_c
    C = problem_damping(problem, q, 0.0, ContactDamping(RATE)).toarray()
    assert np.abs(C).max() > 0
    assert np.abs(C - C.T).max() <= 1e-15 * np.abs(C).max()
    assert np.linalg.eigvalsh(C).min() >= -1e-13 * np.abs(C).max()
    N = problem.network.N
    for axis in (0, 1):
        T = np.zeros(3 * N)
        T[axis * N:(axis + 1) * N] = 1.0
        assert np.abs(C @ T).max() <= 1e-14 * np.abs(C).max()
    # a loose disk's contacts are watched rows: no dashpot acts on it
    loose = np.flatnonzero(problem.gauge.loose)
    assert loose.size
    dofs = np.concatenate([loose, N + loose, 2 * N + loose])
    assert not C[dofs].any() and not C[:, dofs].any()


def test_minus_c_v_is_the_dashpots_forces_contact_by_contact(packing):
    """At a strain where rows across the sheared boundary (cy != 0) overlap, with a random
    velocity and tangential dashpots on a random half of the rows."""
    problem = charged(packing)
    network, rows, gamma = problem.network, problem.rows_c, 2e-4
    rng = np.random.default_rng(1)
    v = rng.standard_normal(network.ndof)
    tangential = rng.uniform(size=rows.shape[0]) < 0.5
    damping = ContactDamping(RATE, 0.7)
    C = damping_matrix(network, problem.q_c, rows, gamma, problem.mass, damping, tangential)
    expected = dashpot_forces(network, problem.q_c, rows, gamma, problem.mass, v, tangential,
                              RATE, 0.7)
    across = rows[:, 3] != 0
    assert (network.overlaps(problem.q_c, rows[across], gamma) > 0).any()
    assert np.abs(-C @ v - expected).max() <= 1e-13 * np.abs(expected).max()


def isolated_pair(problem, delta: float, angle: float):
    """(network, q, rows, gamma, mass) of two disks of the packing's radii 0.5 and 0.7, overlapping
    by delta along the direction `angle`, disk 1 seen through the Lees-Edwards image (1, -1) at
    gamma = 0.3 (the other disks of the network far away: their contacts are not rows)."""
    network = dataclasses.replace(problem.network, radii=np.array([0.5, 0.7]), L=10.0)
    gamma, L = 0.3, network.L
    n = np.array([np.cos(angle), np.sin(angle)])
    centre = np.array([1.2, 2.0])
    image = centre - (1.2 - delta) * n  # = r_1 + (cx L + cy gamma L, cy L), (cx, cy) = (1, -1)
    q = np.array([centre[0], image[0] - L + gamma * L, centre[1], image[1] + L, 0.0, 0.0])
    mass = np.array([0.25, 0.49, 0.25, 0.49, 0.5 * 0.25 * 0.25, 0.5 * 0.49 * 0.49])
    rows = np.array([[0, 1, 1, -1]])
    assert network.overlaps(q, rows, gamma)[0] == pytest.approx(delta, rel=1e-9)
    return network, q, rows, gamma, mass


def test_an_isolated_pair_relaxes_at_the_documented_rates(packing):
    """M^-1 C of one contact has two nonzero eigenvalues: the normal relative velocity's decay
    rate eta and the tangential one's, ratio eta (1 + 1 / c) for I = c m R^2 (c = 1/2 here)."""
    network, q, rows, gamma, mass = isolated_pair(problem_at_start(packing), 0.01, 0.4)
    C = damping_matrix(network, q, rows, gamma, mass, ContactDamping(RATE), np.array([True]))
    rates = np.sort(scipy.linalg.eigvals(C.toarray() / mass[:, None]).real)
    assert rates[:4] == pytest.approx(np.zeros(4), abs=1e-12 * RATE)
    assert rates[4:] == pytest.approx(np.sort([RATE, TANGENTIAL_RATIO * RATE * 3.0]), rel=1e-12)


def test_rolling_is_free_and_a_rigid_rotation_slides_by_the_overlap(packing):
    """Two disks rolling on each other (R_0 omega_0 = -R_1 omega_1, centres at rest) move no
    contact point: no force. A rigid rotation of the pair at Omega about any point moves the
    contact points of the lever arms R_i apart at -Omega delta along s (the arms reach past the
    overlap's middle): no normal force, a tangential one c_t Omega delta."""
    delta = 0.01
    network, q, rows, gamma, mass = isolated_pair(problem_at_start(packing), delta, 2.2)
    damping = ContactDamping(RATE)
    C = damping_matrix(network, q, rows, gamma, mass, damping, np.array([True])).toarray()
    rolling = np.array([0.0, 0.0, 0.0, 0.0, 1.0 / 0.5, -1.0 / 0.7])
    assert np.abs(C @ rolling).max() <= 1e-14 * np.abs(C).max()
    Omega, pivot = 0.3, np.array([4.0, -1.0])
    image = np.array([q[1] + (1 + -1 * gamma) * network.L, q[3] - network.L])
    centres = np.array([[q[0], q[2]], image])
    at = Omega * np.stack([-(centres[:, 1] - pivot[1]), centres[:, 0] - pivot[0]], axis=1)
    rotation = np.array([at[0, 0], at[1, 0], at[0, 1], at[1, 1], Omega, Omega])
    force = -C @ rotation
    n = (centres[0] - centres[1]) / np.linalg.norm(centres[0] - centres[1])
    s = np.array([-n[1], n[0]])
    c_t = damping.coefficients(mass[0], mass[1])[1]
    F_t = c_t * Omega * delta
    expected = np.array([F_t * s[0], -F_t * s[0], F_t * s[1], -F_t * s[1], -0.5 * F_t, -0.7 * F_t])
    assert force == pytest.approx(expected, rel=1e-9, abs=1e-12 * abs(F_t))


@pytest.mark.parametrize("matrix", ["M^-1 J", "J"])
def test_the_drag_gives_the_damped_exponents_of_the_tracked_spectrum(packing, matrix):
    """C = eta M reduced to the tracked spectrum's coordinates: s^2 + eta s + lambda = 0 for
    every eigenvalue lambda of the problem's M^-1 J (DenseSpectra), whichever matrix the problem
    tracks (the dynamics is M^-1 J's)."""
    eta = 0.3 * SCENE.omega_0
    reference = charged(packing)
    system = DenseSpectra().eigensystem(reference, reference.q_c, 0.0)
    expected = damped_exponents(system.values[~system.excluded], eta).ravel()
    problem = charged(packing, matrix)
    ours = reduced_exponents(problem, problem.q_c, 0.0, eta * sp.diags_array(problem.mass))
    assert ours.size == 2 * problem.gauge.kept.size == expected.size
    assert matched_distance(ours, expected) <= 1e-10 * np.abs(expected).max()


def test_a_small_contact_damping_shifts_each_mode_at_first_order(packing):
    """With eta -> 0 the exponents tend to +-sqrt(-lambda) for the eigenvalues lambda of A_red,
    each moved by -(l^T C_red r) / (2 l^T r) (r, l: lambda's right and left vectors, C_red = P
    M^-1 C E): the shift is found to 1 % at eta = 1e-4 omega_0 (the second order left is 5e-4
    of it there), and it is no rounding: the exponents are that far from +-sqrt(-lambda)."""
    problem = charged(packing)
    q, g = problem.q_c, problem.gauge
    damping = ContactDamping(1e-4 * SCENE.omega_0)
    C = problem_damping(problem, q, 0.0, damping)
    C_red = (g.P @ (C / problem.mass[:, None])).toarray()[:, g.kept]
    lam, left, right = scipy.linalg.eig(problem.reduced(q, 0.0).toarray(), left=True)
    shift = -(np.einsum("ik,ij,jk->k", left.conj(), C_red, right)
              / (2 * np.sum(left.conj() * right, axis=0)))
    root = np.sqrt(-lam.astype(complex))
    undamped = np.concatenate([root, -root])
    predicted = np.concatenate([root + shift, -root + shift])
    ours = damped_spectrum(problem, q, 0.0, damping).exponents
    assert matched_distance(ours, undamped) >= 0.5 * np.abs(shift).max()
    assert matched_distance(ours, predicted) <= 1e-2 * np.abs(shift).max()


def test_the_damped_spectrum_of_a_stable_state_decays(packing):
    """At the start (every lambda > 0) dashpots remove energy from every mode: the growth rate is
    the largest Re s, negative, and the exponents come in conjugate pairs."""
    problem = problem_at_start(packing)
    spectrum = damped_spectrum(problem, problem.q_c, 0.0, ContactDamping(RATE))
    assert spectrum.exponents.size == 2 * problem.gauge.kept.size
    assert spectrum.growth == spectrum.exponents.real.max() < 0
    assert matched_distance(spectrum.exponents, spectrum.exponents.conj()) <= 1e-9 * np.abs(
        spectrum.exponents).max()
