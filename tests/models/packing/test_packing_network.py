"""The contact network of a packing (issue 25, docs/packings.md): contacts found by the cell
list, forces and the sparse Jacobian from the grain-pair kernel, against finite differences,
an mpmath transcription of one contact, and the chain's own kernels for equal disks."""
from __future__ import annotations

import itertools

import mpmath as mp
import numpy as np
import pytest

import reference_model as ref
from diskfriction.models.packing.network import Network
from diskfriction.scenes import Scene
from diskfriction.symbolic.system import System

K_N, K_T, MU = 2000.0, 4000.0 / 7.0, 10.0


def dense_state(N: int, seed: int, phi: float = 0.95, gamma: float = 0.0):
    """A random bidisperse configuration (radii 0.5 and 0.7) dense enough to overlap,
    shifted out of the box (unwrapped coordinates), with histories within the Coulomb cap."""
    rng = np.random.default_rng(seed)
    radii = np.where(rng.random(N) < 0.5, 0.5, 0.7)
    L = float(np.sqrt(np.pi * np.sum(radii**2) / phi))
    net = Network.build(radii, L, K_N, K_T, MU)
    q = np.concatenate([rng.uniform(-L, 2 * L, 2 * N), rng.uniform(-1, 1, N)])
    contacts = net.contacts(q, gamma)
    t_star = MU * K_N * np.maximum(net.overlaps(q, contacts, gamma), 0) / K_T
    xi = rng.uniform(-0.9, 0.9, contacts.shape[0]) * t_star
    return net, q, contacts, xi


def brute_force_pairs(net: Network, q: np.ndarray, gamma: float, reach: float) -> set:
    """Every (i, j, cx, cy) with i < j over the images |cx|, |cy| <= 8 that overlaps by more
    than -reach."""
    N, L = net.N, net.L
    i, j = np.array(list(itertools.combinations(range(N), 2))).T
    found = set()
    for cx, cy in itertools.product(range(-8, 9), repeat=2):
        dx = q[i] - q[j] - cx * L - cy * gamma * L
        dy = q[N + i] - q[N + j] - cy * L
        hit = net.radii[i] + net.radii[j] - np.hypot(dx, dy) > -reach
        found |= {(a, b, cx, cy) for a, b in zip(i[hit].tolist(), j[hit].tolist())}
    return found


@pytest.mark.parametrize("gamma", [0.0, 0.37, -1.3])
def test_the_cell_list_finds_every_overlapping_image_and_nothing_else(gamma):
    net, q, _, _ = dense_state(60, seed=3, phi=0.8, gamma=gamma)
    for reach in (0.0, 0.2):
        rows = net.contacts(q, gamma, reach)
        assert {tuple(r) for r in rows.tolist()} == brute_force_pairs(net, q, gamma, reach)
        assert np.all(rows[:, 0] < rows[:, 1])
    assert len(net.contacts(q, gamma, 0.2)) > len(net.contacts(q, gamma))


def total_jacobian_fd(net: Network, q, xi, contacts, gamma, h=1e-7):
    """-dF/dq and dF/dgamma by central differences, the history following each step."""
    def F_at(q1, gamma1):
        xi1, _ = net.history_step(q, q1, gamma, gamma1, xi, contacts, cap=False)
        return net.forces(q1, xi1, contacts, gamma1)

    J = np.empty((q.size, q.size))
    for k in range(q.size):
        e = np.zeros(q.size)
        e[k] = h
        J[:, k] = -(F_at(q + e, gamma) - F_at(q - e, gamma)) / (2 * h)
    return J, (F_at(q, gamma + h) - F_at(q, gamma - h)) / (2 * h)


@pytest.mark.parametrize("gamma", [0.0, 0.21])
def test_the_packing_jacobian_matches_finite_differences_with_the_history_following(gamma):
    net, q, contacts, xi = dense_state(16, seed=11, gamma=gamma)
    assert np.sum(net.overlaps(q, contacts, gamma) > 0) >= 10 and np.any(contacts[:, 3] != 0)
    F, J, F_gamma = net.evaluate(q, xi, contacts, gamma)
    J_fd, F_gamma_fd = total_jacobian_fd(net, q, xi, contacts, gamma)
    scale = np.abs(J_fd).max()
    assert np.abs(J.toarray() - J_fd).max() <= 1e-7 * scale
    assert np.abs(F_gamma - F_gamma_fd).max() <= 1e-7 * np.abs(F_gamma_fd).max()
    assert np.allclose(F, net.forces(q, xi, contacts, gamma), rtol=0, atol=1e-12 * np.abs(F).max())
    assert not np.allclose(J.toarray(), J.toarray().T)  # friction: J is not symmetric


def test_a_grain_pair_of_equal_disks_is_the_chains_pair_kernel():
    """The same law with R_i = R_j = R: the grain kernel writes the chain's numbers up to
    rounding (sympy's cse orders the two kernels' operations differently)."""
    chain = System.from_scene(Scene()).kernels
    grain = Network.build(np.array([0.5, 0.5]), 3.0, K_N, K_T, MU).kernels
    rng = np.random.default_rng(5)
    f1, f2, J1, J2 = np.empty(6), np.empty(6), np.empty((6, 6)), np.empty((6, 6))
    for _ in range(50):
        dx, dy = rng.uniform(-1, 1, 2)
        delta = rng.uniform(1e-6, 1e-2)
        xi = rng.uniform(-1, 1) * MU * K_N * delta / K_T
        chain.pair_contact(dx, dy, delta, xi, 0.5, K_N, K_T, MU, f1, J1)
        grain.grain_contact(dx, dy, delta, xi, 0.5, 0.5, K_N, K_T, MU, f2, J2)
        assert np.abs(f1 - f2).max() <= 1e-14 * np.abs(f1).max()
        assert np.abs(J1 - J2).max() <= 1e-14 * np.abs(J1).max()


def test_three_equal_disks_in_a_box_have_the_chains_forces_and_jacobian():
    """The chain's ring of 3 disks (eps = 0.01) lifted off the substrate (every wall contact
    open) is a packing of three equal disks in a box of side L, the ring closed through the
    periodic x boundary; the contact (disk 1, disk 3) is the chain's pair (disk 3, disk 1) seen
    from the other side, with the same history (swapping the disks turns both s and r_ij, and
    d xi = s . d r_ij - R (d theta_i + d theta_j) stays)."""
    scene = Scene(N=3, eps=0.01)
    chain = System.from_scene(scene)
    net = Network.build(np.full(3, scene.R), scene.L, scene.k_n, scene.k_t, scene.mu)
    rng = np.random.default_rng(2)
    q = np.concatenate([(np.arange(3) + 0.5) * scene.L / 3 + rng.uniform(-1e-3, 1e-3, 3),
                        scene.R + 0.2 + rng.uniform(-1e-3, 1e-3, 3), rng.uniform(-1, 1, 3)])
    contacts = net.contacts(q, 0.0)
    assert [tuple(r) for r in contacts] == [(0, 1, 0, 0), (0, 2, -1, 0), (1, 2, 0, 0)]
    delta = net.overlaps(q, contacts, 0.0)
    xi_pairs = rng.uniform(-0.5, 0.5, 3) * MU * scene.k_n * delta[[0, 2, 1]] / scene.k_t
    xi_chain = np.concatenate([xi_pairs, np.zeros(3)])  # pairs (1,2), (2,3), (3,1); walls
    xi_net = xi_pairs[[0, 2, 1]]
    F_chain, J_chain = chain.forces_and_jacobian(q, xi_chain, 0.0)
    F_chain[3:6] += scene.F_y  # the chain's dead load F_y; no wall contact is closed
    F, J, _ = net.evaluate(q, xi_net, contacts, 0.0)
    assert np.allclose(F, F_chain, rtol=0, atol=1e-13 * np.abs(F).max())
    assert np.allclose(J.toarray(), J_chain, rtol=0, atol=1e-13 * np.abs(J_chain).max())


def mp_grain(dx, dy, xi, R_i, R_j):
    """Forces and torques (f_x, f_y, T_i on disk i; T_j on disk j) of one grain contact from
    docs/packings.md's equations, in 50-digit mpmath."""
    rho = mp.sqrt(dx * dx + dy * dy)
    delta = R_i + R_j - rho
    nx, ny = dx / rho, dy / rho
    Fn = ref.normal_force("hertz", K_N, delta)
    Ft = ref.tangential("mindlin-smooth", K_N, K_T, MU, delta, xi)
    return [Fn * nx - Ft * ny, Fn * ny + Ft * nx, -R_i * Ft, -(Fn * nx - Ft * ny),
            -(Fn * ny + Ft * nx), -R_j * Ft]


@mp.workdps(50)  # whatever precision other tests left mpmath at
def test_one_contact_of_unequal_disks_matches_the_mpmath_transcription():
    """f and the total stiffness of disks of radii 0.5 and 0.7: the stiffness by 50-digit
    central differences, d xi = s . d r_ij - (R_i d theta_i + R_j d theta_j) along each step."""
    net = Network.build(np.array([0.5, 0.7]), 4.0, K_N, K_T, MU)
    R_i, R_j = mp.mpf("0.5"), mp.mpf("0.7")
    dx0, dy0 = mp.mpf("0.7315"), mp.mpf("-0.8504")
    delta0 = R_i + R_j - mp.sqrt(dx0**2 + dy0**2)
    xi0 = mp.mpf("0.6") * MU * K_N * delta0 / K_T
    f, J = np.empty(6), np.empty((6, 6))
    net.kernels.grain_contact(float(dx0), float(dy0), float(delta0), float(xi0), 0.5, 0.7,
                              K_N, K_T, MU, f, J)
    f_ref = mp_grain(dx0, dy0, xi0, R_i, R_j)
    assert np.allclose(f, [float(v) for v in f_ref], rtol=1e-13, atol=0)
    h = mp.mpf("1e-20")
    for b in range(6):  # local dof b: x_i, y_i, theta_i, x_j, y_j, theta_j
        sign = 1 if b < 3 else -1
        step = [0, 0]
        if b % 3 < 2:
            step[b % 3] = sign * h

        def at(t):  # forces after moving dof b by t h, the history following (midpoint s)
            dx, dy = dx0 + t * step[0], dy0 + t * step[1]
            mx, my = (dx0 + dx) / 2, (dy0 + dy) / 2
            rho = mp.sqrt(mx * mx + my * my)
            dxi = (-my / rho) * (dx - dx0) + (mx / rho) * (dy - dy0)
            if b % 3 == 2:
                dxi -= t * h * (R_i if b < 3 else R_j)
            return mp_grain(dx, dy, xi0 + dxi, R_i, R_j)

        column = [-(p - m) / (2 * h) for p, m in zip(at(1), at(-1))]
        assert np.allclose(J[:, b], [float(v) for v in column], rtol=1e-12,
                           atol=1e-12 * np.abs(J).max())


def test_a_rigid_translation_charges_no_history_and_shear_charges_the_boundary_contacts():
    net, q, contacts, xi = dense_state(16, seed=4, gamma=0.1)
    shift = np.concatenate([np.full(16, 0.3), np.full(16, -0.2), np.zeros(16)])
    xi1, _ = net.history_step(q, q + shift, 0.1, 0.1, xi, contacts, cap=False)
    assert np.abs(xi1 - xi).max() <= 1e-15 * np.abs(xi).max()
    xi2, _ = net.history_step(q, q, 0.1, 0.1 + 1e-6, xi, contacts, cap=False)
    across = contacts[:, 3] != 0
    assert np.array_equal(xi2[~across], xi[~across]) and np.all(xi2[across] != xi[across])


def test_a_relaxations_force_evaluation_is_the_history_step_then_the_forces():
    """carried_forces in one compiled call equals history_step (the cap on) then forces, bit
    for bit, with contacts opening, closing and sliding in the step."""
    net, q, contacts, xi = dense_state(40, seed=5, gamma=0.2)
    q1 = q + np.random.default_rng(6).normal(scale=0.05, size=q.size)
    delta0, delta1 = net.overlaps(q, contacts, 0.2), net.overlaps(q1, contacts, 0.2)
    xi1, slid = net.history_step(q, q1, 0.2, 0.2, xi, contacts)
    assert np.any((delta0 > 0) != (delta1 > 0)) and np.any(slid)
    F, xi_carried, delta = net.carried_forces(q, q1, xi, delta0, contacts, 0.2)
    assert np.array_equal(xi_carried, xi1) and np.array_equal(delta, delta1)
    assert np.array_equal(F, net.forces(q1, xi1, contacts, 0.2))
