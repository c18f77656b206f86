"""Damped stability along the 24-disk shear (models/packing/damped.py): eta = 0 is the undamped
analysis bit for bit, every located damped Hopf point is one (the quadratic eigenproblem solved
directly there has a root on the imaginary axis), and the count of damped-unstable pairs changes
only at the located points."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from sheared_packing import SCENE

from diskfriction.dynamics.damped_modes import damped_growth_rates
from diskfriction.models.packing.damped import TOL_GAMMA, damped_hopfs, damped_rates, in_gauge, problem_at
from diskfriction.continuation.stepping.newton import fixed_p_newton
from diskfriction.models.packing.equilibria import LINEAR_SOLVER, PackingEquilibria, mass_diagonal
from diskfriction.models.packing.shear import network_of
from diskfriction.models.packing.dynamics import fastest_pair

DRAGS = (0.002, 0.01, 0.05)
"""The drags tested, in units of omega_0 (the 24-disk branch's critical damping: median 0.007,
largest 0.17 omega_0)."""


@pytest.fixture(scope="module")
def network(packing):
    net = network_of(SCENE, packing)
    return net, mass_diagonal(net, SCENE.m, SCENE.inertia)


def test_without_drag_the_undamped_analysis_bit_for_bit(network, branch):
    hopfs = damped_hopfs(*network, branch, 0.0)
    assert [(h.gamma, h.kind, h.eigenvalue.real) for h in hopfs] == [
        (c.p, {"birth": "onset", "death": "end"}[c.kind], c.eigenvalue) for c in branch.collisions]
    rates = damped_rates(branch.eigenvalues, 0.0)
    undamped = [fastest_pair(e)[1] for e, n in zip(branch.eigenvalues, branch.n_complex) if n > 0]
    assert np.array_equal(rates[branch.n_complex > 0], undamped)
    assert np.array_equal(rates > 0, branch.n_complex > 0)


def unstable_pairs(eigenvalues: np.ndarray, eta: float) -> int:
    """The pairs with Re s > 0 at the drag eta, counted by their upper members."""
    lam = eigenvalues[eigenvalues.imag > 1e-9 * np.abs(eigenvalues).max()]
    return int((damped_growth_rates(lam, eta) > 0).sum())


@pytest.mark.parametrize("drag", DRAGS)
def test_the_count_of_damped_unstable_pairs_changes_only_at_located_points(network, branch, drag):
    eta = drag * SCENE.omega_0
    hopfs = damped_hopfs(*network, branch, eta)
    assert hopfs, "the drags tested are below the branch's largest critical damping"
    counts = np.array([unstable_pairs(e, eta) for e in branch.eigenvalues])
    net = np.zeros(len(branch), int)
    for h in hopfs:
        assert branch.p[h.step] <= h.gamma <= branch.p[h.step + 1]
        assert h.bracket[1] - h.bracket[0] <= TOL_GAMMA
        net[h.step] += 1 if h.kind == "onset" else -1
    segment_starts = {piece.start for piece in branch.of_kind("segment")}
    for k in range(len(branch) - 1):
        if k + 1 not in segment_starts:
            assert counts[k + 1] - counts[k] == net[k], k


def imaginary_axis_root(A: np.ndarray, eta: float, w: float) -> complex:
    """The root s nearest i w of M q'' + eta M q' + J q = 0 written first-order with A = M^-1 J as
    [[0, I], [-A, -eta I]] and solved by a dense eigensolver (no use of s^2 + eta s + lambda)."""
    n = A.shape[0]
    s = np.linalg.eigvals(np.block([[np.zeros((n, n)), np.eye(n)], [-A, -eta * np.eye(n)]]))
    return complex(s[np.argmin(np.abs(s - 1j * w))])


@pytest.mark.slow
@pytest.mark.parametrize("drag", DRAGS)
def test_each_point_has_a_mode_crossing_the_imaginary_axis_there(network, branch, drag):
    """At every located point the first-order system has a root near s = i w (w^2 = Re lambda)
    and max |F| is at the shear's tolerance; at the equilibria 1e-9 of strain before and after
    it (fixed contacts, within its step) that root's Re s has the two signs an onset (- then +)
    or an end (+ then -) has. (Re s at the point itself is not tiny everywhere: near a pair's
    birth or death Im lambda grows like the square root of the strain's distance from it, and
    on the 24-disk branch Re s changed by 2e-5 over 1e-10 of strain there.)"""
    eta = drag * SCENE.omega_0
    net, mass = network
    for h in damped_hopfs(net, mass, branch, eta):
        problem = PackingEquilibria(net, branch.u[h.step], branch.xi[h.step], branch.rows[h.step],
                                    float(branch.p[h.step]), mass, SCENE.matrix)
        assert np.abs(problem.residual(h.q, h.gamma)).max() <= 1e-10
        w = h.frequency
        root = imaginary_axis_root(problem.stability_matrix(h.q, h.gamma).toarray(), eta, w)
        assert root.imag == pytest.approx(w, rel=1e-6)
        signs = []
        for gamma in (max(h.gamma - 1e-9, branch.p[h.step]), min(h.gamma + 1e-9, branch.p[h.step + 1])):
            result = fixed_p_newton(problem, h.q, float(gamma), 1e-11, 20, LINEAR_SOLVER)
            assert result.converged
            signs.append(np.sign(imaginary_axis_root(
                problem.stability_matrix(result.x[:-1], gamma).toarray(), eta, w).real))
        assert signs == ([-1, 1] if h.kind == "onset" else [1, -1])


def test_refused_without_spectra_or_with_J(network, branch):
    with pytest.raises(ValueError, match="M\\^-1 J"):
        damped_hopfs(*network, replace(branch, matrix="J"), 0.1)
    bare = replace(branch, eigenvalues=np.zeros((len(branch), 0), complex))
    with pytest.raises(ValueError, match="spectra \"full\""):
        damped_hopfs(*network, bare, 0.1)


def test_a_later_state_in_the_gauge_of_its_steps_start_is_the_same_state_translated(network, branch):
    """in_gauge: state k + 1 solved in problem k's gauge (its reference disk and loose disks
    pinned where state k has them) is state k + 1 translated as a whole, the loose disks apart."""
    net, mass = network
    N = net.N
    for k in range(len(branch) - 1):
        problem = problem_at(net, mass, branch, k)
        x = in_gauge(problem, branch.u[k + 1], float(branch.p[k + 1]))
        assert x[-1] == branch.p[k + 1] and np.abs(problem.residual(x[:-1], x[-1])).max() <= 1e-10
        held = ~problem.gauge.loose
        for c in (0, 1):
            shift = x[c * N:(c + 1) * N] - branch.u[k + 1][c * N:(c + 1) * N]
            assert np.ptp(shift[held]) <= 1e-9, (k, c)
