"""Where the 24-disk shear's states lose or regain damped stability (models/packing/
contact_onsets.py): with the drag eta M in place of the dashpots the points are damped_hopfs'
changes between no damped-unstable pair and one, checked against the closed form of
dynamics/damped_modes.py; with contact dashpots each point has a root of the quadratic
eigenproblem on the imaginary axis (a first-order form of the full system, solved directly) and
the largest growth rate the two signs its kind says on either side, and its mode is the full
system's; dashpots strong enough to damp every state give no point, nor does a sign change made
by a damping that jumps at a commit."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from sheared_packing import SCENE, problem_at_start

from diskfriction.continuation.linalg.solves import blas_threads
from diskfriction.continuation.stepping.newton import fixed_p_newton
from diskfriction.dynamics.damped_modes import damped_growth_rates
from diskfriction.dynamics.quadratic_modes import largest_growth
from diskfriction.models.packing.contact_damping import (ContactDamping, damped_spectrum, problem_damping,
                                                          reduced_exponents, reduced_pencil)
from diskfriction.models.packing.contact_onsets import (contact_hopfs, mode_translations, null_vector,
                                                        stability_changes)
from diskfriction.models.packing.damped import TOL_GAMMA, damped_hopfs, fastest_damped, problem_at
from diskfriction.models.packing.equilibria import LINEAR_SOLVER, mass_diagonal
from diskfriction.models.packing.shear import network_of

DRAGS = (0.002, 0.01, 0.05)
"""The rates tested, in units of omega_0 (test_packing_damped's drags)."""

AWAY = 1e-9
"""The strain from a point at which the growth rate's sign is read on either side [1]."""


@pytest.fixture(autouse=True)
def one_blas_thread():
    """Every test's dense eigenproblems on one BLAS thread, as the module's own (on a shared
    machine several times faster than BLAS's threads: solves.blas_threads)."""
    with blas_threads():
        yield


@pytest.fixture(scope="module")
def network(packing):
    net = network_of(SCENE, packing)
    return net, mass_diagonal(net, SCENE.m, SCENE.inertia)


def drag(eta: float):
    """The dashpots' C replaced by the viscous drag eta M [mass / time]."""
    return lambda problem, q, gamma: eta * sp.diags_array(problem.mass)


def either_side(network, branch, h):
    """The equilibria (q, gamma) AWAY before and after a point, within its step and with its
    step's contacts."""
    problem = problem_at(*network, branch, h.step)
    sides = []
    for gamma in (max(h.gamma - AWAY, branch.p[h.step]), min(h.gamma + AWAY, branch.p[h.step + 1])):
        result = fixed_p_newton(problem, h.q, float(gamma), 1e-11, 20, LINEAR_SOLVER)
        assert result.converged
        sides.append((result.x[:-1], float(gamma)))
    return problem, sides


def closed_form_growth(problem, q, gamma, eta: float) -> float:
    """The fastest damped pair's growth rate from the eigenvalues of M^-1 J (damped_modes'
    s^2 + eta s + lambda = 0), no quadratic eigenproblem solved."""
    return fastest_damped(np.linalg.eigvals(problem.reduced(q, gamma).toarray()), eta)


def overlap(a: np.ndarray, b: np.ndarray) -> float:
    """|<a, b>| / (|a| |b|) of two complex fields: 1 where one is the other times a number."""
    return float(abs(np.vdot(a, b)) / (np.linalg.norm(a) * np.linalg.norm(b)))


def count_changes(hopfs, counts: np.ndarray):
    """(point, count before it, count after it) of damped_hopfs' points in strain order, the
    counts of damped-unstable pairs starting from each step's first state."""
    out, step, count = [], None, 0
    for h in hopfs:
        if h.step != step:
            step, count = h.step, counts[h.step]
        after = count + (1 if h.kind == "onset" else -1)
        out.append((h, count, after))
        count = after
    return out


def unstable_pairs(eigenvalues: np.ndarray, eta: float) -> int:
    """The pairs with Re s > 0 at the drag eta, counted by their upper members."""
    lam = eigenvalues[eigenvalues.imag > 1e-9 * np.abs(eigenvalues).max()]
    return int((damped_growth_rates(lam, eta) > 0).sum())


@pytest.mark.slow
@pytest.mark.parametrize("rate", DRAGS)
def test_with_the_drag_the_points_are_damped_hopfs_changes_from_none_to_one(network, branch, rate):
    """One point in every step whose two states differ in having a damped-unstable pair, none
    elsewhere; the closed form's growth rate has the kind's signs AWAY on either side of each;
    and each coincides to 1e-9 with damped_hopfs' point in its step where the count goes 0 -> 1 or
    1 -> 0, with its frequency and mode (the eigenvector of M^-1 J there). Except where
    damped_hopfs counts no pair that the closed form shows unstable just before its onset: a
    pair born and dead within the step (no state holds it, and damped_hopfs follows the states'
    tracked pairs), whose own onset comes first; the point found is then earlier than
    damped_hopfs'. (At 0.002 omega_0, step 5: a pair born at 1.0122e-3, unstable from 1.0171e-3,
    dead at 1.0562e-3; damped_hopfs' first onset there is another pair's, 1.0298e-3.)"""
    eta = rate * SCENE.omega_0
    net, mass = network
    ours = stability_changes(net, mass, branch, eta, drag(eta))
    counts = np.array([unstable_pairs(e, eta) for e in branch.eigenvalues])
    changes = {}
    for h, before, after in count_changes(damped_hopfs(net, mass, branch, eta), counts):
        if {before, after} == {0, 1}:
            changes.setdefault(h.step, []).append(h)
    differ = [k for k in range(len(branch) - 1) if (counts[k] > 0) != (counts[k + 1] > 0)]
    assert differ, "the rates tested see damped instability on the branch"
    assert [h.step for h in ours] == differ
    for h in ours:
        assert h.eta == eta and h.eigenvalue is None
        assert branch.p[h.step] <= h.bracket[0] <= h.gamma <= h.bracket[1] <= branch.p[h.step + 1]
        assert h.bracket[1] - h.bracket[0] <= TOL_GAMMA
        problem, sides = either_side(network, branch, h)
        signs = [np.sign(closed_form_growth(problem, q, gamma, eta)) for q, gamma in sides]
        assert signs == ([-1, 1] if h.kind == "onset" else [1, -1])
        theirs = changes[h.step]
        assert len(theirs) == 1
        if abs(theirs[0].gamma - h.gamma) > 1e-9:  # the exception (docstring)
            unseen = theirs[0]
            assert h.kind == unseen.kind == "onset" and h.gamma < unseen.gamma
            before = fixed_p_newton(problem, h.q, unseen.gamma - AWAY, 1e-11, 20, LINEAR_SOLVER)
            assert closed_form_growth(problem, before.x[:-1], unseen.gamma - AWAY, eta) > 0
            kinds = [c.kind for c in branch.collisions if c.step == h.step]
            assert "birth" in kinds and "death" in kinds[kinds.index("birth"):]
        else:
            assert h.kind == theirs[0].kind
            assert h.frequency == pytest.approx(theirs[0].frequency, rel=1e-8)
            assert overlap(h.mode, theirs[0].mode) == pytest.approx(1.0, abs=1e-9)


def companion_root(problem, q, gamma, damping: ContactDamping, near: complex):
    """(s, the disks' translations (N, 2) in its vector) of the root nearest `near` of M q'' + C q'
    + J q = 0 on every dof of every disk (translations and loose disks included), written
    [[0, I], [-M^-1 J, -M^-1 C]] and solved by a dense eigensolver."""
    N, n = problem.network.N, problem.network.ndof
    A = problem.physical(q, gamma).toarray()
    C = problem_damping(problem, q, gamma, damping).toarray() / problem.mass[:, None]
    s, vectors = np.linalg.eig(np.block([[np.zeros((n, n)), np.eye(n)], [-A, -C]]))
    j = np.argmin(np.abs(s - near))
    return complex(s[j]), np.stack([vectors[:N, j], vectors[N:2 * N, j]], axis=1)


def test_the_mode_of_an_exponent_is_the_full_systems(packing):
    """At the packing's start with contact dashpots (0.1 omega_0), for the slowest-decaying
    exponent s of the tracked coordinates' pencil and its conjugate: mode_translations of
    null_vector is, up to a complex factor, the translations of the full system's vector for the
    root nearest s (every dof of every disk: translations and loose disks included), and the
    null vector's residual is at rounding."""
    problem = problem_at_start(packing)
    q, damping = problem.q_c, ContactDamping(0.1 * SCENE.omega_0)
    C = problem_damping(problem, q, 0.0, damping)
    C_red, K_red = reduced_pencil(problem, q, 0.0, C)
    s = damped_spectrum(problem, q, 0.0, damping).exponents[0]
    assert s.imag != 0 and problem.gauge.loose.any()
    for root in (s, s.conjugate()):
        z = null_vector(root, C_red, K_red)
        residual = (root * root * np.eye(z.size) + root * C_red + K_red) @ z
        assert np.linalg.norm(residual) <= 1e-12 * np.linalg.norm(K_red)
        full, translations = companion_root(problem, q, 0.0, damping, root)
        assert full == pytest.approx(root, rel=1e-9)
        assert overlap(mode_translations(problem, z), translations) == pytest.approx(1.0, abs=1e-9)


def test_with_contact_dashpots_each_point_has_a_root_on_the_imaginary_axis(network, branch):
    """At 0.002 omega_0 (three points): at each the full system has a root s with |Re s| below
    1e-7 |Im s| (3e-14 found) and -Im s the point's frequency, whose translations are the point's
    mode (up to a complex factor); its equilibrium is one to the shear's tolerance; AWAY before
    and after it the largest growth rate has the kind's two signs."""
    damping = ContactDamping(0.002 * SCENE.omega_0)
    hopfs = contact_hopfs(*network, branch, damping)
    assert [h.kind for h in hopfs] == ["onset", "end", "onset"]
    for h in hopfs:
        assert h.eta == damping.rate and h.bracket[1] - h.bracket[0] <= TOL_GAMMA
        problem, sides = either_side(network, branch, h)
        assert np.abs(problem.residual(h.q, h.gamma)).max() <= 1e-10
        s, translations = companion_root(problem, h.q, h.gamma, damping, -1j * h.frequency)
        assert abs(s.real) <= 1e-7 * abs(s.imag)
        assert -s.imag == pytest.approx(h.frequency, rel=1e-7)
        assert overlap(translations, h.mode) == pytest.approx(1.0, abs=1e-9)
        signs = [np.sign(damped_spectrum(problem, q, gamma, damping).growth) for q, gamma in sides]
        assert signs == ([-1, 1] if h.kind == "onset" else [1, -1])


def test_dashpots_that_damp_every_state_give_no_point(network, branch):
    """At 2 omega_0 every state's largest growth rate is negative (the fastest pair, at the
    branch's largest critical drag 0.17 omega_0, needs more than 1 omega_0 of contact dashpots)."""
    damping = ContactDamping(2.0 * SCENE.omega_0)
    growth = [damped_spectrum(problem_at(*network, branch, k), branch.u[k], float(branch.p[k]),
                              damping).growth for k in range(len(branch))]
    assert max(growth) < 0
    assert contact_hopfs(*network, branch, damping) == ()


def test_a_sign_change_made_at_a_commit_is_no_point(network, branch):
    """A damping that jumps at a commit, the drag 2 omega_0 with the contacts committed before
    state 8 and 0.002 omega_0 from it on: every state before 8 is damped, every one from 8 on is
    not, and g changes sign at state 8 only by the jump (with step 7's contacts it is negative at
    both ends): no exponent crosses the imaginary axis, and no point is returned."""
    switch = float(branch.p[8])

    def jumping(problem, q, gamma):
        rate = 2.0 if problem.gamma_c < switch else 0.002
        return rate * SCENE.omega_0 * sp.diags_array(problem.mass)

    def growth(k: int, state: int) -> float:
        problem = problem_at(*network, branch, k)
        q, gamma = branch.u[state], float(branch.p[state])
        return largest_growth(reduced_exponents(problem, q, gamma, jumping(problem, q, gamma)))

    assert [np.sign(growth(k, k)) for k in range(len(branch))] == [-1] * 8 + [1] * (len(branch) - 8)
    assert growth(7, 8) < 0
    assert stability_changes(*network, branch, 0.0, jumping) == ()
