"""Dynamics of a packing from its shear branch (issue 25, docs/packings.md#dynamics): the
energy budget closes as dt^2, and a complex pair's growth rate measured in the dynamics is the
spectrum's, |Im sqrt(lambda)| of M^-1 J, within 0.1 %."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.models.packing.dynamics import fastest_pair, simulate, time_step
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.runs import run_from_state
from diskfriction.models.packing.shear import network_of
from diskfriction.scenes.packing import PackingScene

SCENE = PackingScene(N=24, seed=3, gamma_range=(0.0, 0.002))


@pytest.fixture(scope="module")
def setting(sheared):
    packing, branch, _ = sheared(SCENE)  # conftest.sheared: shared with test_packing_shear
    network = network_of(SCENE, packing)
    return branch, network, mass_diagonal(network, SCENE.m, SCENE.inertia)


@pytest.mark.slow
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


@pytest.mark.slow
def test_a_complex_pair_grows_at_the_rate_of_the_spectrum(setting):
    """At the end of the branch one complex pair lambda of M^-1 J: the equilibrium started on
    its growing solution at 1e-12 grows as e^(sigma t), sigma = |Im sqrt(lambda)|; the fit of
    the pair's amplitude over the linear range is within 0.1 % of sigma (velocity Verlet's
    error at the default step is 0.03 %)."""
    branch, network, mass = setting
    k = len(branch) - 1
    done = run_from_state(branch, k, network, mass, "eigenvector", 1e-12, 30 / fastest_pair(
        branch.eigenvalues[k])[1], SCENE.delta_0)
    assert done.fit.reason == "ok" and done.fit.frames >= 100, done.fit
    assert abs(done.sigma_measured / done.sigma_predicted - 1) <= 1e-3, done.fit


def test_a_run_at_rest_is_told_by_its_contacts_then_by_its_stress():
    from diskfriction.models.packing.runs import NOT_RELAXED, SLIPPED, AtRest

    assert AtRest(0.0, 0.0, 1, 0).outcome == AtRest(0.0, 0.0, 0, 2).outcome == "rearranged"
    assert AtRest(-2 * SLIPPED, 1e-3, 0, 0).outcome == "slipped"
    assert AtRest(0.5 * SLIPPED, 1e-6, 0, 0).outcome == "came back"
    assert NOT_RELAXED.outcome == "not relaxed" and NOT_RELAXED.opened is None
