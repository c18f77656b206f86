"""Damped Hopf points at contact events (models/packing/damped.py): 24 disks at P = 0.01 and
mu = 0.3, where disks turn loose at contact events, so that some crossings are the spectrum's
jump at an event and one cannot be refined inside its step."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.dynamics.damped_modes import damped_growth_rates
from diskfriction.models.packing.damped import damped_hopfs, in_gauge, problem_at
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, network_of, shear
from diskfriction.scenes.packing import PackingScene

SCENE = PackingScene(N=24, seed=1, pressure=0.01, mu=0.3, gamma_range=(0.0, 0.002), spectra="full")
DRAG = 0.003


@pytest.fixture(scope="module")
def at_drag():
    packing = prepare_scene(SCENE)
    branch = shear(SCENE, packing, ShearParams(workers=0), plastic_events=100)
    network = network_of(SCENE, packing)
    mass = mass_diagonal(network, SCENE.m, SCENE.inertia)
    return network, mass, branch, damped_hopfs(network, mass, branch, DRAG * SCENE.omega_0)


def growth_in(problem, x, near, eta):
    """The damped growth rate at x = (q, gamma) of problem's eigenvalue nearest `near`."""
    lam = np.linalg.eigvals(problem.stability_matrix(x[:-1], x[-1]).toarray())
    return damped_growth_rates(np.array([lam[np.argmin(np.abs(lam - near))]]), eta)[0]


@pytest.mark.slow
def test_a_crossing_at_a_contact_event_is_the_spectrums_jump_there(at_drag):
    """Every point found at an event ("jump") sits at the end of its step, which is a contact
    event; with the step's own contacts the growth rate has one sign at both ends, the sign the
    point's kind leaves, and the eigenvalue the point carries (its unstable side's: after the
    event for an onset, before it for an end) grows."""
    network, mass, branch, hopfs = at_drag
    eta = DRAG * SCENE.omega_0
    jumps = [h for h in hopfs if h.jump]
    assert jumps
    events = {e.row for e in branch.event}
    for h in jumps:
        k = h.step
        assert h.gamma == branch.p[k + 1] and h.bracket == (h.gamma, h.gamma) and k + 1 in events
        problem = problem_at(network, mass, branch, k)
        before = np.sign(growth_in(problem, np.append(branch.u[k], branch.p[k]), h.eigenvalue, eta))
        within = np.sign(growth_in(problem, in_gauge(problem, branch.u[k + 1], h.gamma), h.eigenvalue, eta))
        assert before == within == (-1 if h.kind == "onset" else 1)
        assert damped_growth_rates(np.array([h.eigenvalue]), eta)[0] > 0


@pytest.mark.slow
def test_a_crossing_not_refined_keeps_its_step_as_the_bracket(at_drag):
    network, mass, branch, hopfs = at_drag
    unresolved = [h for h in hopfs if not h.resolved]
    assert unresolved
    for h in unresolved:
        assert h.bracket == (branch.p[h.step], branch.p[h.step + 1]) and h.q is None and h.mode is None
        assert h.bracket[0] < h.gamma < h.bracket[1]
    refined = [h for h in hopfs if h.resolved and not h.jump]
    assert all(h.bracket[1] - h.bracket[0] <= 1e-10 for h in refined)
