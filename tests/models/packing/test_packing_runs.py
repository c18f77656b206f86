"""Runs from states of a packing's shear branch (models/packing/runs.py, docs/packings.md#dynamics):
the eigenvector start is the fastest pair's growing solution in the full state, the growth
rate is fitted from the pair's complex amplitude (no maxima needed), or one line says why not
and what to change, and a run ends at exactly its t_end."""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from diskfriction.cli.main import main
from diskfriction.models.packing.dynamics import fastest_pair, simulate, time_step
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.runs import GrowingMode, linearized, run_from_state
from diskfriction.models.packing.shear import network_of
from diskfriction.scenes.packing import PackingScene

SCENE = PackingScene(N=24, seed=3, gamma_range=(0.0, 0.002))
"""The 24-disk shear of tests/models/packing/test_packing_dynamics.py (conftest.sheared computes it once)."""


@pytest.fixture(scope="module")
def setting(sheared):
    packing, branch, _ = sheared(SCENE)
    network = network_of(SCENE, packing)
    return branch, network, mass_diagonal(network, SCENE.m, SCENE.inertia)


def mass_norm(x: np.ndarray, mass: np.ndarray) -> float:
    return float(np.sqrt(np.sum(mass * x * x)))


def test_the_eigenvector_start_charges_the_histories_the_mode_charges(setting):
    """At gamma = 0.002 (one complex pair): the start's displacement a Re V with the histories
    the linear problem's rule charges gives the acceleration of the mode, M^-1 dF = -a Re(lambda
    V), to 1e-4; with the histories of the state left as they were it is off by half of itself
    (the tangential forces of the displacement missing: a slip)."""
    branch, network, mass = setting
    k = len(branch) - 1
    linear = linearized(branch, k, network, mass)
    mode, a = linear.mode, 1e-10
    q0, xi0, rows, gamma = branch.q[k], branch.xi[k], branch.rows[k], float(branch.gamma[k])
    q = q0 + a * mode.right.real
    want = -a * (mode.lam * mode.right).real
    at_rest = network.forces(q0, xi0, rows, gamma)
    charged = linear.problem.trial(q, gamma)[0]
    for xi, off in ((charged, (0.0, 1e-4)), (xi0, (0.3, np.inf))):
        acceleration = (network.forces(q, xi, rows, gamma) - at_rest) / mass
        error = mass_norm(acceleration - want, mass) / mass_norm(want, mass)
        assert off[0] <= error <= off[1], (error, off)


def test_the_run_follows_the_growing_solution_from_its_start(setting):
    """From the eigenvector start at a = 1e-10 (q = q_eq + a Re V, v = a Re(s V), histories
    charged) the pair's amplitude is |c(t)| = a e^(sigma t) over the whole linear range: the
    start is on the growing solution alone (no decaying partner, no slip), so the line through
    log |c| passes through log a within 1e-3 and nothing oscillates about it; sigma measured is
    the spectrum's within 0.05 % (velocity Verlet's error is 0.03 %)."""
    branch, network, mass = setting
    k = len(branch) - 1
    a = 1e-10
    done = run_from_state(branch, k, network, mass, "eigenvector", a, 300.0, SCENE.delta_0)
    assert done.fit.reason == "ok" and done.fit.t_start == 0.0 and done.fit.frames >= 500
    assert done.distance[0] == pytest.approx(a, rel=1e-5)
    inside = done.run.t <= done.fit.t_end
    off = np.log(done.mode_amplitude[inside] / a) - done.sigma_measured * done.run.t[inside]
    assert np.abs(off).max() <= 1e-3, np.abs(off).max()
    assert abs(done.sigma_measured / done.sigma_predicted - 1) <= 5e-4, done.fit


@pytest.mark.slow
def test_a_fast_pair_in_a_long_run_is_told_what_to_change_and_then_measured(setting):
    """The state of the fastest pair (sigma / omega about 0.3), from a = 1e-9: a run to 1000
    records a frame every 0.5, and the growth through the linear range lasts about 3: too few
    frames, so no rate (nan), and the reason says to shorten --t-end and by how much; the run to
    that t_end fits the rate within 0.1 % of the spectrum's."""
    branch, network, mass = setting
    k = int(np.argmax([fastest_pair(lam)[1] for lam in branch.eigenvalues]))
    linear = linearized(branch, k, network, mass)
    assert linear.mode.sigma > 0.2 * -linear.mode.s.imag
    long = run_from_state(branch, k, network, mass, "eigenvector", 1e-9, 1000.0, SCENE.delta_0,
                          linear=linear)
    assert long.unmeasured and np.isnan(long.sigma_measured)
    suggested = re.search(r"a shorter --t-end \(at most ([0-9.e+-]+)\) or a smaller --amplitude",
                          long.fit.reason)
    assert suggested, long.fit.reason
    short = run_from_state(branch, k, network, mass, "eigenvector", 1e-9,
                           float(suggested.group(1)), SCENE.delta_0, linear=linear)
    assert short.fit.reason == "ok" and not short.unmeasured
    assert abs(short.sigma_measured / short.sigma_predicted - 1) <= 1e-3, short.fit


def test_the_amplitude_of_a_pair_that_grows_faster_than_it_oscillates_has_no_oscillation():
    """A linear system M q'' = -J q of 2 dofs whose complex pair has sqrt(lambda) = omega +
    i sigma with sigma = 3 omega (the distance from rest has no maxima to fit), started with
    both its growing and its decaying solutions: the amplitude c(t) of the growing one is
    c_0 e^(s t) exactly, whatever the decaying one does."""
    root = 0.5 + 1.5j  # omega + i sigma
    lam = root ** 2
    rng = np.random.default_rng(1)
    u = rng.normal(size=2) + 1j * rng.normal(size=2)
    basis = np.column_stack([u, u.conj()])  # the pair's right vectors: M^-1 J is real
    A = basis @ np.diag([lam, lam.conjugate()]) @ np.linalg.inv(basis)
    assert np.abs(A.imag).max() < 1e-12
    V, W = basis[:, 0], np.linalg.inv(basis)[0]  # W A = lambda W, W V = 1
    mode = GrowingMode(lam, V, W)
    s = mode.s
    assert s == pytest.approx(1.5 - 0.5j)
    t = np.linspace(0.0, 4.0, 50)
    c0, d0 = 2e-3 * np.exp(0.7j), 5e-3 * np.exp(-0.2j)  # the growing and a decaying solution
    grow, decay = c0 * np.exp(s * t), d0 * np.exp(-s * t)
    dq = np.real(grow[:, None] * V + decay[:, None] * V)
    v = np.real(s * grow[:, None] * V - s * decay[:, None] * V)
    distance = np.hypot(*dq.T)
    assert not any(distance[f - 1] <= distance[f] >= distance[f + 1] for f in range(1, 49))
    assert np.allclose(mode.amplitude(dq, v), grow, rtol=1e-12, atol=0)


def test_a_run_ends_at_exactly_its_t_end(setting):
    """t_end that no whole number of default steps reaches: the run takes equal steps no
    longer than the default, its last frame at exactly t_end, its frames evenly spaced."""
    branch, network, mass = setting
    dt_max = time_step(branch.eigenvalues[0])
    t_end = 9.99 * dt_max * 100 / 7
    run = simulate(network, branch.q[0], np.zeros_like(branch.q[0]), branch.xi[0],
                   branch.rows[0], 0.0, mass, dt_max, t_end, frames=50)
    assert run.t[-1] == t_end and run.dt <= dt_max
    assert np.allclose(np.diff(run.t), run.t[1], rtol=1e-9)


@pytest.mark.slow
def test_simulate_at_gamma_0_runs_from_0_to_t_end_and_says_why_no_rate(tmp_path, capsys):
    """`simulate PACKING --gamma 0 --t-end 10` (16 disks): the run is at gamma = 0 exactly,
    printed as 0 (in the progress lines too), ends at t = 10 exactly; every eigenvalue is real there, so no rate: null in
    summary.json and one stderr line saying why. With --amplitude 1e-6, beyond the linear
    range, at a state with a complex pair: one warning line naming --amplitude."""
    scene = tmp_path / "p16.toml"
    scene.write_text('geometry = "packing"\nname = "p16"\n[packing]\nN = 16\nseed = 1\n'
                     '[shear]\ngamma = [0.0, 0.001]\n', encoding="utf-8")
    assert main(["simulate", str(scene), "--gamma", "0", "--t-end", "10",
                 "--out", str(tmp_path / "at0")]) == 0
    out, err = capsys.readouterr()
    summary = json.loads((tmp_path / "at0" / "summary.json").read_text())
    assert summary["gamma"] == 0.0 and summary["t_end"] == 10.0 and summary["dt"] <= 10.0
    assert out.startswith("gamma = 0: 0 complex pairs") and "1e-12" not in out + err
    assert "simulate: shear gamma 0 -> 0\n" in err
    assert summary["sigma_measured"] is None and summary["fit"]["sigma"] is None
    notes = [line for line in err.splitlines() if "no growth rate measured" in line]
    assert len(notes) == 1 and "every eigenvalue of M^-1 J is real" in notes[0]
    with np.load(tmp_path / "at0" / "run.npz") as run:
        assert run["t"][-1] == 10.0 and np.isnan(run["amplitude"]).all()

    assert main(["simulate", str(scene), "--gamma", "0.001", "--t-end", "10", "--amplitude",
                 "1e-6", "--out", str(tmp_path / "big")]) == 0
    out, err = capsys.readouterr()
    summary = json.loads((tmp_path / "big" / "summary.json").read_text())
    assert summary["complex_pairs"] >= 1 and summary["sigma_measured"] is None
    warnings = [line for line in err.splitlines() if "no growth rate measured" in line]
    assert len(warnings) == 1 and warnings[0].startswith("simulate warning: ")
    assert "beyond the linear range" in warnings[0] and "a smaller --amplitude" in warnings[0]
