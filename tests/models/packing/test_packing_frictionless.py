"""A frictionless packing sheared (docs/packings.md#shear): mu = 0, or the tangential law "none",
is the baseline of every frictional result. Without tangential forces the disks' rotations carry
no force, so the unknowns are the positions alone, J is the symmetric Hessian of the Hertz
energy and the tracked spectrum of M^-1 J is real: no complex pair can exist. The shear runs
through its plastic events (folds, relaxed by FIRE without friction) to the end of its range."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.models.packing.equilibria import NotJammed, PackingEquilibria, mass_diagonal, start
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, network_of, shear
from diskfriction.scenes import Effects
from diskfriction.scenes.packing import PackingScene

SCENE = PackingScene(N=32, mu=0.0, gamma_range=(0.0, 0.01))


@pytest.fixture(scope="module")
def packing():
    return prepare_scene(SCENE)


@pytest.fixture(scope="module")
def branch(packing):
    return shear(SCENE, packing, ShearParams(workers=0), plastic_events=20)


def problem_at_start(scene, packing) -> PackingEquilibria:
    network = network_of(scene, packing)
    q, xi, rows = start(network, packing.positions)
    return PackingEquilibria(network, q, xi, rows, 0.0,
                             mass_diagonal(network, scene.m, scene.inertia), scene.matrix)


def test_a_frictionless_packing_shears_through_its_plastic_events_to_the_end(branch):
    """The whole range is sheared, each fold relaxed (without friction) and the shear gone on
    from there; every point in force balance to the corrector's tolerance, and the rotations
    never move (no torque acts on a disk)."""
    assert branch.status.reached and branch.gamma[-1] == SCENE.gamma_range[1]
    assert len(branch.plastic) >= 1 and branch.segment.max() == len(branch.plastic)
    assert all(event.kind == "fold" for event in branch.plastic)
    assert branch.residual.max() <= ShearParams().newton_tol
    assert np.all(np.diff(branch.gamma) > 0)
    assert not branch.q[:, 2 * SCENE.N:].any()
    assert not any(xi.any() for xi in branch.xi)
    first = np.flatnonzero(branch.segment == 0)[-1]  # positive strain loads the packing
    assert branch.stress[first, 2] > branch.stress[0, 2]


def test_no_complex_pair_is_ever_found_and_j_is_symmetric_at_every_point(branch, packing):
    """J, the Hessian of the Hertz energy, is symmetric to rounding at every accepted point; the
    tracked spectrum of M^-1 J is real, exactly: no complex pair and no collision anywhere."""
    network = network_of(SCENE, packing)
    for k in range(len(branch)):
        J = network.evaluate(branch.q[k], branch.xi[k], branch.rows[k], branch.gamma[k])[1]
        assert abs(J - J.T).max() <= 1e-12 * abs(J).max()
    assert not branch.n_complex.any() and not branch.collisions
    assert not branch.eigenvalues.imag.any()


@pytest.mark.slow
def test_a_spectral_window_tracks_the_dense_spectrums_real_eigenvalues(branch, packing):
    """With a window (sparse shift-invert of the non-symmetric tracked matrix) the eigenvalues
    in it are the dense run's, real, at the same points; no collision is found."""
    windowed = shear(SCENE, packing, ShearParams(workers=0), plastic_events=20, window=(-3.0, 8.0))
    assert np.array_equal(windowed.gamma, branch.gamma) and not windowed.collisions
    assert not windowed.n_complex.any() and not np.nan_to_num(windowed.eigenvalues.imag).any()
    for dense, window in zip(branch.eigenvalues, windowed.eigenvalues):
        inside = np.sort(dense[(dense != 0) & (dense.real >= -3) & (dense.real <= 8)].real)
        seen = np.sort(window[~np.isnan(window) & (window.real >= -3) & (window.real <= 8)].real)
        assert inside.size == seen.size and np.allclose(inside, seen, rtol=0, atol=1e-9)


def test_the_unknowns_are_the_positions_and_the_spectrum_is_the_networks(packing):
    """The tracked spectrum is that of the network's M^-1 J without its zeros (the two
    translations, every rotation, the loose disks' positions): 2 (N - loose) - 2 eigenvalues,
    real; its right and left vectors (rows l^H) are the tracked matrix's, normalised l^H r = 1."""
    problem = problem_at_start(SCENE, packing)
    q, N = problem.q_c, SCENE.N
    loose = int(problem.gauge.loose.sum())
    assert problem.gauge.kept.size == 2 * (N - loose) - 2 and (problem.gauge.kept < 2 * N).all()
    full = np.linalg.eigvals(problem.physical(q, 0.0).toarray())
    system = DenseSpectra().eigensystem(problem, q, 0.0, vectors=True)
    tracked = system.values[~system.excluded]
    zeros = 2 + N + 2 * loose
    nonzero = np.sort(full[np.argsort(np.abs(full))[zeros:]].real)
    assert np.allclose(nonzero, np.sort(tracked.real), rtol=0, atol=1e-9 * np.abs(full).max())
    assert not tracked.imag.any()
    A = problem.stability_matrix(q, 0.0).toarray()
    columns = system.columns[~system.excluded]
    right, left = system.right[:, columns], system.left[columns]
    scale = np.abs(tracked).max()
    assert np.abs(A @ right - right * tracked).max() <= 1e-9 * scale * np.abs(right).max()
    assert np.abs(left @ A - tracked[:, None] * left).max() <= 1e-9 * scale * np.abs(left).max()
    assert np.allclose(np.einsum("ij,ji->i", left, right), 1.0, rtol=0, atol=1e-9)


def test_mu_above_zero_without_a_tangential_law_is_the_same_branch(branch, packing):
    """tangential = "none" with mu = 10 is the frictionless packing: the same branch to the bit
    (mu acts only through a tangential law)."""
    scene = replace(SCENE, mu=10.0, effects=Effects(wall_friction=False, tangential="none"))
    other = shear(scene, packing, ShearParams(workers=0), plastic_events=20)
    assert np.array_equal(other.gamma, branch.gamma) and np.array_equal(other.q, branch.q)
    assert np.array_equal(other.eigenvalues, branch.eigenvalues)
    assert [e.gamma for e in other.plastic] == [e.gamma for e in branch.plastic]


@pytest.mark.slow
def test_bifurcate_shears_the_frictionless_copy_of_the_packing_scene(tmp_path, capsys):
    """The packaged scene with N = 32, mu = 0 and gamma = [0, 0.01] (it stopped at the start,
    "no equilibrium found"): exit 0, the whole range written, every eigenvalue real."""
    from diskfriction.cli.main import main

    text = (Path(__file__).resolve().parents[3] / "scenes" / "packing.toml").read_text()
    for old, new in (("N = 256 ", "N = 32 "), ("mu = 10.0 ", "mu = 0.0 "),
                     ("gamma = [0.0, 0.05]", "gamma = [0.0, 0.01]")):
        assert old in text
        text = text.replace(old, new)
    scene = tmp_path / "frictionless.toml"
    scene.write_text(text)
    assert main(["bifurcate", str(scene), "--out", str(tmp_path / "out")]) == 0, capsys.readouterr().err
    with np.load(tmp_path / "out" / "branch.npz") as branch:
        assert branch["gamma"][-1] == 0.01 and branch["residual"].max() <= 1e-11
        assert not branch["eigenvalues"].imag.any() and not branch["n_complex"].any()
    assert "0 collisions" in capsys.readouterr().out


@pytest.mark.slow
def test_a_relaxation_that_unjams_the_packing_ends_the_shear_in_one_line(tmp_path, capsys):
    """32 frictionless disks, seed 2 (prepared at phi = 0.8406): the relaxation after the plastic
    event near gamma = 0.0204 leaves no disk held by two contacts, an unjammed packing at that
    strain. bifurcate says so in one line naming the strain, exit 1, no traceback."""
    from diskfriction.cli.main import main

    scene = tmp_path / "unjams.toml"
    scene.write_text('geometry = "packing"\n[packing]\nN = 32\nseed = 2\n[contacts]\nmu = 0.0\n'
                     "[shear]\ngamma = [0.0, 0.021]\n")
    assert main(["bifurcate", str(scene), "--out", str(tmp_path / "out")]) == 1
    line = capsys.readouterr().err.strip().splitlines()[-1]
    assert line.startswith(f"bifurcate error: {scene}: after the plastic event at gamma = 0.0203")
    assert "not jammed" in line and "p0" not in line
    assert line.endswith(f"(the segments finished before it are kept in {tmp_path / 'out' / 'segments'}: "
                         "a rerun resumes after them)")


def test_a_branch_that_cannot_start_says_where_in_words():
    """The core's start failures name the parameter's value in words, never an internal name:
    no equilibrium (u^2 + 1 = 0 has no root), and no tangent (u^2 = 0 at u = 0, G_p = 0)."""
    from diskfriction.continuation.stepping.arclength import ContinuationError, continuation
    from diskfriction.continuation.problem import FunctionProblem

    rootless = FunctionProblem(lambda u, p: u**2 + 1, lambda u, p: np.diag(2 * u),
                               lambda u, p: np.zeros(1))
    with pytest.raises(ContinuationError) as none:
        continuation(rootless, np.array([0.3]), 0.5, workers=0)
    assert str(none.value).startswith("no equilibrium found at the start of the branch, parameter = 0.5 (")
    singular = FunctionProblem(lambda u, p: u**2, lambda u, p: np.diag(2 * u), lambda u, p: np.zeros(1))
    with pytest.raises(ContinuationError) as flat:
        continuation(singular, np.array([0.0]), 0.0, workers=0)
    assert str(flat.value).startswith("the branch has no tangent at its start, parameter = 0 (")
    assert "p0" not in str(none.value) + str(flat.value)


@pytest.mark.slow
def test_a_packing_that_unjams_under_shear_ends_there_in_one_line():
    """64 frictionless disks, seed 1, prepared at P = 0.1: at fixed area the shear unloads the
    packing across its plastic events until every contact is below delta_hold and no disk is
    held by two. The shear ends there with one line naming the strain, the pressure of the last
    segment passed fallen over a thousandfold."""
    scene = PackingScene(N=64, seed=1, mu=0.0, gamma_range=(0.0, 0.0087))
    passed = []
    with pytest.raises(NotJammed) as unjammed:
        shear(scene, prepare_scene(scene), ShearParams(workers=0), plastic_events=50,
              on_segment=passed.append)
    message = str(unjammed.value)
    assert message.startswith("sheared to gamma = ") and "not jammed" in message and "\n" not in message
    strain = float(message.split("sheared to gamma = ")[1].split(",")[0])
    assert passed and passed[-1].gamma[-1] < strain <= scene.gamma_range[1]
    pressure = [-(s[0] + s[1]) / 2 for s in (passed[0].stress[0], passed[-1].stress[-1])]
    assert pressure[1] < 1e-3 * pressure[0]


def test_a_frictionless_run_counts_no_sliding_update(branch, packing):
    """Dynamics of the frictionless packing from its sheared state with random velocities: no
    contact carries a tangential force, so none slides (the Coulomb cap at t* = 0 acted at
    every step and was counted, about 1e5 updates in 100 time units), and the energy budget
    E_k + U_n closes."""
    from diskfriction.models.packing.dynamics import simulate, time_step

    network = network_of(SCENE, packing)
    mass = mass_diagonal(network, SCENE.m, SCENE.inertia)
    k = len(branch) - 1
    v = np.random.default_rng(1).normal(size=network.ndof) * 1e-6
    run = simulate(network, branch.q[k], v, branch.xi[k], branch.rows[k], branch.gamma[k], mass,
                   time_step(branch.eigenvalues[k]), 100.0)
    assert not run.capped.any()
    assert np.ptp(run.budget) <= 1e-3 * run.kinetic.max()
