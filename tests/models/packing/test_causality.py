"""Causality by dynamics (issue 63, item 4; models/packing/causality.py): the damped dynamics
at fixed strain from the shear branch's states. A drag at zero is the undamped run bit for bit
and otherwise lowers the energy budget by its work; a perturbed stable state returns at its
slowest damped rate; a damped-unstable pair grows at Re s of s^2 + eta s + lambda = 0 and,
above the critical damping, the same start returns."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import expm
from sheared_packing import SCENE

from diskfriction.dynamics.damped_modes import critical_damping, damped_exponents
from diskfriction.models.packing.causality import (VERDICTS, DampedMode, causality, damped_modes,
                                                   fastest, mass_overlap, onsets,
                                                   run_mode)
from diskfriction.models.packing.damped import damped_rates
from diskfriction.models.packing.dynamics import LINEAR_RANGE, fit_growth, simulate, time_step
from diskfriction.models.packing.equilibria import PackingEquilibria, mass_diagonal
from diskfriction.models.packing.shear import network_of


@pytest.fixture(scope="module")
def setting(packing, branch):
    network = network_of(SCENE, packing)
    return branch, network, mass_diagonal(network, SCENE.m, SCENE.inertia)


def state(branch, k):
    return branch.q[k], branch.xi[k], branch.rows[k], float(branch.gamma[k])


def unstable_state(branch, eta):
    """The state of the branch whose fastest pair grows fastest at the drag eta."""
    return int(np.argmax(damped_rates(branch.eigenvalues, eta)))


def test_a_drag_at_zero_is_the_undamped_run_and_otherwise_takes_its_work_from_the_budget(setting):
    """simulate at eta = 0 is the run without a drag bit for bit; at eta = 1 the budget
    E_k + U_n - W_t falls by the drag's work int eta v.M v dt = int 2 eta E_k dt (the
    trapezoid over 2000 frames: within 1e-4)."""
    branch, network, mass = setting
    q, xi, rows, gamma = state(branch, 0)
    v0 = np.random.default_rng(0).normal(size=q.size) * 1e-4
    dt = time_step(branch.eigenvalues[0])
    plain = simulate(network, q, v0, xi, rows, gamma, mass, dt, 5.0)
    zero = simulate(network, q, v0, xi, rows, gamma, mass, dt, 5.0, eta=0.0)
    for name in ("t", "q", "v", "budget", "kinetic", "capped", "xi", "rows"):
        assert np.array_equal(getattr(plain, name), getattr(zero, name)), name
    eta = 1.0
    run = simulate(network, q, v0, xi, rows, gamma, mass, dt, 5.0, frames=2000, eta=eta)
    work = np.trapezoid(2.0 * eta * run.kinetic, run.t)
    assert run.kinetic[-1] < 0.1 * run.kinetic[0]
    assert abs((run.budget[0] - run.budget[-1]) / work - 1.0) <= 1e-4


def test_a_perturbed_stable_state_returns_at_its_slowest_damped_rate(setting):
    """At gamma = 0 (every eigenvalue of M^-1 J real), displaced at random (the disks that are
    not loose, without a translation) and let go at a drag that overdamps the slowest mode: the
    run comes to rest within 1e-3 of its start's distance from the state (the state's residual
    forces, 1.4e-13, hold the dynamics' rest 2e-13 away from it), and its distance from that
    rest decays at the largest Re s of damped_exponents (fitted from 6 to 12 decay times: within
    1 %)."""
    branch, network, mass = setting
    q, xi, rows, gamma = state(branch, 0)
    lam = branch.eigenvalues[0]
    lam = np.sort(lam[lam != 0].real)
    eta = 3.0 * np.sqrt(lam[0])  # the slowest mode overdamped, the others decay faster
    rate = damped_exponents(lam, eta)[:, 0].real.max()
    loose = PackingEquilibria(network, q, xi, rows, gamma, mass).gauge.loose
    held = np.tile(~loose, 3)
    dq = np.where(held, np.random.default_rng(1).normal(size=q.size), 0.0)
    N = network.N
    for part in (slice(0, N), slice(N, 2 * N)):
        dq[part] -= np.where(held[part], np.sum(mass[part] * dq[part] * held[part])
                             / np.sum(mass[part] * held[part]), 0.0)
    a = 1e-6 * SCENE.delta_0
    dq *= a / np.sqrt(np.sum(mass * dq * dq))
    run = simulate(network, q + dq, np.zeros(q.size), network.history_step(
        q, q + dq, gamma, gamma, xi, rows)[0], rows, gamma, mass, time_step(branch.eigenvalues[0]),
        24.0 / abs(rate), frames=400, eta=eta)
    assert np.sqrt(np.sum(mass * (run.q[-1] - q) ** 2)) <= 1e-3 * a
    d = np.sqrt(np.sum((mass * (run.q - run.q[-1]) ** 2)[:, held], axis=1))
    window = (run.t >= 6.0 / abs(rate)) & (run.t <= 12.0 / abs(rate))
    slope = np.polyfit(run.t[window], np.log(d[window]), 1)[0]
    assert abs(slope / rate - 1.0) <= 1e-2, (slope, rate)


def test_the_complex_amplitude_of_a_damped_pair_grows_exactly_at_re_s():
    """On M q'' + eta M q' + J q = 0 solved exactly (the matrix exponential of its first-order
    form; 3 dofs, J not symmetric, one complex pair), c = (W v - s' W q) / (s - s') of the
    pair's mode is c_0 e^(s t) to rounding, whatever else the start holds."""
    rng = np.random.default_rng(2)
    mass = np.array([1.0, 2.0, 0.5])
    J = np.array([[3.0, 1.0, 0.0], [-2.5, 4.0, 0.5], [0.2, 0.0, 2.0]])
    A = J / mass[:, None]
    lam, right = np.linalg.eig(A)
    i = int(np.argmax(lam.imag))
    left = np.linalg.inv(right)[i]
    V = right[:, i] / np.sqrt(np.sum(mass * right[:, i].real ** 2))
    mode = DampedMode(complex(lam[i]), V, left / (left @ V))
    eta = 0.3
    s = mode.exponents(eta)[0]
    assert s.real > 0 and abs(s * s + eta * s + lam[i]) <= 1e-12 * abs(lam[i])
    first = np.block([[np.zeros((3, 3)), np.eye(3)], [-A, -eta * np.eye(3)]])
    x0 = rng.normal(size=6)
    c0 = mode.amplitude(eta, x0[:3], x0[3:])
    for t in (0.5, 2.0, 5.0):
        x = expm(first * t) @ x0
        assert abs(mode.amplitude(eta, x[:3], x[3:]) / (c0 * np.exp(s * t)) - 1.0) <= 1e-10


def test_the_overlap_of_two_fields_ignores_their_translations():
    """mass_overlap: 1 for a field against itself shifted uniformly, 0 against a field
    M-orthogonal to it, |cos| of the angle between them otherwise."""
    rng = np.random.default_rng(3)
    N = 5
    mass = np.concatenate([np.full(2 * N, 1.5), np.full(N, 0.2)])
    u = rng.normal(size=3 * N)
    u[:N] -= np.mean(u[:N])
    u[N:2 * N] -= np.mean(u[N:2 * N])
    shifted = u + np.concatenate([np.full(N, 0.7), np.full(N, -0.3), np.zeros(N)])
    assert abs(mass_overlap(u, shifted, mass) - 1.0) <= 1e-12
    w = rng.normal(size=3 * N)
    w[:N] -= np.mean(w[:N])
    w[N:2 * N] -= np.mean(w[N:2 * N])
    w -= np.sum(mass * u * w) / np.sum(mass * u * u) * u
    assert abs(mass_overlap(u, w, mass)) <= 1e-12
    mixed = 0.6 * u / np.sqrt(np.sum(mass * u * u)) - 0.8 * w / np.sqrt(np.sum(mass * w * w))
    assert abs(mass_overlap(u, mixed, mass) - 0.6) <= 1e-12


def test_the_onsets_are_where_the_critical_damping_first_exceeds_the_drag(branch):
    """onsets: a state where a pair is damped-unstable (critical_damping above eta) after one
    where none is, along the 24-disk branch (one segment), at three drags."""
    critical = np.array([critical_damping(e[e != 0]) for e in branch.eigenvalues])
    for damping in (0.001, 0.01, 0.05):
        eta = damping * SCENE.omega_0
        above = critical > eta
        expected = [k for k in range(len(branch)) if above[k] and (k == 0 or not above[k - 1])]
        assert onsets(branch, eta).tolist() == expected and expected, damping


def test_a_damped_unstable_pair_grows_at_re_s_and_returns_above_the_critical_damping(setting):
    """At the state with the largest critical damping on the 24-disk branch, along its fastest
    pair: at eta = 0.1 (below it) the run from 1e-10 delta_0 on the growing solution grows at
    Re s of s^2 + eta s + lambda = 0 (fit_growth of the pair's amplitude over the linear range:
    within 2 %); at 1.2 times the critical damping the same start returns (run_mode)."""
    branch, network, mass = setting
    critical = [critical_damping(e[e != 0]) for e in branch.eigenvalues]
    k = int(np.argmax(critical))
    q, xi, rows, gamma = state(branch, k)
    eta = 0.1
    mode = fastest(damped_modes(network, mass, q, xi, rows, gamma)[1], eta)
    s = mode.exponents(eta)[0]
    assert s.real > 0.1 * abs(s.imag)
    a = 1e-10 * SCENE.delta_0
    dq, v = a * mode.right.real, (a * s * mode.right).real
    run = simulate(network, q + dq, v, network.history_step(q, q + dq, gamma, gamma, xi, rows)[0],
                   rows, gamma, mass, time_step(branch.eigenvalues[k]), 20.0 / s.real, frames=400,
                   eta=eta)
    d = np.sqrt(np.sum(mass * (run.q - q) ** 2, axis=1))
    fit = fit_growth(run.t, np.abs(mode.amplitude(eta, run.q - q, run.v)), d,
                     LINEAR_RANGE * SCENE.delta_0)
    assert fit.reason == "ok" and fit.frames >= 100, fit
    assert abs(fit.sigma / s.real - 1.0) <= 2e-2, (fit.sigma, s.real)
    back = run_mode(network, mass, q, xi, rows, gamma, mode, 1.2 * critical[k], SCENE.delta_0)
    assert back.verdict == "returned" and back.gained == back.lost == 0
    assert back.distance <= 1.5 * back.start
    assert np.sqrt(np.sum(mass * back.displacement ** 2)) <= back.start


def test_the_runs_from_the_onsets_of_the_24_disk_branch(setting):
    """causality at eta = 0.05 omega_0: one run from each onset, along the state's fastest
    damped mode (its Re s the largest of damped_rates there), every verdict counted once; the
    branch has no plastic event, so no overlap."""
    branch, network, mass = setting
    eta = 0.05 * SCENE.omega_0
    found = causality(branch, network, mass, eta, SCENE.delta_0)
    assert found.states.tolist() == onsets(branch, eta).tolist()
    assert np.allclose(found.rates, damped_rates(branch.eigenvalues[found.states], eta), rtol=1e-9)
    assert sum(found.counts.values()) == len(found.outcomes) + len(found.failed)
    assert set(found.counts) == {*VERDICTS, "failed"}
    assert all(np.isnan(found.folds)) and all(o.overlap is None for o in found.outcomes)
    assert all(o.distance > 1e3 * o.start for o in found.outcomes)  # each grew


@pytest.mark.slow
def test_a_run_before_the_fold_rearranges_as_the_fold_does():
    """32 disks (seed 1) sheared through their first plastic event (gamma = 0.00260): at eta =
    0.1 omega_0 a run from an onset before the fold rearranges along the event's displacement
    (mass-weighted overlap above 0.9)."""
    from diskfriction.models.packing.prepared import prepare_scene
    from diskfriction.models.packing.shear import ShearParams, shear
    from diskfriction.scenes.packing import PackingScene

    scene = PackingScene(N=32, seed=1, gamma_range=(0.0, 0.0027), spectra="full")
    packing = prepare_scene(scene)
    branch = shear(scene, packing, ShearParams(workers=0), plastic_events=1)
    assert len(branch.plastic) == 1
    network = network_of(scene, packing)
    mass = mass_diagonal(network, scene.m, scene.inertia)
    found = causality(branch, network, mass, 0.1 * scene.omega_0, scene.delta_0)
    before = found.gamma < branch.plastic[0].gamma
    assert before.any() and (found.folds[before] == branch.plastic[0].gamma).all()
    assert any(o.verdict == "rearranged" and o.overlap > 0.9
               for o, b in zip(found.outcomes, before) if b), found.outcomes
