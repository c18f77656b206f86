"""Quasistatic shear of a packing (issue 25, docs/packings.md#shear): every accepted point in
force balance, the tracked spectrum equal to the network's own, every change in the number of
complex pairs accounted for by a located collision, and the collisions where the dense spectra
say they are."""
from __future__ import annotations

import dataclasses
from dataclasses import replace

import numpy as np
import pytest
import scipy.sparse as sp
from invariants import unaccounted_pair_changes

from diskfriction.continuation.detection.detectors import fast
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.models.packing.assembly import Assembly
from diskfriction.models.packing.equilibria import Gauge, PackingEquilibria, mass_diagonal, start
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, network_of, shear
from diskfriction.scenes.packing import PackingScene

SCENE = PackingScene(N=24, seed=3, gamma_range=(0.0, 0.002))


@pytest.fixture(scope="module")
def packing(sheared):
    return sheared(SCENE)[0]


@pytest.fixture(scope="module")
def recorded(sheared):
    """(branch, ends) of SCENE's shear (conftest.sheared: shared with test_packing_dynamics)."""
    return sheared(SCENE)[1:]


@pytest.fixture(scope="module")
def branch(recorded):
    return recorded[0]


def problem_at_start(packing, matrix: str = SCENE.matrix) -> PackingEquilibria:
    network = network_of(SCENE, packing)
    q, xi, rows = start(network, packing.positions)
    return PackingEquilibria(network, q, xi, rows, 0.0,
                             mass_diagonal(network, SCENE.m, SCENE.inertia), matrix)


@pytest.mark.parametrize("matrix", ["M^-1 J", "J"])
def test_the_tracked_spectrum_is_the_networks_without_its_zero_modes(packing, matrix):
    """A_red's eigenvalues are those of the network's M^-1 J (or J) less its two translation
    zeros and the loose disks' zero rows; the same after friction has charged the histories
    (xi != 0)."""
    problem = problem_at_start(packing, matrix)
    rng = np.random.default_rng(0)
    problem.xi_c = rng.uniform(-0.5, 0.5, problem.xi_c.size) * 1e-4  # a charged history
    q = problem.q_c
    full = np.linalg.eigvals(problem.physical(q, 0.0).toarray())
    system = DenseSpectra().eigensystem(problem, q, 0.0)
    tracked = system.values[~system.excluded]
    zeros = 2 + 3 * int(problem.gauge.loose.sum())
    nonzero = full[np.argsort(np.abs(full))[zeros:]]
    assert np.allclose(np.sort_complex(nonzero), np.sort_complex(tracked),
                       rtol=0, atol=1e-9 * np.abs(full).max())
    assert np.sort(np.abs(full))[zeros - 1] <= 1e-9 * np.abs(full).max()


def test_the_bordered_systems_factorized_by_minimum_degree_solve_as_superlus_default(packing, monkeypatch):
    """The shear's linear solver (ShearParams.linear_solver: minimum degree on A + A^T, partial
    pivoting): the corrector's and the tangent's factorizations take its ordering, with less
    fill than SuperLU's default (COLAMD), and the bordered solves agree with the default's to
    1e-12."""
    from diskfriction.continuation.linalg import solves as linalg
    from diskfriction.continuation.stepping import newton
    problem, solver = problem_at_start(packing), ShearParams().linear_solver
    x = np.append(problem.q_c, 0.0)
    e_p = np.zeros(x.size)
    e_p[-1] = 1.0
    M = newton.bordered_matrix(problem, x, e_p)
    rhs = np.random.default_rng(1).standard_normal(x.size)
    ours, default = solver.factorize(M), linalg.DIRECT.factorize(M)
    fill = [f.lu.L.nnz + f.lu.U.nnz for f in (ours, default)]
    assert fill[0] < fill[1]
    assert np.allclose(ours.solve(rhs), default.solve(rhs), rtol=0, atol=1e-12 * np.abs(default.solve(rhs)).max())
    taken, factorize = [], linalg.factorize
    recorded = lambda M, options=None: taken.append(options) or factorize(M, options)  # noqa: E731
    monkeypatch.setattr(linalg, "factorize", recorded)  # the corrector's and the tangent's (RefinedSolve)
    newton.tangent(problem, x, e_p, linear_solver=solver)
    newton.bordered_newton(problem, x + 1e-9, e_p, tol=0.0, max_iter=1, linear_solver=solver)
    assert taken == [solver.options] * 2 and solver.options["permc_spec"] == "MMD_AT_PLUS_A"


def test_every_accepted_point_is_in_force_balance(branch):
    assert len(branch) > 10 and branch.gamma[-1] > 0
    assert branch.residual.max() <= ShearParams().newton_tol


def test_complex_pairs_appear_only_once_shear_has_charged_the_histories(branch):
    """At gamma = 0 every history is 0 and J is symmetric: no complex pair; the histories the
    shear charges make J non-symmetric and pairs are born."""
    assert branch.n_complex[0] == 0 and branch.n_complex.max() > 0


def test_every_change_in_the_complex_pairs_is_a_located_collision(branch):
    kinds = [(c.p, c.kind) for c in branch.collisions]
    assert unaccounted_pair_changes(branch.gamma, branch.n_complex, kinds) == []


def test_shear_stress_grows_with_strain(branch):
    """Positive strain loads the packing: sigma_xy rises from its value at rest."""
    assert branch.stress[-1, 2] > branch.stress[0, 2]


def test_contact_events_are_located_on_the_branch_to_1e_12(recorded):
    """Every step cut at an event ends where an event function vanishes: a contact opening or
    closing (delta), starting or ending to hold its disk (delta - delta_hold) or reaching its
    Coulomb limit. The crossed component's |g| at the step's end over its mean slope in gamma
    across the step, the strain between the end and the zero, is at most 1e-12."""
    branch, ends = recorded
    assert branch.events >= 2 and len(ends) >= branch.events
    assert max(ends) <= 1e-12, ends


@pytest.mark.slow
def test_a_contact_sliding_through_steps_fires_no_event_at_their_start():
    """mu = 0.3, 24 disks, to gamma = 0.0015: contacts slide over many steps. At every commit,
    no contact that slid into the committed state crosses its Coulomb margin from inside to
    outside (a second slip of a sliding contact: the rounding of the cap and the re-solve left
    it inside the cap, and the step was cut within 1e-9 of its start, 63 times in 80 points);
    the shear ends and no two points are closer than 1e-12 in strain. A problem started at the
    end state flags the contacts on their cap as sliding."""
    import diskfriction.models.packing.equilibria as equilibria

    scene = PackingScene(N=24, seed=1, gamma_range=(0.0, 0.0015), mu=0.3)
    slips = []
    commit = equilibria.PackingEquilibria.commit

    def recording(self, q_old, g_old, q_new, g_new):
        before = self.event_functions(q_old, g_old)
        after = self.event_functions(q_new, g_new)
        m = self.rows_c.shape[0]
        slid = self.sliding & (before[2 * m:] > 0) & (after[2 * m:] <= 0)
        slips.append(int(slid.sum()))
        return commit(self, q_old, g_old, q_new, g_new)

    packing = prepare_scene(scene)  # once: the problem below starts from the same packing
    equilibria.PackingEquilibria.commit = recording
    try:
        branch = shear(scene, packing, ShearParams(workers=0))
    finally:
        equilibria.PackingEquilibria.commit = commit
    assert branch.status.reached and sum(slips) == 0, slips
    assert np.diff(branch.gamma).min() > 1e-12
    # a problem started from a state (a new segment after a plastic event, a run's state)
    # knows its sliding contacts from their histories: they fire no slip event either
    network = network_of(scene, packing)
    k = len(branch) - 1
    problem = PackingEquilibria(network, branch.q[k], branch.xi[k], branch.rows[k],
                                float(branch.gamma[k]),
                                mass_diagonal(network, scene.m, scene.inertia), scene.matrix)
    m = problem.rows_c.shape[0]
    delta = network.overlaps(problem.q_c, problem.rows_c, problem.gamma_c)
    t_star = problem.coulomb_limit(delta)
    capped = problem.active & (delta > 0) & (np.abs(problem.xi_c) >= t_star * (1 - 1e-12))
    margin = problem.event_functions(problem.q_c, problem.gamma_c)[2 * m:]
    assert capped.any() and problem.sliding[capped].all() and (margin[capped] < 0).all()


@pytest.fixture(scope="module")
def passed_run():
    """32 disks, seed 2, sheared to gamma = 0.0021 passing plastic events: (scene, packing,
    branch, the segments passed, as shear's on_segment was told them)."""
    scene = PackingScene(N=32, seed=2, gamma_range=(0.0, 0.0021))
    packing = prepare_scene(scene)
    finished = []
    branch = shear(scene, packing, ShearParams(workers=0), plastic_events=5, on_segment=finished.append)
    return scene, packing, branch, finished


@pytest.mark.slow
def test_a_plastic_event_is_passed_by_relaxing_with_friction(passed_run):
    """32 disks, seed 2, sheared to gamma = 0.0021: the first segment ends at a fold (its
    smallest eigenvalue near 0: a saddle-node); the packing is relaxed past it and the shear goes
    on to the end as a second segment, every point of which is in force balance."""
    passed = passed_run[2]
    assert passed.status.reached and passed.gamma[-1] == 0.0021
    assert len(passed.plastic) >= 1 and passed.segment.max() == len(passed.plastic)
    first = passed.plastic[0]
    end = np.flatnonzero(passed.segment == 0)[-1]
    assert first.kind == "fold" and first.gamma == passed.gamma[end]
    smallest = [e[e != 0].real.min() for e in passed.eigenvalues[[0, end]]]
    assert 0 < smallest[1] <= 1e-4 * smallest[0]
    assert passed.residual.max() <= ShearParams().newton_tol
    assert np.all(np.diff(passed.gamma) > 0)


@pytest.mark.slow
def test_a_damped_relaxation_passes_the_same_fold_to_force_balance(passed_run):
    """The same shear with relaxation = "damped" (Newtonian dynamics with a drag after each
    plastic event, models/packing/plastic.damped): the first segment and its fold are the FIRE run's
    to the bit (the relaxation acts only past a fold), the relaxed state takes dynamics steps,
    and the shear goes on to the end with every point in force balance."""
    scene, packing, fire_run, _ = passed_run
    damped = shear(replace(scene, relaxation="damped", damping=0.5), packing, ShearParams(workers=0),
                   plastic_events=5)
    assert damped.status.reached and damped.gamma[-1] == scene.gamma_range[1]
    assert len(damped.plastic) >= 1 and damped.plastic[0].gamma == fire_run.plastic[0].gamma
    first = np.flatnonzero(fire_run.segment == 0)
    assert np.array_equal(damped.q[first], fire_run.q[first])
    assert damped.plastic[0].steps > 0 and damped.plastic[0].stress_after < damped.plastic[0].stress_before
    assert damped.residual.max() <= ShearParams().newton_tol


def test_the_damped_steps_drag_is_exact_and_its_drift_second_order(passed_run):
    """advance with a drag on disks without contacts: v(t) = v0 exp(-eta t) to rounding (the
    drag is applied exactly, half a step at either end), and x(t) within O(dt^2) of
    x0 + v0 (1 - exp(-eta t)) / eta (halving dt divides the error by about 4)."""
    scene, packing, _, _ = passed_run
    network = network_of(scene, packing)
    q0 = start(network, packing.positions)[0]
    v0 = np.linspace(-1.0, 1.0, q0.size)
    rows = np.empty((0, 4), dtype=start(network, packing.positions)[2].dtype)
    eta, T = 3.0, 0.5
    errors = []
    for steps in (100, 200):
        q, v, xi = q0.copy(), v0.copy(), np.zeros(0)
        F = np.zeros(q.size)
        network.kernels.advance(q, v, xi, network.radii, rows, network.params(0.0), np.ones(q.size),
                                T / steps, steps, F, np.zeros(1), eta)
        assert np.allclose(v, v0 * np.exp(-eta * T), rtol=1e-13, atol=0)
        errors.append(np.abs(q - (q0 + v0 * (1 - np.exp(-eta * T)) / eta)).max())
    assert 0 < errors[1] < errors[0] / 3.5


@pytest.mark.slow
def test_a_relaxation_that_stalls_near_its_tolerance_is_finished_by_newton(passed_run, monkeypatch):
    """FIRE after a plastic event made to stop short, within 50 times the tolerance (as 256
    disks stalled at 2.5e-11 against 1e-11): the next segment's first Newton solve finishes it
    and the shear goes on to the end, every point in force balance, the first plastic event
    where it was; one that stops 1e4 times above the tolerance still fails in one line."""
    from diskfriction.models.packing import plastic

    scene, packing, whole, _ = passed_run
    real = plastic.fire

    def stalling(factor):
        def fire(forces, x0, dt0, f_tol, max_steps):
            return dataclasses.replace(real(forces, x0, dt0, factor * f_tol, max_steps), converged=False)
        return fire

    monkeypatch.setattr(plastic, "fire", stalling(50.0))
    finished = shear(scene, packing, ShearParams(workers=0), plastic_events=5)
    assert finished.status.reached and finished.residual.max() <= ShearParams().newton_tol
    assert finished.plastic[0].gamma == whole.plastic[0].gamma and len(finished.plastic) >= 1
    monkeypatch.setattr(plastic, "fire", stalling(1e4))
    with pytest.raises(plastic.RelaxationFailed, match="after the plastic event at gamma"):
        shear(scene, packing, ShearParams(workers=0), plastic_events=5)


def test_a_relaxation_that_does_not_settle_starts_again_with_half_the_time_step(passed_run,
                                                                                monkeypatch):
    """FIRE made to fail (as it circles with sliding contacts: 256 disks after the event at
    gamma = 0.0147) at the first time step of the relaxation after the first fold: the
    relaxation starts again from the fold state with half the step, and gives bit for bit the
    state of a relaxation whose first step is that half; its steps count both runs. Failing at
    every attempt raises RelaxationFailed in one line."""
    from diskfriction.models.packing import plastic

    scene, packing, branch, _ = passed_run
    network = network_of(scene, packing)
    k = np.flatnonzero(branch.segment == 0)[-1]
    fold = (branch.q[k], branch.xi[k], branch.rows[k], branch.gamma[k])
    f_tol, real_fire, real_step = ShearParams().newton_tol, plastic.fire, plastic.time_step
    dt0 = real_step(network, *fold)
    monkeypatch.setattr(plastic, "time_step", lambda *state: dt0 / 2)
    halved = plastic.relax(network, *fold, f_tol)
    monkeypatch.setattr(plastic, "time_step", real_step)

    def failing_from(dt_largest):
        def fire(forces, x0, dt, f_tol, max_steps):
            run = real_fire(forces, x0, dt, f_tol, max_steps)
            return run if dt < dt_largest else dataclasses.replace(run, max_force=1.0, steps=7)
        return fire

    monkeypatch.setattr(plastic, "fire", failing_from(dt0))
    again = plastic.relax(network, *fold, f_tol)
    assert all(np.array_equal(a, b) for a, b in zip(again[:3], halved[:3]))
    assert again[3] == halved[3] + 7
    monkeypatch.setattr(plastic, "fire", failing_from(0.0))
    with pytest.raises(plastic.RelaxationFailed, match=f"{plastic.ATTEMPTS} attempts"):
        plastic.relax(network, *fold, f_tol)


def test_a_relaxation_still_settling_when_its_attempts_run_out_goes_on_from_the_closest(
        passed_run, monkeypatch):
    """Every attempt from the fold state made to run out of steps early (as FIRE still settling
    after a second rearrangement: 256 disks, window [-3, 2], gamma = 0.0405607): the attempt
    that ended with the least force goes on from its end with its own time step, and its end is
    the relaxed state, in force balance; its steps count every run."""
    from diskfriction.models.packing import plastic

    scene, packing, branch, _ = passed_run
    network = network_of(scene, packing)
    k = np.flatnonzero(branch.segment == 0)[-1]
    fold = (branch.q[k], branch.xi[k], branch.rows[k], branch.gamma[k])
    f_tol, real_fire = ShearParams().newton_tol, plastic.fire
    calls = []

    def cut_short(forces, x0, dt, f_tol, max_steps):
        run = real_fire(forces, x0, dt, f_tol, max_steps if len(calls) == plastic.ATTEMPTS else 40 + len(calls))
        calls.append((x0.copy(), dt, run))
        return run

    monkeypatch.setattr(plastic, "fire", cut_short)
    mass = mass_diagonal(network, scene.m, scene.inertia)
    q, xi, rows, gamma, steps = plastic.past_fold(network, *fold, f_tol, mass)
    assert len(calls) == plastic.ATTEMPTS + 1
    tried = calls[:plastic.ATTEMPTS]
    assert all(not run.converged for _, _, run in tried)
    closest = min(tried, key=lambda call: call[2].max_force)
    x0, dt, last = calls[-1]
    assert np.array_equal(x0, closest[2].x) and dt == closest[1]
    assert np.array_equal(q, last.x) and last.converged
    assert steps == sum(run.steps for _, _, run in calls)
    assert np.abs(network.forces(q, xi, rows, gamma)).max() <= f_tol


def same(a, b) -> bool:
    """Whether two results are equal value for value: arrays (nan equal to nan), and
    dataclasses, tuples, lists and dicts of them, field by field."""
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(same(getattr(a, f.name), getattr(b, f.name))
                                          for f in dataclasses.fields(a))
    if isinstance(a, (tuple, list)):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, np.ndarray):
        return isinstance(b, np.ndarray) and np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")
    return a == b


@pytest.mark.parametrize("window", [None, (0.0, 50.0)])
@pytest.mark.slow
def test_a_run_resumed_after_its_finished_segments_equals_one_never_interrupted(passed_run, window,
                                                                                tmp_path):
    """The segments a run passed, each written to a file and read back (models/packing/segments.py),
    and the run resumed after the first of them: its branch equals the uninterrupted run's
    value for value (points, spectra, collisions with their Jordan chains, plastic events),
    every eigenvalue tracked or a window (its blocks numbered across the segments); a segment
    file is refused for another key, or missing arrays (one line, no traceback)."""
    from diskfriction.files import save_npz
    from diskfriction.models.packing.segments import SegmentFileError, load_segment, save_segment

    scene, packing, whole, finished = passed_run
    if window is not None:
        finished = []
        whole = shear(scene, packing, ShearParams(workers=0), plastic_events=5, window=window,
                      on_segment=finished.append)
    assert len(finished) == len(whole.plastic) >= 1
    for k, segment in enumerate(finished):
        save_segment(tmp_path / f"{k}.npz", segment, "inputs")
        assert same(load_segment(tmp_path / f"{k}.npz", "inputs"), segment)
    with pytest.raises(SegmentFileError, match="other inputs"):
        load_segment(tmp_path / "0.npz", "other inputs")
    save_npz(tmp_path / "short.npz", key=np.array("inputs"), q=np.zeros((1, 3)))
    with pytest.raises(SegmentFileError, match="incomplete"):
        load_segment(tmp_path / "short.npz", "inputs")
    told = []
    resumed = shear(scene, packing, ShearParams(workers=0), plastic_events=5, window=window,
                    done=[load_segment(tmp_path / "0.npz", "inputs")], on_segment=told.append)
    assert same(resumed, whole) and len(told) == len(finished) - 1
    assert resumed.gamma.size == whole.gamma.size and len(resumed.collisions) == len(whole.collisions) > 0


@pytest.mark.slow
def test_detection_at_64_disks_agrees_with_dense_spectra_inside_every_step(monkeypatch):
    """Issue 25: 64 disks (seed 1) sheared to gamma = 5e-4, every eigenvalue tracked. At 97
    points across every step (its segment, in the state committed at its start), the dense
    spectrum of A_red has as many complex pairs as at the step's start plus the births less
    the deaths the scan located before that point; points within 1e-9 in strain of a located
    collision are left out (there the pair's Im is still near the status threshold). The
    steps ending at a contact reaching its Coulomb limit hold up to a dozen collisions within
    1e-5 of strain (docs/packings.md, Accuracy measured)."""
    from diskfriction.continuation.detection import scans
    from diskfriction.continuation.spectra.tracking import count_complex_pairs

    scene = PackingScene(N=64, seed=1, gamma_range=(0.0, 5e-4))
    packing = prepare_scene(scene)
    real_scan, checked, wrong = scans.scan_step, [], []

    def pairs(problem, x):
        found = DenseSpectra().eigensystem(problem, x[:-1], float(x[-1]))
        return count_complex_pairs(found.values[~found.excluded])

    def checking_scan(problem, segment, start, end, *args, **kwargs):
        result = real_scan(problem, segment, start, end, *args, **kwargs)
        at = [(float(segment.sigma @ (np.append(c.u, c.p) - segment.x_a)) / segment.length, c)
              for c in result.collisions]
        first = pairs(problem, segment.x_a)
        for s in np.linspace(0.0, 1.0, 97)[1:]:
            x = segment.point(s)
            if any(abs(c.p - x[-1]) <= 1e-9 for _, c in at):
                continue
            located = sum(1 if c.kind.value == "birth" else -1 for s_c, c in at if s_c < s)
            checked.append(s)
            if pairs(problem, x) != first + located:
                wrong.append((float(x[-1]), pairs(problem, x), first + located))
        return result

    monkeypatch.setattr(scans, "scan_step", checking_scan)
    run = shear(scene, packing, ShearParams(workers=0), plastic_events=5)
    assert run.status.reached and len(run.collisions) >= 30 and len(checked) >= 400
    assert wrong == []


def test_a_loose_disk_pushed_into_gives_way(packing):
    """A loose disk moved into its neighbour (overlap 100 delta_hold, a force the network's
    equations leave out): _release_pushed moves it back along its normal force until no contact
    of it holds it, and the forces of its rows fall below 1e-3 of a contact's force P 2R."""
    problem = problem_at_start(packing)
    N, rows = problem.network.N, problem.rows_c
    loose = [d for d in np.flatnonzero(problem.gauge.loose)
             if ((rows[:, 0] == d) | (rows[:, 1] == d)).any()]
    assert loose
    d = loose[0]
    mine = rows[(rows[:, 0] == d) | (rows[:, 1] == d)]
    q = problem.q_c.copy()
    near = int(np.argmax(problem.network.overlaps(q, mine, 0.0)))
    other = mine[near, 1] if mine[near, 0] == d else mine[near, 0]
    toward = np.array([q[other] - q[d], q[N + other] - q[N + d]])
    gap = -problem.network.overlaps(q, mine[near:near + 1], 0.0)[0] + 100 * problem.delta_hold
    q[[d, N + d]] += gap * toward / np.linalg.norm(toward)
    assert problem.network.overlaps(q, mine, 0.0).max() > 50 * problem.delta_hold
    problem._set_committed(q, problem.xi_c, rows, 0.0)
    moved = problem._release_pushed(q, rows, 0.0)
    assert moved is not None
    assert problem.network.overlaps(moved, mine, 0.0).max() <= problem.delta_hold
    force = problem.network.forces(moved, np.zeros(len(mine)), mine, 0.0)
    assert np.abs(force).max() <= 1e-3 * SCENE.pressure * 2 * SCENE.R


def test_a_disk_held_only_against_loose_disks_is_loose():
    """Disks 0, 1, 2 hold each other; disk 3 has two holding contacts, with 0 and with disk 4,
    whose only holding contact is 3: 4 is loose, so its contact holds nothing and 3 is loose
    too (its equations would keep one loaded contact, whose only equilibrium is at delta = 0);
    disk 5, held by 1 and 2, is not. The reference disk is one of most contacts in the
    network."""
    holding = np.array([[0, 1], [1, 2], [0, 2], [0, 3], [3, 4], [1, 5], [2, 5]])
    gauge = Gauge.of(6, holding)
    assert gauge.loose.tolist() == [False, False, False, True, True, False]
    assert gauge.ref in (1, 2)


@pytest.mark.parametrize("mu, gamma_end", [(0.3, 0.004), (1.0, 0.005)])
@pytest.mark.slow
def test_a_loose_disk_caught_against_a_loose_disk_ends_no_segment(mu, gamma_end):
    """24 disks, seed 3. At mu = 0.3, gamma = 3.43e-3, a loose disk pushed by the network was
    caught between its pusher and another loose disk. Counted as held by both, it joined the
    network with one loaded contact (the other, with a loose disk, carries no force): the
    re-solve's only root had that contact's delta at 0, the Hertz force's singular point,
    where Newton divides delta by 3 per update, and every commit failed (1000 "plastic events"
    1e-7 apart in strain). At mu = 1, gamma = 4.13e-3, the same disk stopped giving way in a
    cage closed by a loose disk, its two network contacts a wedge that cannot hold it, joined,
    and both contacts unloaded together in the re-solve. Now the push travels on to the loose
    disks in the way: the run reaches the end with no lost branch, every point in force
    balance, and every disk's force with every row counted (the loose disks' included) within
    1e-3 of a contact's force P 2R."""
    scene = PackingScene(N=24, seed=3, mu=mu, gamma_range=(0.0, gamma_end))
    packing = prepare_scene(scene)
    run = shear(scene, packing, ShearParams(workers=0), plastic_events=5)
    assert run.status.reached and run.gamma[-1] == gamma_end
    assert run.plastic == ()
    assert run.residual.max() <= ShearParams().newton_tol
    network = network_of(scene, packing)
    largest = max(np.abs(network.forces(q, np.where(network.overlaps(q, rows, g) > 0, xi, 0.0),
                                        rows, g)).max()
                  for g, q, rows, xi in zip(run.gamma, run.q, run.rows, run.xi))
    assert largest <= 1e-3 * scene.pressure * 2 * scene.R


WINDOW = (0.0, 50.0)


@pytest.fixture(scope="module")
def windowed(packing):
    return shear(SCENE, packing, ShearParams(workers=0), window=WINDOW)


def test_a_spectral_window_finds_the_full_spectrums_collisions_in_it(branch, windowed):
    """Shear tracking only Re lambda in [0, 50] (sparse shift-invert, its k sized at the start):
    the same collisions as the dense spectra's with their double eigenvalue in the window, each
    at the same strain within 1e-9; every change of the window's complex pairs is one of them."""
    window = WINDOW
    inside = sorted(c.p for c in branch.collisions if window[0] <= c.eigenvalue <= window[1])
    assert windowed.status.reached and len(inside) >= 4
    assert len(windowed.collisions) == len(inside)
    assert np.abs(np.array(sorted(c.p for c in windowed.collisions)) - inside).max() <= 1e-9
    kinds = [(c.p, c.kind) for c in windowed.collisions]
    assert unaccounted_pair_changes(windowed.gamma, windowed.n_complex, kinds) == []
    assert windowed.window == window and windowed.eigenvalues.shape[1] < 3 * SCENE.N


@pytest.mark.slow
def test_a_window_that_crowds_is_widened_and_finds_the_same_collisions(packing, monkeypatch):
    """A window [0, 40] sized with k = the eigenvalues within reach + 1 crowds as the shear
    softens the packing: the run is not lost (256 disks lost 205 s so), the window is sized
    anew, wider, at the last certified state and the shear goes on; the collisions equal a
    generous window's within 1e-9, and each strain is recorded once. The crowding comes before
    the collisions here: the steps after the restart differ, and the history makes the branch
    depend on its steps (measured 1.2e-10; the chain's 5.9e-10, tests/continuation/detection/test_detection.py)."""
    from diskfriction.models.packing import shear as shearing

    window = (0.0, 40.0)
    generous = shear(SCENE, packing, ShearParams(workers=0), window=window)
    monkeypatch.setattr(shearing, "WINDOW_MARGIN", 1.0)  # the shear's window's margins
    monkeypatch.setattr(shearing, "WINDOW_EXTRA", 1)
    tight = shear(SCENE, packing, ShearParams(workers=0), window=window)
    assert generous.widenings == 0 and tight.widenings >= 1
    assert tight.status.reached and np.all(np.diff(tight.gamma) > 0)
    assert len(tight.collisions) == len(generous.collisions) >= 4
    assert np.abs(np.array([c.p for c in tight.collisions])
                  - [c.p for c in generous.collisions]).max() <= 1e-9
    kinds = [(c.p, c.kind) for c in tight.collisions]
    assert unaccounted_pair_changes(tight.gamma, tight.n_complex, kinds) == []


def test_a_window_that_crowds_at_its_first_point_is_widened_there(packing, windowed, monkeypatch):
    """A window sized with k = the eigenvalues within its reach crowds at once, at the first
    point of the run (as 256 disks' window did at the start of a segment after a plastic event
    at gamma = 0.0102, a pair with |Im| = 12.7 in its band, where the exception lost 334 s of
    shear): it is sized anew, wider, there and the shear goes on; the same collisions as a
    generous window within 1e-12."""
    from diskfriction.continuation.spectra import window as spectral_window

    sized, decompose = spectral_window.sized, spectral_window.window_eigensystem
    points, crowded_at = [], []

    def watched(A, window, vectors, deflated=None):
        try:
            return decompose(A, window, vectors, deflated)
        except spectral_window.WindowCrowded:
            crowded_at.append(len(points))
            raise

    def too_tight(w, problem, u, p):  # at the start; widened with the window's own margins
        return w if w.k else replace(w, k=sized(w, problem.stability_structure(u, p).shifted(), 1.0, 1).k - 1)

    monkeypatch.setattr(spectral_window.SpectralWindow, "prepared", too_tight)
    monkeypatch.setattr(spectral_window, "window_eigensystem", watched)
    tight = shear(SCENE, packing, ShearParams(workers=0), points.append, window=WINDOW)
    assert crowded_at[0] == 0 and tight.widenings >= 1 and tight.status.reached
    assert len(tight.collisions) == len(windowed.collisions) >= 4
    assert np.abs(np.array([c.p for c in tight.collisions])
                  - [c.p for c in windowed.collisions]).max() <= 1e-12


@pytest.mark.slow
def test_a_commit_that_leaves_the_matrix_the_same_keeps_the_spectrum(packing, windowed, monkeypatch):
    """Commits where loose disks gave way or histories were capped change the state but not
    A_red: the re-solve from the committed q (PackingEquilibria.resolve_start) takes no update,
    and the end sample's spectrum is kept at the new point (arclength._moved) instead of a
    second decomposition of the same matrix. With that second decomposition forced, the branch
    is the same point for point and the collisions within 1e-12 in strain."""
    from diskfriction.continuation.stepping import arclength

    kept, updates, same_matrix = [], {}, arclength.same_matrix
    real_newton = arclength.factored_fixed_p

    def counting_newton(*args, **kwargs):
        result, near = real_newton(*args, **kwargs)
        updates["last"] = result.iterations
        return result, near

    def counting_same(A, B):
        same = same_matrix(A, B)
        if same:
            kept.append(updates["last"])
        return same

    monkeypatch.setattr(arclength, "factored_fixed_p", counting_newton)
    monkeypatch.setattr(arclength, "same_matrix", counting_same)
    counted = shear(SCENE, packing, ShearParams(workers=0), window=WINDOW)
    assert len(kept) >= 5 and set(kept) == {0}
    monkeypatch.setattr(arclength, "same_matrix", lambda A, B: False)
    again = shear(SCENE, packing, ShearParams(workers=0), window=WINDOW)
    for run in (counted, again):
        assert np.array_equal(run.gamma, windowed.gamma) and np.array_equal(run.q, windowed.q)
    assert len(again.collisions) == len(windowed.collisions) >= 4
    assert np.abs(np.array([c.p for c in again.collisions])
                  - [c.p for c in windowed.collisions]).max() <= 1e-12


def test_the_condition_numbers_follow_the_eigenvalues_columns(branch, windowed):
    """branch.condition has the eigenvalues' shape: nan exactly at the translations' and loose
    disks' zeros (no vectors), at least 1 elsewhere (|l| |r| >= |l^H r|); with a window, nan
    exactly where the window's columns are."""
    zero = branch.eigenvalues == 0
    assert branch.condition.shape == branch.eigenvalues.shape
    assert np.isnan(branch.condition[zero]).all() and (branch.condition[~zero] >= 1 - 1e-12).all()
    assert np.array_equal(np.isnan(windowed.condition), np.isnan(windowed.eigenvalues))


def test_assembly_is_the_product_it_replaces_on_one_pattern():
    """Assembly (models/packing/assembly.py): L J(v) R + C for a pattern with repeated entries, the
    same CSR pattern (sorted) at every v, an entry that is zero at some v kept."""
    rng = np.random.default_rng(2)
    n, m, k = 12, 9, 7
    rows, cols = rng.integers(0, n, 60), rng.integers(0, n, 60)
    L = sp.random_array((m, n), density=0.3, random_state=3)
    R = sp.random_array((n, k), density=0.3, random_state=4)
    C = sp.random_array((m, k), density=0.2, random_state=5)
    assembly = Assembly.of(rows, cols, L, R, C)
    patterns = set()
    for v in (rng.standard_normal(60), np.zeros(60)):
        A = assembly(v)
        J = sp.coo_array((v, (rows, cols)), shape=(n, n))
        assert np.abs((A - (L @ J @ R + C)).toarray()).max() <= 1e-14
        assert all(np.all(np.diff(A.indices[A.indptr[i]:A.indptr[i + 1]]) > 0) for i in range(m))
        patterns.add((A.indptr.tobytes(), A.indices.tobytes()))
    assert len(patterns) == 1 and assembly(np.zeros(60)).nnz > C.nnz


def test_the_assembled_matrices_are_the_products_of_the_gauge(packing):
    """dG/dq = -diag(keep) J + kappa diag(gauge), A_red = P M^-1 J E and A_g (A_red at the kept
    dofs, the parked constant on the gauge rows' diagonal) at a point off the committed one,
    against the sparse products they replace, to 1e-14 of the largest entry."""
    problem = problem_at_start(packing)
    rng = np.random.default_rng(1)
    q, gamma, g = problem.q_c + 1e-6 * rng.standard_normal(problem.q_c.size), 1e-5, problem.gauge
    n = q.size
    J = problem.network.evaluate(q, problem.trial(q, gamma)[0][problem.active],
                                 problem.rows_c[problem.active], gamma)[1]
    keep, gauge = np.ones(n), np.zeros(n)
    keep[g.rows], gauge[g.rows] = 0.0, problem.kappa
    A_red = g.P @ sp.diags_array(1.0 / problem.mass) @ J @ sp.eye_array(n, format="csr")[:, g.kept]
    parked = problem.stability_matrix(problem.q_c, problem.gamma_c).diagonal()[g.rows]
    A_g = sp.lil_array((n, n))
    A_g[np.ix_(g.kept, g.kept)] = A_red
    A_g[g.rows, g.rows] = parked
    for got, expected in ((problem.jacobian(q, gamma), sp.diags_array(-keep) @ J + sp.diags_array(gauge)),
                          (problem.reduced(q, gamma), A_red), (problem.stability_matrix(q, gamma), A_g)):
        assert np.abs((got - expected).toarray()).max() <= 1e-14 * np.abs(expected.toarray()).max()
    assert np.all(parked < 0) and np.ptp(parked) == 0.0


def test_the_deflated_shift_invert_finds_the_tracked_matrix_eigensystem(branch, packing):
    """nearest_eigensystem with the problem's Deflated (A with the loose disks parked, its
    translations projected out) against the shift-invert of A_g itself, at a sheared state
    with complex pairs and with sigma next to 0, where A's translation zeros would be the
    nearest: the same k eigenvalues to 1e-12 of the largest, eigenvectors of A_g (residuals
    1e-9), and the LU of A sparser than A_g's."""
    from diskfriction.continuation.linalg.solves import factorize
    from diskfriction.continuation.spectra.nearest import SHIFT_INVERT_ORDERING, nearest_eigensystem

    problem = problem_at_start(packing)
    point = int(np.argmax(branch.n_complex[branch.segment == 0]))
    q, gamma = branch.q[point], float(branch.gamma[point])
    problem._set_committed(q, branch.xi[point], branch.rows[point], gamma)
    structure = problem.stability_structure(q, gamma)
    A, deflated = structure.matrix, structure.deflated
    assert np.abs(deflated.matrix @ deflated.right_null).max() <= 1e-12 * np.abs(deflated.matrix).max()
    k = 12
    for sigma in (0.05, 3.0):
        plain, r_plain = nearest_eigensystem(A, sigma, k)
        fast_, r_fast = nearest_eigensystem(A, sigma, k, deflated)
        scale = np.abs(plain.values).max()
        distance = np.abs(plain.values[:, None] - fast_.values[None, :])
        assert max(distance.min(axis=0).max(), distance.min(axis=1).max()) <= 1e-12 * scale
        assert abs(r_plain - r_fast) <= 1e-12 * scale
        assert np.abs(fast_.values).min() > 1e-6  # no translation zero among them
        right = A @ fast_.right - fast_.right * fast_.values
        left = fast_.left @ A - fast_.values[:, None] * fast_.left
        assert np.abs(right).max() <= 1e-9 * scale * np.abs(fast_.right).max()
        assert np.abs(left).max() <= 1e-9 * scale * np.abs(fast_.left).max()
    fill = [factorize(M - 3.0 * sp.identity(M.shape[0], format="csr"), SHIFT_INVERT_ORDERING).lu
            for M in (A, deflated.matrix)]
    assert fill[1].L.nnz + fill[1].U.nnz < fill[0].L.nnz + fill[0].U.nnz


def test_a_restored_state_is_the_state_set_afresh(packing):
    """restore of a state() snapshot kept from an earlier commit (PackingEquilibria._kept) gives
    the residual, dG/dq and A_g of a problem set to that state afresh, bit for bit, without
    assembling again; an unknown snapshot is set afresh, its matrices assembled at their first
    use only (a restore to record a point assembles nothing); only the last KEPT_STATES are
    kept."""
    from diskfriction.models.packing import assembly, equilibria

    problem = problem_at_start(packing)
    first = problem.state()
    rng = np.random.default_rng(2)
    states = [first]
    for k in range(equilibria.KEPT_STATES + 1):  # other committed states: the disks moved by ~1e-9
        problem._set_committed(first[0] + 1e-9 * (k + 1) * rng.standard_normal(first[0].size), first[1],
                               first[2], first[3], first[4])
        problem.jacobian(problem.q_c, problem.gamma_c)  # assembled at the first use
        states.append(problem.state())
    assert len(problem._kept) == equilibria.KEPT_STATES
    fresh = problem_at_start(packing)
    target = states[-3]
    fresh.restore(target)  # not kept by `fresh`: set afresh
    assembled = []
    original = assembly.Assembly.of
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(assembly.Assembly, "of", lambda *a, **k: assembled.append(1) or original(*a, **k))
        problem.restore(target)
    assert not assembled
    x = target[0] + 1e-7 * rng.standard_normal(target[0].size)
    for got, expected in ((problem.residual(x, 1e-6), fresh.residual(x, 1e-6)),
                          (problem.jacobian(x, 1e-6).toarray(), fresh.jacobian(x, 1e-6).toarray()),
                          (problem.stability_matrix(x, 1e-6).toarray(), fresh.stability_matrix(x, 1e-6).toarray())):
        assert np.array_equal(got, expected)
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(assembly.Assembly, "of", lambda *a, **k: assembled.append(1) or original(*a, **k))
        problem.restore(first)  # dropped from the kept states long ago
        assert not assembled
        problem.residual(x, 1e-6)
        assert not assembled  # the residual needs no assembled matrix
        problem.stability_matrix(x, 1e-6)
    assert assembled


@pytest.mark.slow
def test_the_locator_starts_from_the_predicted_branch_point(monkeypatch):
    """256 disks (seed 1), window [-3, 8], to gamma = 1.27e-4: every located collision is found
    by the locator's first run. It starts from the point the segment predicts from the solved
    points nearest it; from the secant point of the whole step (off the branch: at a birth
    near lambda = 6.504 the spectrum there had 6.45 and 6.15 instead of 6.501 and 6.508) it
    failed 13 times on this stretch, each time converging on another birth 4.1e-7 away, and
    each failure cost a full split sample."""
    failed = []
    locate = fast.locate

    def counted(scan, idx, i, j, kind):
        found = locate(scan, idx, i, j, kind)
        if found is None:
            failed.append((scan.samples[idx].p, i, j))
        return found

    monkeypatch.setattr(fast, "locate", counted)
    scene = PackingScene(N=256, seed=1, gamma_range=(0.0, 1.27e-4))
    branch = shear(scene, prepare_scene(scene), ShearParams(workers=0), window=(-3.0, 8.0))
    assert len(branch.collisions) >= 5 and failed == []


def test_the_relaxations_time_step_is_stable_for_the_stiffest_mode():
    """time_step's dt_max = 10 dt0 keeps omega dt_max <= DT_MAX_STABLE < 2 for every eigenvalue
    of J at the state (the dense spectrum), and is not more than 3 times below that bound."""
    scene = PackingScene(N=32, seed=3)
    packing = prepare_scene(scene)
    network = network_of(scene, packing)
    q, xi, rows = start(network, packing.positions)[:3]
    from diskfriction.models.packing import plastic

    dt_max = 10 * plastic.time_step(network, q, xi, rows, 0.0)
    omega = np.sqrt(np.abs(np.linalg.eigvals(network.evaluate(q, xi, rows, 0.0)[1].toarray())).max())
    assert plastic.DT_MAX_STABLE / 3 <= omega * dt_max <= plastic.DT_MAX_STABLE < 2
