"""Dynamics of a packing from its shear branch (issue 25, docs/packings.md#dynamics): the
energy budget closes as dt^2, and a complex pair's growth rate measured in the dynamics is the
spectrum's, |Im sqrt(lambda)| of M^-1 J, within 2 %."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.packings.dynamics import distance, fastest_pair, growth_rate, simulate, time_step
from diskfriction.packings.equilibria import PackingEquilibria, mass_diagonal
from diskfriction.packings.shear import network_of
from diskfriction.scenes.packing import PackingScene

SCENE = PackingScene(N=24, seed=3, gamma_range=(0.0, 0.002))


@pytest.fixture(scope="module")
def setting(sheared):
    packing, branch, _ = sheared(SCENE)  # conftest.sheared: shared with test_packing_shear
    network = network_of(SCENE, packing)
    return branch, network, mass_diagonal(network, SCENE.m, SCENE.inertia)


def test_the_energy_budget_closes_as_dt_squared(setting):
    """From the equilibrium at gamma = 0 kicked with small random velocities: the drift of
    E_k + U_n - W_t stays below 1e-3 of the kinetic energy and falls 3.5 to 4.5 times when dt
    is halved (velocity Verlet's second order)."""
    branch, network, mass = setting
    v0 = np.random.default_rng(0).normal(size=branch.q.shape[1]) * 1e-4
    dt = time_step(branch.eigenvalues[0])
    drift = []
    for step in (dt, dt / 2):
        run = simulate(network, branch.q[0], v0, branch.xi[0], branch.rows[0], 0.0, mass,
                       step, 200.0)
        drift.append(np.abs(run.budget - run.budget[0]).max())
        assert drift[-1] <= 1e-3 * run.kinetic.max()
    assert 3.5 <= drift[0] / drift[1] <= 4.5


def test_a_complex_pair_grows_at_the_rate_of_the_spectrum(setting):
    """At the end of the branch one complex pair lambda of M^-1 J: the equilibrium displaced by
    1e-12 along its eigenvector grows as e^(sigma t), sigma = |Im sqrt(lambda)|; the fit of the
    mass-weighted distance's maxima between 1e-11 and 1e-6 is within 2 % of sigma."""
    branch, network, mass = setting
    k = len(branch) - 1
    lam = branch.eigenvalues[k]
    i, sigma = fastest_pair(lam)
    assert i >= 0
    problem = PackingEquilibria(network, branch.q[k], branch.xi[k], branch.rows[k],
                                branch.gamma[k], mass, SCENE.matrix)
    system = problem.eigensystem(branch.q[k], branch.gamma[k], vectors=True)
    j = int(np.argmin(np.abs(system.values - lam[i])))
    mode = np.real(system.vectors(j)[0])
    mode /= np.sqrt(np.sum(mass * mode * mode))
    run = simulate(network, branch.q[k] + 1e-12 * mode, np.zeros_like(mode), branch.xi[k],
                   branch.rows[k], branch.gamma[k], mass, time_step(lam), 30 / sigma,
                   frames=2000)
    fitted, used = growth_rate(run.t, distance(run, branch.q[k], mass), 1e-11, 1e-6)
    assert used >= 20 and abs(fitted / sigma - 1) <= 0.02, (fitted, sigma)


def test_a_run_at_rest_is_told_by_its_contacts_then_by_its_stress():
    from diskfriction.packings.runs import NOT_RELAXED, SLIPPED, AtRest

    assert AtRest(0.0, 0.0, 1, 0).outcome == AtRest(0.0, 0.0, 0, 2).outcome == "rearranged"
    assert AtRest(-2 * SLIPPED, 1e-3, 0, 0).outcome == "slipped"
    assert AtRest(0.5 * SLIPPED, 1e-6, 0, 0).outcome == "came back"
    assert NOT_RELAXED.outcome == "not relaxed" and NOT_RELAXED.opened is None
