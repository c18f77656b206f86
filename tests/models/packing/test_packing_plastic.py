"""Plastic events passed in a shear (models/packing/plastic.py, segments.py): the packing
relaxed past a fold by FIRE or damped dynamics, relaxations that stall, do not settle or run out
of attempts, and a run resumed after its finished segments equal to one never interrupted."""
from __future__ import annotations

import dataclasses
from dataclasses import replace

import numpy as np
import pytest

from diskfriction.models.packing.equilibria import mass_diagonal, start
from diskfriction.models.packing.prepared import prepare_scene
from diskfriction.models.packing.shear import ShearParams, network_of, shear
from diskfriction.scenes.packing import PackingScene


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
    where it was; one that ends 1e4 times above the tolerance still fails in one line."""
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
