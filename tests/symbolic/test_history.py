"""The history rule of one step: docs/model.md's increments (midpoint), reset, first contact, cap."""
from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest

import reference_model as ref
from jacobian_check import N, all_effects, effects_id, random_state, reference
from diskfriction.scenes import Effects, Scene
from diskfriction.symbolic import System, load_kernels


@pytest.mark.parametrize("effects", all_effects(), ids=effects_id)
def test_increment_matches_reference_midpoint_rule(effects):
    kernels = load_kernels(effects)
    rng = np.random.default_rng(11)
    for case in range(10):
        q0, xi, L = random_state(rng, N, effects.rotation, case, effects.normal)
        q1 = q0 + rng.normal(0, 1e-4, q0.size)
        params = np.array([0.5, 2000.0, 2000.0 * 2 / 7, 10.0, 0.1, L])
        dxi = np.empty(2 * N)
        kernels.history_increment(q0, q1, params, dxi)
        expected = ref.increment(reference(effects, N, L), [mp.mpf(v) for v in q0], [mp.mpf(v) for v in q1])
        assert np.abs(dxi - [float(v) for v in expected]).max() <= 1e-12 * np.abs(q1 - q0).max()


def test_rolling_without_slip_does_not_charge_the_substrate():
    """dx = -R dtheta: xi_w = dx + R dtheta = 0 (theta counter-clockwise, docs/model.md#contacts)."""
    s = System.from_scene(Scene())
    q0, xi0 = s.rest_state()
    q1 = q0.copy()
    q1[:s.N] += 1e-4
    q1[2 * s.N:] -= 1e-4 / s.scene.R
    xi1, _ = s.history_step(q0, q1, xi0)
    rounding = 4 * np.finfo(float).eps * np.abs(q1).max()  # of the displacements q1 - q0
    assert np.abs(xi1[s.N:]).max() <= rounding


def test_sliding_without_rolling_charges_the_substrate_by_the_displacement():
    s = System.from_scene(Scene())
    q0, xi0 = s.rest_state()
    q1 = q0.copy()
    q1[:s.N] += 1e-6
    xi1, slid = s.history_step(q0, q1, xi0)
    rounding = 4 * np.finfo(float).eps * np.abs(q1).max()
    assert np.abs(xi1[s.N:] - 1e-6).max() <= rounding and not slid.any()


def step_one_contact(xi0, dxi, delta0, delta1, cap=True, conventions="model"):
    s = System.from_scene(Scene(N=2, effects=Effects(conventions=conventions)))
    xi1, slid = np.empty(1), np.empty(1, dtype=np.bool_)
    n = s.kernels.commit_history(np.array([xi0]), np.array([dxi]), np.array([delta0]),
                                 np.array([delta1]), s.params, cap, xi1, slid)
    return xi1[0], bool(slid[0]), n


def test_opening_resets_and_first_contact_charges_only_after_closing():
    assert step_one_contact(1e-6, 1e-7, 1e-4, -1e-6)[0] == 0.0
    assert step_one_contact(0.0, 1e-7, -3e-6, 1e-6)[0] == pytest.approx(0.25e-7, rel=1e-15)
    assert step_one_contact(0.0, 1e-7, 0.0, 1e-6)[0] == 1e-7  # touching at the start: all of it
    assert step_one_contact(2e-7, 1e-7, 1e-4, 1e-4)[0] == pytest.approx(3e-7, rel=1e-15)


def test_lammps_conventions_charge_a_closing_contact_with_the_whole_step():
    """LAMMPS finds a contact closed at the end of a step and charges it with v_t dt."""
    assert step_one_contact(0.0, 1e-7, -3e-6, 1e-6, conventions="lammps")[0] == 1e-7
    assert step_one_contact(1e-6, 1e-7, 1e-4, -1e-6, conventions="lammps")[0] == 0.0
    assert step_one_contact(2e-7, 1e-7, 1e-4, 1e-4, conventions="lammps")[0] == pytest.approx(3e-7, rel=1e-15)


def test_coulomb_cap_sets_the_history_to_its_limit_and_reports_sliding():
    s = Scene()
    delta = 1e-4
    t_star = s.mu * s.k_n * delta / s.k_t
    xi1, slid, n = step_one_contact(0.9 * t_star, -0.3 * t_star, delta, delta)
    assert (xi1, slid, n) == (pytest.approx(0.6 * t_star), False, 0)
    xi1, slid, n = step_one_contact(-0.9 * t_star, -0.3 * t_star, delta, delta)
    assert (xi1, slid, n) == (-t_star, True, 1)
    xi1, slid, n = step_one_contact(-0.9 * t_star, -0.3 * t_star, delta, delta, cap=False)
    assert (xi1, slid) == (pytest.approx(-1.2 * t_star), False)
