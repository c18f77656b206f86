"""Newtonian dynamics: the step is Verlet with the quasistatic history rule, the energy budget
closes at second order, growth rates match the spectrum, sliding and staying put."""
from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from diskfriction.models.chain.sweep import sweep
from diskfriction.dynamics import (OnsetParams, Perturbation, Stepper, choose_dt, simulate, sliding_onset,
                      spectrum, summarize)
from diskfriction.dynamics.onset import trailing_mean
from diskfriction.scenes import Effects, Scene
from diskfriction.symbolic import System


@pytest.fixture(scope="module")
def paper():
    return System.from_scene(Scene())


@pytest.fixture(scope="module")
def branch_point(paper):
    """(q, xi) at F_x from a sweep that ends exactly there, cached per F_x."""
    cache = {}

    def at(F_x):
        if F_x not in cache:
            b = sweep(paper, 0.0, F_x)
            cache[F_x] = (b.q[-1], b.xi[-1])
        return cache[F_x]
    return at


def observed_order(errors: list[float]) -> np.ndarray:
    """log2 of the ratios of errors at dt, dt/2, dt/4, ..."""
    e = np.asarray(errors)
    return np.log2(e[:-1] / e[1:])


@pytest.mark.parametrize("conventions", ["model", "lammps"])
def test_one_step_is_verlet_with_the_quasistatic_history_rule(branch_point, conventions):
    """The guard of symbolic/template.py: the stepper's pasted assembly and increments equal
    the kernel module's forces and history_step (continuation's), in both conventions. Disk 10
    moves 5e-3 towards disk 1 (closing pair 10-1, 2.5e-3 open, and opening pair 9-10, 8e-6
    closed) and disk 5 turns by 0.2 (its contacts slide)."""
    q, xi = branch_point(0.083)
    system = System.from_scene(Scene(effects=Effects(conventions=conventions)))
    N = system.N
    rng = np.random.default_rng(5)
    v = rng.normal(0, 1e-3, q.size)
    v[N - 1], v[2 * N + 4] = 0.5, 20.0
    dt, F_x = 1e-2, 0.083
    st = Stepper(system, q, v, xi, F_x, dt, 1, 4)
    st.advance(1)
    minv = 1 / system.mass_diagonal()
    v_half = v + 0.5 * dt * minv * system.forces(q, xi, F_x)
    q1 = q + dt * v_half
    xi1, slid = system.history_step(q, q1, xi, cap=True)
    v1 = v_half + 0.5 * dt * minv * system.forces(q1, xi1, F_x)
    delta0, delta1 = system.overlaps(q), system.overlaps(q1)
    assert ((delta0 <= 0) & (delta1 > 0)).any() and ((delta0 > 0) & (delta1 <= 0)).any()
    assert slid.any()
    assert np.abs(st.q - q1).max() <= 1e-15 * np.abs(q1).max()
    assert np.abs(st.xi - xi1).max() <= 1e-12 * np.abs(xi1).max()
    assert np.abs(st.v - v1).max() <= 1e-12 * np.abs(v1).max()


def test_a_run_split_into_calls_is_bit_identical_to_one_call(paper, branch_point):
    q, xi = branch_point(0.083)
    v = np.random.default_rng(6).normal(0, 1e-3, q.size)
    one, split = (Stepper(paper, q, v, xi, 0.083, 5e-3, 7, 200) for _ in range(2))
    one.advance(700)
    for n in (1, 99, 300, 300):
        split.advance(n)
    for a, b in ((one.q, split.q), (one.v, split.v), (one.xi, split.xi),
                 (one.frames().energy, split.frames().energy)):
        assert np.array_equal(a, b)


def budget_errors(scene: Scene, fractions, t_end=50.0, amplitude=1e-3):
    """Max |budget - budget(0)| and max |E_kin + U_n + U_load - its start| (no W_t) per dt."""
    s = System.from_scene(scene)
    q, xi = s.rest_state()
    spec = spectrum(s, q, xi)
    with_w, without_w = [], []
    for f in fractions:
        tr = simulate(s, q, xi, 0.0, t_end, dt=choose_dt(spec, f),
                      perturbation=Perturbation("random-velocity", amplitude, seed=2))
        assert np.isnan(tr.breach_t).all() and tr.W_slip[-1] == 0.0  # nothing slides
        e = tr.E_kin + tr.U_n + tr.U_load
        with_w.append(tr.budget_error())
        without_w.append(np.abs(e - e[0]).max())
    return with_w, without_w


def test_frictionless_energy_is_conserved_and_its_error_is_second_order_in_dt():
    """mu = 0 (no tangential force): E_kin + U_n + U_load is the energy; Verlet keeps its error
    O(dt^2). Pre-compressed ring (eps = 1e-3) so every contact stays closed."""
    with_w, without_w = budget_errors(Scene(N=4, eps=1e-3, mu=0.0), (0.2, 0.1, 0.05))
    assert with_w == without_w  # W_t = 0 without friction
    assert np.all(np.abs(observed_order(with_w) - 2) < 0.15), with_w
    assert with_w[-1] < 1e-3 * 6e-6  # E_kin ~ 6e-6 in this run


@pytest.mark.parametrize("conventions", ["model", "lammps"])
def test_budget_with_tangential_work_closes_at_second_order_while_sticking(conventions):
    """With friction and nothing sliding the Mindlin force is still not conservative: only the
    budget with the tangential work W_t closes, and it closes at O(dt^2). With the "lammps"
    lever arm W_t includes the torques' extra path (delta/2)(dtheta_i + dtheta_j)
    (symbolic/template.py); without it the order drops to 1.8 here."""
    with_w, without_w = budget_errors(Scene(eps=1e-3, effects=Effects(conventions=conventions)),
                                      (0.2, 0.1, 0.05))
    assert np.all(np.abs(observed_order(with_w) - 2) < 0.15), with_w
    # dropping W_t leaves an error that does not converge: the path's tangential work
    assert np.all(np.abs(observed_order(without_w)) < 0.2) and without_w[-1] > 100 * with_w[-1]


def test_budget_closes_while_the_chain_slides(paper, branch_point):
    q, xi = branch_point(0.083)
    tr = simulate(paper, q, xi, 0.083, 300.0, perturbation=Perturbation("eigenvector", 1e-10))
    assert tr.W_slip[-1] < -1e-3  # sliding dissipated energy ...
    assert np.all(np.diff(tr.W_slip) <= 1e-15)  # ... and never produced any
    mechanical = tr.E_kin + tr.U_n + tr.U_load  # what the tangential work exchanges with
    assert tr.budget_error() < 1e-3 * np.ptp(mechanical)


@pytest.mark.parametrize("F_x", [0.03, 0.083])
def test_measured_growth_rate_matches_the_spectrum_within_5_percent(paper, branch_point, F_x):
    """Started along the growing solution of the largest complex pair of M^-1 J, small."""
    q, xi = branch_point(F_x)
    tr = simulate(paper, q, xi, F_x, 150.0, perturbation=Perturbation("eigenvector", 1e-10))
    s = summarize(tr)
    assert s["fit"]["reason"] == "ok" and s["fit"]["blocks"] >= 20
    assert s["sigma_predicted"] > 0.05
    assert abs(s["sigma_measured"] / s["sigma_predicted"] - 1) < 0.05, s["fit"]


def test_stable_point_stays_put(paper, branch_point):
    """F_x = 0.05: all eigenvalues of M^-1 J real; a random kick neither grows nor slides."""
    q, xi = branch_point(0.05)
    assert spectrum(paper, q, xi).pairs.size == 0
    tr = simulate(paper, q, xi, 0.05, 500.0, perturbation=Perturbation("random-velocity", 1e-6))
    s = summarize(tr)
    assert s["M_max"] < 1e-10 and not s["slid"] and s["sigma_measured"] is None
    assert all(t is None for t in s["first_breach"]["t"])


@pytest.mark.parametrize("F_x, slides", [(0.06, True), (0.09, True), (0.02, False)])
def test_load_above_the_total_coulomb_limit_slides(F_x, slides):
    """N = 3, mu = 0.1, F_y = 0.1: Coulomb limit N mu F_y = 0.03. Above it every substrate
    contact slides at |F_t| = mu F_n and the centre of mass accelerates at
    (F_x - N mu F_y) / (N m); below it the chain stays."""
    s = System.from_scene(Scene(N=3, mu=0.1, eps=1e-3))
    q, xi = s.rest_state()
    tr = simulate(s, q, xi, F_x, 20.0)
    summary = summarize(tr)
    C = tr.C_x - tr.C_x[0]
    if slides:
        late = tr.t > 5.0
        accel = 2 * np.polyfit(tr.t[late], C[late], 2)[0]
        assert accel == pytest.approx((F_x - 3 * 0.1 * 0.1) / 3, rel=0.02)
        assert summary["slid"] and np.isfinite(tr.breach_t).all()
    else:
        assert abs(C).max() < 1e-2 and not summary["slid"]


def test_trajectory_converges_at_second_order_under_dt(paper, branch_point):
    from diskfriction.dynamics.start import perturb
    q, xi = branch_point(0.05)
    q0, v0, xi0 = perturb(paper, q, xi, Perturbation("random-velocity", 1e-4, seed=4))
    t_end, n0 = 20.0, 1000  # dt = 0.02, a fifth of the step limit 2 / omega_max
    end = []
    for n in (n0, 2 * n0, 4 * n0, 16 * n0):
        st = Stepper(paper, q0, v0, xi0, 0.05, t_end / n, n, 2)
        st.advance(n)
        end.append(st.q.copy())
    errors = [np.abs(e - end[-1]).max() for e in end[:-1]]
    assert np.all(np.abs(observed_order(errors) - 2) < 0.3), errors


def test_eigenvector_start_has_the_requested_amplitude_and_follows_the_history(paper,
                                                                                branch_point):
    from diskfriction.dynamics.start import perturb
    q, xi = branch_point(0.083)
    q1, v1, xi1 = perturb(paper, q, xi, Perturbation("eigenvector", 1e-7))
    N = paper.N
    assert np.hypot(q1[:N] - q[:N], q1[N:2 * N] - q[N:2 * N]).max() <= 1e-7 * (1 + 1e-12)
    assert np.allclose(xi1, paper.history_step(q, q1, xi)[0], rtol=0, atol=1e-20)
    with pytest.raises(ValueError, match="complex pair"):
        perturb(paper, q, xi, Perturbation("eigenvector", 1e-7, pair=5))


def test_onset_is_the_last_upward_crossing_of_a_lasting_excursion():
    t = np.linspace(0, 10, 1001)
    x = np.zeros((t.size, 3))
    x[:, 0] = np.where(t > 5, 0.01 * (t - 5), 0.0)  # slides from t = 5
    x[:, 1] = np.where((t > 2) & (t < 3), 0.05, 0.0)  # an excursion that returns
    x[:, 2] = 0.02 * np.sin(40 * t)  # oscillates, no drift
    onset_t, onset_x = sliding_onset(t, x, period=2 * np.pi / 40, params=OnsetParams(1e-3))
    assert onset_t[0] == pytest.approx(5.1 + np.pi / 40, abs=0.02)  # + half the mean's window
    assert np.isnan(onset_t[1:]).all() and np.isnan(onset_x[1:]).all()


def test_trailing_mean_is_exact():
    t = np.arange(10.0)
    a = np.arange(10.0)[:, None]
    m = trailing_mean(t, a, 3.0)[:, 0]
    assert list(m) == [0.0, 0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]


def test_bad_input_is_refused_at_the_door(paper, branch_point):
    q, xi = branch_point(0.05)
    with pytest.raises(ValueError, match="t_end"):
        simulate(paper, q, xi, 0.05, -1.0)
    with pytest.raises(ValueError, match="dt"):
        Stepper(paper, q, q * 0, xi, 0.05, 0.0, 1, 2)
    with pytest.raises(ValueError, match="kind"):
        Perturbation("kick", 1e-3)


def test_steps_end_exactly_at_t_end_and_never_pass_it():
    """--dt is an upper bound: the fewest whole strides of steps of t_end / n_steps no longer
    than dt (issue 9), so that the last frame is the end state (issue 23)."""
    from diskfriction.dynamics.simulate import plan_run
    from diskfriction.dynamics.start import Spectrum

    spec = Spectrum(np.array([4e-4, 1e-4]), np.eye(2), np.array([], dtype=int))  # limit 100
    for t_end, dt, stride, steps in [(10.0, 3.0, 1, 4), (10.0, 2.5, 1, 4), (1.0, 5.0, 1, 1),
                                     (10.0, 3.0, 3, 6), (10.0, 0.1, 7, 105), (7.0, None, 1, 2)]:
        plan = plan_run(spec, t_end, dt, stride)
        assert plan.n_steps == steps and plan.n_steps % plan.stride == 0
        assert plan.dt * plan.n_steps == pytest.approx(t_end, rel=1e-15)
        assert plan.dt <= (dt or 0.05 * 100)


def test_a_step_not_below_the_stability_limit_is_refused():
    """Velocity Verlet amplifies a mode once omega dt >= 2 (issue 23): dt = 2 / omega_max is
    refused, the step just below it is planned."""
    from diskfriction.dynamics.simulate import UnstableStep, plan_run, stability_limit
    from diskfriction.dynamics.start import Spectrum

    spec = Spectrum(np.array([4.0, 1.0]), np.eye(2), np.array([], dtype=int))  # omega_max = 2
    assert stability_limit(spec) == 1.0
    with pytest.raises(UnstableStep, match="stability limit"):
        plan_run(spec, 10.0, 1.0, 1)
    assert plan_run(spec, 10.0, 0.99, 1).dt < 1.0


def test_a_run_whose_budget_does_not_close_reports_no_sliding(paper, branch_point):
    """Below the start's stability limit a run can still go unstable when contacts stiffen
    (here at 0.95 of it, F_x = 0.03, where the chain does not slide): the budget does not
    close, so the summary says the run is not accurate and reports slid as None, in JSON
    without inf or nan; the same run at the default dt is accurate (issue 23)."""
    from diskfriction.dynamics.simulate import stability_limit

    q, xi = branch_point(0.03)
    limit = stability_limit(spectrum(paper, q, xi))
    start = Perturbation("eigenvector", 1e-10)
    bad = summarize(simulate(paper, q, xi, 0.03, 300.0, dt=0.95 * limit, perturbation=start))
    assert bad["accurate"] is False and bad["slid"] is None
    assert bad["budget_relative"] is None or bad["budget_relative"] > bad["budget_bound"]
    json.dumps(bad, allow_nan=False)
    good = summarize(simulate(paper, q, xi, 0.03, 300.0, perturbation=start))
    assert good["accurate"] is True and good["slid"] is False
    assert good["budget_relative"] < 0.1 * good["budget_bound"]  # the default dt: 2e-4


def test_the_last_frame_is_the_end_of_the_run(paper, branch_point):
    """summary t_end is the time the run ended, which is also the last frame's (issue 23: it
    was the last frame before t_end)."""
    q, xi = branch_point(0.03)
    traj = simulate(paper, q, xi, 0.03, 300.0, perturbation=Perturbation("eigenvector", 1e-10))
    assert traj.steps % traj.stride == 0
    assert traj.t[-1] == pytest.approx(300.0, rel=1e-12)
    assert summarize(traj)["t_end"] == pytest.approx(300.0, rel=1e-12)


@pytest.mark.slow
def test_compiled_stepper_is_reused_from_the_cache_by_a_new_process(paper):
    """numba's cache=True keeps the loop compiled against the generated kernel module."""
    Stepper(paper, *paper.rest_state()[:1], np.zeros(paper.ndof), paper.rest_state()[1],
            0.0, 1e-3, 1, 4).advance(1)  # compiled (or loaded) in this process
    code = ("from diskfriction.scenes import Scene; from diskfriction.symbolic import System\n"
            "import numpy as np\nfrom diskfriction.dynamics import Stepper\n"
            "s = System.from_scene(Scene()); q, xi = s.rest_state()\n"
            "st = Stepper(s, q, np.zeros_like(q), xi, 0.0, 1e-3, 1, 4); st.advance(1)\n"
            "print(sum(st.module.advance.stats.cache_hits.values()),"
            " sum(st.module.advance.stats.cache_misses.values()))")
    out = subprocess.run([sys.executable, "-c", code], env=dict(os.environ), check=True,
                         capture_output=True, text=True).stdout.split()
    assert out == ["1", "0"]
