"""The normal laws (scenes.rules.NORMAL_LAWS): the functions printed from symbolic/laws.py into
the kernel module against the independent mpmath transcription (reference_model.py), the
scene's rest overlap and stiffness against them, and a sweep and a run with a law that is not
the paper's (Hooke, F_n = k_n delta)."""
from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

import reference_model as ref
from diskfriction.models.chain.sweep import sweep
from diskfriction.dynamics import Perturbation, simulate
from diskfriction.scenes import NORMAL_LAWS, Effects, Scene
from diskfriction.symbolic import System, load_kernels

K_N, K_T, MU = 2000.0, 2000.0 * 2 / 7, 10.0
DELTAS = (1e-10, 1e-4, 3e-3)


@pytest.mark.parametrize("normal", NORMAL_LAWS)
def test_law_functions_match_the_mpmath_reference(normal):
    """F_n, dF_n/ddelta (mpmath's derivative of the reference F_n), U_n (its quadrature from 0)
    and t* to 1e-13 relative; t* on an array of delta equals it contact by contact."""
    k = load_kernels(Effects(normal=normal))
    force = lambda d: ref.normal_force(normal, K_N, d)
    for delta in DELTAS:
        d = mp.mpf(delta)
        pairs = [(k.normal_force(delta, K_N), force(d)),
                 (k.normal_stiffness(delta, K_N), mp.diff(force, d)),
                 (k.normal_energy(delta, K_N), mp.quad(force, [0, d])),
                 (k.coulomb_limit(delta, K_N, K_T, MU), ref.coulomb_limit(normal, K_N, K_T, MU, d))]
        for value, reference in pairs:
            assert abs(value - float(reference)) <= 1e-13 * abs(float(reference)), (delta, value)
    deltas = np.array(DELTAS)
    assert np.array_equal(k.coulomb_limit(deltas, K_N, K_T, MU),
                          [k.coulomb_limit(d, K_N, K_T, MU) for d in DELTAS])


@pytest.mark.parametrize("normal", NORMAL_LAWS)
def test_rest_overlap_and_stiffness_of_the_scene_are_the_kernels(normal):
    """F_n(delta_w0) = F_y and kappa_w0 = dF_n/ddelta(delta_w0) to rounding; the rest state is
    an equilibrium, and its N y modes sit at kappa_w0 (eps = 0)."""
    system = System.from_scene(Scene(effects=Effects(normal=normal)))
    s, k = system.scene, system.kernels
    assert k.normal_force(s.delta_w0, s.k_n) == pytest.approx(s.F_y, rel=1e-14)
    assert k.normal_stiffness(s.delta_w0, s.k_n) == pytest.approx(s.kappa_w0, rel=1e-14)
    q, xi = system.rest_state()
    assert np.abs(system.forces(q, xi, 0.0)).max() <= 1e-12
    eig = np.linalg.eigvals(system.jacobian(q, xi))
    assert np.sum(np.abs(eig - s.kappa_w0) <= 1e-9 * s.kappa_w0) == s.N


def test_hertz_and_hooke_differ_where_they_should():
    """The law really changes the scene: Hooke's rest overlap F_y / k_n, stiffness k_n."""
    hertz, hooke = Scene(), Scene(effects=Effects(normal="hooke"))
    assert hooke.delta_w0 == hooke.F_y / hooke.k_n and hooke.kappa_w0 == pytest.approx(hooke.k_n)
    assert hertz.delta_w0 == pytest.approx((hertz.F_y / hertz.k_n) ** (2 / 3), rel=1e-15)
    assert hertz.kappa_w0 == pytest.approx(1.5 * hertz.k_n * hertz.delta_w0 ** 0.5, rel=1e-14)


def test_a_hooke_sweep_and_run_work():
    """A sweep of the paper's chain with Hooke contacts reaches its end in equilibrium with no
    history beyond t*, and a short run from its last point closes its energy budget (which
    holds only if normal_energy is the integral of the force the kernels apply)."""
    system = System.from_scene(Scene(effects=Effects(normal="hooke")))
    branch = sweep(system, 0.0, 0.06)
    assert branch.F_x[-1] == 0.06
    assert branch.residual.max() <= 1e-10
    for q, xi in zip(branch.q, branch.xi):
        assert np.all(np.abs(xi) <= system.coulomb_limit(system.overlaps(q)) * (1 + 1e-12))
    run = simulate(system, branch.q[-1], branch.xi[-1], 0.06, 20.0,
                   perturbation=Perturbation("random-velocity", 1e-6))
    assert run.accurate and run.budget_relative() < 1e-3
