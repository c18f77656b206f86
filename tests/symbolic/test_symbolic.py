"""Generated kernels against the independent mpmath transcription of docs/model.md.

Stiffness reference (jacobian_check.py): central differences of the reference forces in 50-digit
arithmetic, with the history following q by docs/model.md's increments (midpoint rule). Step h = 1e-8 min(delta) over
the active contacts: it keeps every contact's open/closed state and stays in the analytic
region of each law (truncation error ~ (h / delta)^2 ~ 1e-16, and ~ h / t* ~ 3e-10 at the
xi = 0 kink of xi |xi|), while 50 digits make the rounding error (1e-50 / h) irrelevant.
In double precision such a step is impossible at delta ~ 1e-10 (rounding 1e-16 / h ~ 1), which
is why the reference is not the generated code's own finite difference.

Error measure: for each row r of a matrix, max_c |J_rc - J^ref_rc| / max_c |J^ref_rc|; rows whose
reference is exactly zero must be exactly zero. Tolerance 1e-6 (issue #2).
"""
from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

import reference_model as ref
from diskfriction.scenes import Effects, Scene
from jacobian_check import (N, PARAMS, all_effects, effects_id, generated, random_state, reference,
                            worst_errors)
from diskfriction.symbolic import System, load_kernels

STATES = 50
TOL = 1e-6


@pytest.mark.parametrize("effects", all_effects(), ids=effects_id)
@pytest.mark.slow
def test_jacobian_matches_finite_differences(effects: Effects):
    """Per contact block and assembled: relative error <= 1e-6 at 50 random admissible states,
    half of them with a contact at delta ~ 1e-10, histories |xi|/t* in {0, 1e-8, 0.5, 1-1e-8}."""
    worst = worst_errors(effects, STATES)
    assert worst["tiny_contacts"] >= 20, worst  # the delta ~ 1e-10 case was really visited
    assert worst["assembled"] <= TOL, worst
    assert worst["contact"] <= TOL, worst


@pytest.mark.parametrize("effects", all_effects(), ids=effects_id)
def test_forces_match_reference_and_each_other(effects: Effects):
    """Generated F equals the reference to 1e-12; the force-only path (its own cse, so another
    order of operations) equals the F+J path to rounding, 1e-14."""
    kernels = load_kernels(effects)
    rng = np.random.default_rng(7)
    for case in range(20):
        q, xi, L = random_state(rng, N, effects.rotation, case, effects.normal)
        m = reference(effects, N, L)
        F, _, _, _, _ = generated(kernels, q, xi, L)
        F_only = np.empty_like(F)
        kernels.forces(q, xi, 0.0, np.array([*PARAMS.values(), L]), F_only)
        F_ref = np.array([float(v) for v in ref.forces(m, [mp.mpf(v) for v in q],
                                                         [mp.mpf(v) for v in xi], 0)])
        scale = np.abs(F_ref).max() + PARAMS["F_y"]
        assert np.abs(F - F_ref).max() <= 1e-12 * scale
        assert np.abs(F - F_only).max() <= 1e-14 * scale


@pytest.mark.parametrize("rotation", [True, False])
def test_frictionless_jacobian_is_symmetric_and_force_is_minus_gradient(rotation):
    """Hertz only: J = J^T to 1e-12 and F = -grad U, U = sum 2/5 k_n delta^(5/2) + loads."""
    effects = Effects("none", False, False, rotation)
    kernels = load_kernels(effects)
    rng = np.random.default_rng(3)
    for case in range(20):
        q, xi, L = random_state(rng, N, rotation, case)
        m = reference(effects, N, L)
        F_x = 0.05
        params = np.array([*PARAMS.values(), L])
        F = np.empty(q.size)
        kernels.forces(q, xi, F_x, params, F)
        J = generated(kernels, q, xi, L)[1]
        assert np.abs(J - J.T).max() <= 1e-12 * np.abs(J).max()
        grad = [float(g) for g in (mp.diff(lambda t: ref.hertz_energy(
            m, [mp.mpf(v) + (t if c == i else 0) for c, v in enumerate(q)], F_x), 0)
            for i in range(q.size))]
        assert np.abs(F + np.array(grad)).max() <= 1e-10 * (np.abs(F).max() + PARAMS["F_y"])


@pytest.mark.parametrize("eps", [0.0, 1e-3, 1e-5])
def test_rest_state_is_an_equilibrium(eps):
    """docs/model.md#history: the analytic F_x = 0 state (also pre-compressed, eps > 0) has |F| <= 1e-12."""
    system = System.from_scene(Scene(eps=eps))
    q, xi = system.rest_state()
    assert np.abs(system.forces(q, xi, 0.0)).max() <= 1e-12


def test_rest_state_y_modes_sit_at_hertz_stiffness():
    """docs/model.md#units, eps = 0: N eigenvalues of J at lambda = 1.5 k_n delta_w^(1/2) = 110.52."""
    system = System.from_scene(Scene())
    q, xi = system.rest_state()
    lam_y = 1.5 * system.scene.k_n * np.sqrt(system.scene.delta_w0)
    assert lam_y == pytest.approx(110.52, rel=5e-5)
    eig = np.linalg.eigvals(system.jacobian(q, xi))
    at_y = np.abs(eig - lam_y) <= 1e-9 * lam_y
    assert at_y.sum() == system.N
    assert np.all(eig[at_y].imag == 0)


def test_nothing_is_nan_at_hard_states():
    """delta exactly 0 (the paper's rest state), delta = 1e-300, xi = 0, |xi| = t*: finite."""
    system = System.from_scene(Scene())
    q, xi = system.rest_state()
    assert np.all(system.overlaps(q)[:system.N] == 0.0)  # eps = 0: pairs exactly touching
    for delta_w in (1e-300, 1e-10, system.scene.delta_w0):
        q[system.N:2 * system.N] = system.scene.R - delta_w
        t_star = system.scene.mu * system.scene.k_n * delta_w / system.scene.k_t
        for ratio in (0.0, 1.0, -1.0):
            xi[system.N:] = ratio * t_star
            F, J = system.forces_and_jacobian(q, xi, 0.05)
            assert np.all(np.isfinite(F)) and np.all(np.isfinite(J))
