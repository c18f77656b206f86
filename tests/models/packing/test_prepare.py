"""Packing preparation (issue 25): FIRE finds minima, prepare reaches its target pressure with
every disk in equilibrium, near the jamming packing fraction, deterministically; rattlers; the
file round trip and its one-line errors. The force is the O(N^2) reference
(tests/packing_reference.py)."""
from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest

from diskfriction.errors import OneLineError
from diskfriction.models.packing.fire import fire, max_row_force
from diskfriction.models.packing.prepare import (PackingFileError, PreparationError, bidisperse_radii,
                                           box_side, contacts, load_packing, prepare, rattlers,
                                           save_packing)
from packing_reference import K_N, hertz_pair_forces

R = 0.5
F_TOL = 1e-8  # a contact carries ~P <2R> = 1.2e-2 at P = 1e-2: P known to ~1e-6


@pytest.fixture(scope="module")
def at_pressure():
    return prepare(32, 7, R, K_N, pressure=1e-2, pair_forces=hertz_pair_forces, f_tol=F_TOL)


def same_packing(a, b) -> bool:
    """Every field equal, the arrays bit for bit (dtype and shape included)."""
    def same(x, y):
        if isinstance(x, np.ndarray):
            return x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
        return type(x) is type(y) and x == y
    return all(same(getattr(a, f.name), getattr(b, f.name)) for f in fields(a))


def test_fire_reaches_the_minimum_of_an_anisotropic_quadratic():
    """E = (x - c)^T A (x - c) / 2, condition number 100: |F| <= f_tol and x within f_tol /
    lambda_min of c."""
    rng = np.random.default_rng(1)
    Q, _ = np.linalg.qr(rng.normal(size=(6, 6)))
    A = Q @ np.diag(np.geomspace(1, 100, 6)) @ Q.T
    c = rng.normal(size=6)
    result = fire(lambda x: (-A @ (x - c), 0.5 * (x - c) @ A @ (x - c)), np.zeros(6), 0.01,
                  1e-10, 100_000)
    assert result.converged and result.max_force <= 1e-10
    assert np.max(np.abs(result.x - c)) <= 1e-10
    assert result.energy <= 1e-20


def test_fire_stops_an_undamped_oscillation_by_its_uphill_restarts():
    """In 1D the mixing cannot damp: x'' = -x would oscillate for ever; FIRE zeroes v when
    F . v <= 0 and so comes to rest at x = 0 (131 steps, never without the restart)."""
    result = fire(lambda x: (-x, 0.5 * x @ x), np.ones(1), 0.1, 1e-10, 1000)
    assert result.converged and abs(result.x[0]) <= 1e-10


def test_fire_separates_three_overlapping_disks():
    """Three disks piled up in a roomy box end apart: no overlap left, zero energy."""
    radii = np.array([0.5, 0.5, 0.7])
    x0 = np.array([[2.0, 2.0], [2.3, 2.1], [2.1, 2.4]])
    result = fire(lambda x: hertz_pair_forces(x, radii, 6.0)[:2], x0, 0.002, 1e-12, 100_000)
    assert result.converged
    i, j = contacts(result.x, radii, 6.0)
    assert len(i) == 0 and result.energy == 0.0


def test_fire_converges_on_the_largest_force_per_row():
    """The criterion is max_i |F_i| over rows (per disk), not the largest component."""
    assert max_row_force(np.array([[3.0, 4.0], [0.0, 1.0]])) == 5.0
    assert max_row_force(np.array([-2.0, 1.0])) == 2.0


def test_fire_is_deterministic_and_leaves_x0_alone():
    radii = np.full(8, 0.5)
    x0 = np.random.default_rng(3).random((8, 2)) * 2.5
    kept = x0.copy()
    runs = [fire(lambda x: hertz_pair_forces(x, radii, 2.5)[:2], x0, 0.002, 1e-9, 50_000)
            for _ in range(2)]
    assert runs[0].x.tobytes() == runs[1].x.tobytes() and runs[0].steps == runs[1].steps
    assert np.array_equal(x0, kept)


def test_fire_reports_when_it_runs_out_of_steps():
    result = fire(lambda x: (-x, 0.5 * x @ x), np.ones(3), 0.01, 1e-12, 10)
    assert not result.converged and result.steps == 10 and result.max_force > 1e-12


def test_bidisperse_radii_have_the_asked_counts_in_a_drawn_order():
    radii = bidisperse_radii(11, R, 1.4, 0.3, rng=np.random.default_rng(0))
    assert np.sum(radii == R) == 3 and np.sum(radii == R * 1.4) == 8
    other = bidisperse_radii(11, R, 1.4, 0.3, rng=np.random.default_rng(1))
    assert not np.array_equal(radii, other)


def test_rattlers_are_removed_iteratively():
    """A braced core 0-3 (every pair touching) and a chain 0, 1 - 4 - 5 - 6: 5 and 6 have fewer
    than 3 contacts; without 5, 4 is left with 2 and rattles too; the core keeps 3 each."""
    i = np.array([0, 0, 0, 0, 1, 1, 1, 2, 4, 5])
    j = np.array([1, 2, 3, 4, 2, 3, 4, 3, 5, 6])
    assert rattlers(i, j, 7).tolist() == [False] * 4 + [True] * 3
    assert rattlers(i[:8], j[:8], 7).tolist() == [False] * 4 + [True] * 3  # 5, 6 without any


def test_contacts_match_every_pair_checked():
    rng = np.random.default_rng(5)
    radii = bidisperse_radii(40, R, rng=rng)
    L = box_side(radii, 0.7)
    positions = rng.random((40, 2)) * L
    i, j = np.triu_indices(40, 1)
    r_ij = positions[i] - positions[j]
    r_ij -= L * np.round(r_ij / L)
    touching = np.hypot(*r_ij.T) < radii[i] + radii[j]
    found = contacts(positions, radii, L)
    assert np.array_equal(found[0], i[touching]) and np.array_equal(found[1], j[touching])


def test_prepare_reaches_the_target_pressure_in_equilibrium(at_pressure):
    p = at_pressure
    assert abs(p.pressure / 1e-2 - 1) <= 1e-3
    assert np.all((p.positions >= 0) & (p.positions < p.L))
    F, energy, virial = hertz_pair_forces(p.positions, p.radii, p.L)
    assert np.max(np.hypot(*F[~p.rattlers].T)) <= F_TOL and p.max_force <= F_TOL
    assert p.pressure == virial / (2 * p.L ** 2) and p.energy == energy
    assert p.phi == pytest.approx(np.pi * np.sum(p.radii ** 2) / p.L ** 2, rel=1e-15)
    assert p.rattlers.sum() < 32 // 4


def test_pressure_is_minus_the_energy_derivative_in_the_area(at_pressure):
    """At equilibrium P = -dE/dA, A = L^2, under an affine dilation (positions and box scaled
    by lambda): P = -dE/dlambda / (2 L^2) at lambda = 1 (central difference)."""
    p, h = at_pressure, 1e-6
    E = [hertz_pair_forces(lam * p.positions, p.radii, lam * p.L)[1] for lam in (1 + h, 1 - h)]
    assert -(E[0] - E[1]) / (2 * h) / (2 * p.L ** 2) == pytest.approx(p.pressure, rel=1e-4)


def test_prepare_is_deterministic_per_seed(at_pressure):
    again = prepare(32, 7, R, K_N, pressure=1e-2, pair_forces=hertz_pair_forces, f_tol=F_TOL)
    assert same_packing(at_pressure, again)
    other = prepare(32, 8, R, K_N, phi=0.86, pair_forces=hertz_pair_forces, f_tol=F_TOL)
    assert not np.array_equal(other.positions, at_pressure.positions)


@pytest.mark.slow
def test_packing_fraction_at_a_small_pressure_is_near_jamming():
    """2D bidisperse (1.4, 50:50) disks jam near phi = 0.84; at P = 1e-2 (overlaps ~5e-4 of a
    diameter) a packing of 64 lies within 0.80 .. 0.90."""
    p = prepare(64, 2, R, K_N, pressure=1e-2, pair_forces=hertz_pair_forces, f_tol=F_TOL)
    assert 0.80 < p.phi < 0.90 and p.target == "pressure" and p.relaxations >= 2


def test_prepare_at_phi_relaxes_once_in_the_asked_box():
    p = prepare(16, 1, R, K_N, phi=0.9, pair_forces=hertz_pair_forces, f_tol=1e-6)
    assert p.phi == pytest.approx(0.9, rel=1e-14) and p.relaxations == 1 and p.pressure > 0


def test_prepare_refuses_a_pressure_out_of_reach():
    with pytest.raises(PreparationError, match="no jammed state below phi = 0.95"):
        prepare(8, 0, R, K_N, pressure=1e4, pair_forces=hertz_pair_forces, f_tol=1e-3)


@pytest.mark.parametrize("asked", [{}, {"pressure": 1.0, "phi": 0.8}, {"pressure": -1.0},
                                   {"phi": 1.2}])
def test_prepare_needs_exactly_one_valid_target(asked):
    with pytest.raises(ValueError, match="prepare needs") as error:
        prepare(8, 0, R, K_N, pair_forces=hertz_pair_forces, f_tol=1e-8, **asked)
    assert isinstance(error.value, OneLineError) and "\n" not in str(error.value)


def test_save_and_load_give_back_the_same_packing(at_pressure, tmp_path):
    save_packing(tmp_path / "packing.npz", at_pressure)
    assert same_packing(load_packing(tmp_path / "packing.npz"), at_pressure)


def test_a_damaged_or_foreign_file_is_one_line_naming_it(at_pressure, tmp_path):
    path = tmp_path / "packing.npz"
    save_packing(path, at_pressure)
    path.write_bytes(path.read_bytes()[:300])
    foreign = tmp_path / "foreign.npz"
    np.savez(foreign, x=np.zeros(3))
    for bad, says in [(path, "cannot read"), (foreign, "not a packing file"),
                      (tmp_path / "missing.npz", "cannot read")]:
        with pytest.raises(PackingFileError, match=says) as error:
            load_packing(bad)
        assert str(bad) in str(error.value) and "\n" not in str(error.value)
