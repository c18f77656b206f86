"""The precursor table (models/packing/precursors.py): the displacement field's measures against
closed forms, and the table of a 32-disk shear through a known fold."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.dynamics.damped_modes import critical_damping
from diskfriction.models.packing.damped import damped_hopfs
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.precursors import (EVENT_COLUMNS, displacement_field, event_rows,
                                                    participation_ratio, plane_overlap)
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, network_of, shear
from diskfriction.scenes.packing import PackingScene


def test_participation_ratio_of_one_disk_and_of_all_alike():
    one = np.zeros((40, 2))
    one[7] = (0.3, -0.1)
    assert participation_ratio(one) == pytest.approx(1 / 40, rel=1e-14)
    assert participation_ratio(np.tile([0.2, 0.5], (40, 1))) == pytest.approx(1.0, rel=1e-14)


def test_overlap_is_one_in_the_modes_plane_and_zero_across_it():
    rng = np.random.default_rng(3)
    mode = rng.normal(size=(20, 2)) + 1j * rng.normal(size=(20, 2))
    centred = mode - mode.mean(axis=0)
    inside = 0.3 * centred.real - 2.0 * centred.imag
    assert plane_overlap(inside, mode) == pytest.approx(1.0, rel=1e-12)
    basis = np.linalg.qr(np.stack([centred.real.ravel(), centred.imag.ravel()], axis=1))[0]
    other = rng.normal(size=40)
    across = (other - basis @ (basis.T @ other)).reshape(20, 2)
    assert plane_overlap(across, mode) == pytest.approx(0.0, abs=1e-12)


def test_the_field_is_the_translations_without_their_mean():
    N = 5
    q0, q1 = np.zeros(3 * N), np.arange(3 * N, dtype=float)
    u = displacement_field(q0, q1, N)
    assert np.allclose(u.mean(axis=0), 0.0) and np.allclose(u[:, 0], np.arange(N) - 2.0)
    assert np.allclose(u[:, 1], np.arange(N) - 2.0)  # y: N..2N-1, its mean N + 2 removed


@pytest.fixture(scope="module")
def fold_run():
    """32 disks, seed 2, to gamma = 0.0021: one plastic event, a fold (tests/models/packing/
    test_packing_plastic.py), and the precursor rows at the drags 0, 0.1 omega_0 and above the
    branch's largest critical damping."""
    scene = PackingScene(N=32, seed=2, gamma_range=(0.0, 0.0021))
    packing = prepare_scene(scene)
    branch = shear(scene, packing, ShearParams(workers=0), plastic_events=5)
    network = network_of(scene, packing)
    mass = mass_diagonal(network, scene.m, scene.inertia)
    above = 1.01 * max(critical_damping(e) for e in branch.eigenvalues) / scene.omega_0
    drags = (0.0, 0.1, above)
    hopfs = {d: damped_hopfs(network, mass, branch, d * scene.omega_0) for d in drags}
    return scene, branch, hopfs, event_rows(network, mass, branch, scene.omega_0, hopfs), drags


@pytest.mark.slow
def test_the_table_of_a_known_fold(fold_run):
    scene, branch, hopfs, rows, drags = fold_run
    assert len(branch.plastic) == 1 and [r["drag"] for r in rows] == list(drags)
    event = branch.plastic[0]
    last = int(np.flatnonzero(branch.segment == 0)[-1])
    u = event.after[0] - branch.u[last]
    x, y = u[:32] - u[:32].mean(), u[32:64] - u[32:64].mean()
    for row in rows:
        assert tuple(row) == EVENT_COLUMNS
        assert row["kind"] == "fold" and abs(row["fold_lambda"]) < 1e-9  # a real eigenvalue at 0
        assert row["gamma"] == event.gamma and row["drop"] == event.stress_before - event.stress_after
        assert row["displacement"] == pytest.approx(np.sqrt(np.sum(x * x + y * y)), rel=1e-12)
    undamped, damped, overdamped = rows
    births = [c.p for c in branch.collisions if c.kind == "birth" and c.p < event.gamma]
    assert undamped["onset_gamma"] == births[-1]  # eta = 0: the last birth before the fold
    assert undamped["strain_gap"] == event.gamma - births[-1]
    onsets = [h.gamma for h in hopfs[0.1] if h.kind == "onset" and h.gamma < event.gamma]
    assert damped["onset_gamma"] == onsets[-1] and 0 <= damped["overlap"] <= 1
    assert undamped["unstable_at_event"] and damped["unstable_at_event"]
    assert overdamped["onset_gamma"] is None and not overdamped["unstable_at_event"]
    assert overdamped["growth_at_event"] < 0


def test_chance_of_being_preceded_against_its_closed_form():
    """Onsets at 0.3 and 0.7 of a segment [0, 1]: 70 % of it has one before it; the gaps run
    from 0 to 0.4 over [0.3, 0.7) and 0 to 0.3 over [0.7, 1]: below g <= 0.3 lies the strain 2 g
    of the 0.7, so the median is 0.175 (to the grid's spacing)."""
    from diskfriction.models.packing.precursors import chance

    fraction, gap = chance(np.array([0.7, 0.3]), 0.0, 1.0, points=10_000)
    assert fraction == pytest.approx(0.7, abs=1e-4) and gap == pytest.approx(0.175, abs=1e-3)
    assert chance(np.array([]), 0.0, 1.0) == (0.0, None)
