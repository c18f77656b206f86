"""Statistics per unit strain (models/packing/strain_statistics.py): on a branch whose states
crowd where the growth rate peaks, on a closed-form spectrum, the strain-weighted fractions and
median converge to an even grid's of 10^5 points within the trapezoid rule's error while the
per-state ones are off; the samples' figures agree with the grid to its spacing; on the shared
24-disk shear, the states' figures agree with the same branch's spectrum solved again on an
even strain grid within the rule's error, step by step from its located collisions."""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from sheared_packing import SCENE

from diskfriction.continuation.branch import Branch, Piece, Stop, StopCode
from diskfriction.continuation.spectra.tracking import count_complex_pairs
from diskfriction.models.packing.damped import fastest_damped
from diskfriction.models.packing.dynamics import fastest_pair
from diskfriction.models.packing.equilibria import mass_diagonal
from diskfriction.models.packing.sampled import SpectrumSample, grid_strains, sampled_spectra, with_samples
from diskfriction.models.packing.shear import network_of
from diskfriction.models.packing.strain_statistics import (cell_widths, sample_weights,
                                                           state_weights, strain_covered, strain_mean,
                                                           strain_quantile, strain_statistics)

PERIOD = 1e-3
"""The closed-form pair's period in strain: lambda = 1 +- i b, b = max(sin(2 pi gamma / PERIOD), 0)."""

SEGMENTS = ((0.0, 0.004), (0.0040001, 0.01))
"""The closed-form branch's two segments, a plastic event's jump of 1e-7 between them."""

STEP, CROWD = 1e-5, 200
"""The states: every STEP, and CROWD more within 2e-5 of every peak of b (as near events)."""

GRID = 100_000
"""The even grid's points over the strain covered."""


def b_of(gamma):
    return np.maximum(np.sin(2 * np.pi * np.asarray(gamma) / PERIOD), 0.0)


def spectrum(gamma: float) -> np.ndarray:
    """Three translations' zeros, two real eigenvalues and the pair 1 +- i b(gamma) [1 / time^2]."""
    pair = 1.0 + 1j * b_of(gamma)
    return np.array([0, 0, 0, 1.0, 2.0, pair, np.conj(pair)], dtype=complex)


def sigma_of(gamma):
    """The pair's undamped growth rate |Im sqrt(1 + i b)|."""
    return np.abs(np.sqrt(1.0 + 1j * b_of(gamma)).imag)


def state_strains(lo: float, hi: float) -> np.ndarray:
    peaks = np.arange(0.25, hi / PERIOD) * PERIOD
    crowds = [np.linspace(p - 2e-5, p + 2e-5, CROWD) for p in peaks if lo < p - 2e-5 and p + 2e-5 < hi]
    return np.unique(np.concatenate([np.arange(lo, hi, STEP), [hi], *crowds]))


def closed_form_branch(every: float = 1e-5) -> Branch:
    """The closed-form spectrum at uneven states in two segments, its samples every `every`."""
    parts = [state_strains(lo, hi) for lo, hi in SEGMENTS]
    gamma = np.concatenate(parts)
    eigenvalues = np.array([spectrum(g) for g in gamma])
    stop = Stop(StopCode.REACHED)
    pieces = (Piece("segment", 0, 0, parts[0].size, stop),
              Piece("segment", 1, parts[0].size, gamma.size, stop))
    samples = tuple(SpectrumSample(float(g), spectrum(g), count_complex_pairs(spectrum(g)[3:]), 0.0)
                    for lo, hi in SEGMENTS for g in grid_strains(lo, hi, every))
    return Branch(gamma, np.zeros((gamma.size, 6)), eigenvalues,
                  np.array([count_complex_pairs(e[3:]) for e in eigenvalues]), np.zeros(gamma.size), (),
                  stop, pieces=pieces, labelled={"sample": samples}, parameter="gamma", matrix="M^-1 J")


def even_grid() -> np.ndarray:
    """GRID strains evenly over the segments (each its share)."""
    covered = sum(hi - lo for lo, hi in SEGMENTS)
    return np.concatenate([np.linspace(lo, hi, round(GRID * (hi - lo) / covered)) for lo, hi in SEGMENTS])


def rule_error(branch: Branch, indicator: np.ndarray) -> float:
    """The trapezoid rule's bound on the strain an indicator at the states misplaces: half of
    every step (within a segment) across which it changes."""
    gamma, error = branch.p, 0.0
    for piece in branch.of_kind("segment"):
        g, on = gamma[piece.start:piece.stop], indicator[piece.start:piece.stop]
        error += 0.5 * float(np.sum(np.diff(g)[on[1:] != on[:-1]]))
    return error


def grid_error(indicator: np.ndarray) -> float:
    """An even grid's bound on the strain it misplaces: its spacing at every change."""
    spacing = sum(hi - lo for lo, hi in SEGMENTS) / GRID
    return spacing * int(np.sum(indicator[1:] != indicator[:-1]))


@pytest.fixture(scope="module")
def closed_form():
    return closed_form_branch()


def test_the_cells_add_up_to_the_strain_covered_and_none_reaches_across_a_plastic_event(closed_form):
    assert np.allclose(cell_widths(np.array([1.0, 2.0, 4.0]), 1.0, 4.0), [0.5, 1.5, 1.0])
    assert np.allclose(cell_widths(np.array([1.0, 2.0]), 0.0, 4.0), [1.5, 2.5])
    covered = sum(hi - lo for lo, hi in SEGMENTS)
    w = state_weights(closed_form)
    assert strain_covered(closed_form) == pytest.approx(covered, rel=1e-12)
    assert w.sum() == pytest.approx(covered, rel=1e-12) and (w > 0).all()
    end = closed_form.of_kind("segment")[0].stop  # the first state after the plastic event
    gamma = closed_form.p
    assert w[end - 1] == pytest.approx(0.5 * (gamma[end - 1] - gamma[end - 2]), rel=1e-12)
    assert w[end] == pytest.approx(0.5 * (gamma[end + 1] - gamma[end]), rel=1e-12)
    samples = sample_weights(closed_form)
    assert samples.sum() == pytest.approx(covered, rel=1e-12)
    first = len(grid_strains(*SEGMENTS[0], 1e-5))  # the first sample after the plastic event
    assert np.allclose(samples[[0, first - 1]], 0.5e-5, rtol=1e-9)  # on the segment's ends
    assert samples[first] == pytest.approx(0.00401 - 0.0040001 + 0.5e-5, rel=1e-9)  # to the end
    assert np.allclose(np.delete(samples, [0, first - 1, first, -1]), 1e-5, rtol=1e-9)
    assert strain_covered(closed_form, above=0.005) == pytest.approx(0.01 - 0.005, rel=1e-12)


def test_the_complex_fraction_per_unit_strain_is_the_grids_and_the_per_state_one_is_off(closed_form):
    grid = even_grid()
    on_grid = b_of(grid) > 0
    truth = float(np.mean(on_grid))
    pairs = closed_form.n_complex > 0
    weighted = strain_mean(pairs, state_weights(closed_form))
    covered = strain_covered(closed_form)
    bound = (rule_error(closed_form, pairs) + grid_error(on_grid)) / covered
    assert bound < 0.01  # a bound that can fail
    assert abs(weighted - truth) <= bound
    assert np.mean(pairs) - truth > 0.2  # the states crowd where the pair is
    statistics = strain_statistics(closed_form)
    assert statistics.complex_fraction == weighted and statistics.unstable_fraction == (weighted,)
    assert statistics.pairs_mean == weighted  # one pair where any
    assert statistics.collisions_per_disk_strain == 0.0  # tracked, none located


@pytest.mark.parametrize("eta", [0.3, 0.8])
def test_the_damped_unstable_fraction_per_unit_strain_is_the_grids(closed_form, eta):
    """1 +- i b grows at the drag eta where b > eta (b^2 > eta^2 Re lambda): over whole
    periods the fraction (pi - 2 arcsin eta) / (2 pi)."""
    grid = even_grid()
    on_grid = b_of(grid) > eta
    grows = np.array([fastest_damped(e, eta) > 0 for e in closed_form.eigenvalues])
    weighted = strain_statistics(closed_form, (0.0, eta)).unstable_fraction[1]
    bound = (rule_error(closed_form, grows) + grid_error(on_grid)) / strain_covered(closed_form)
    assert abs(weighted - np.mean(on_grid)) <= bound < 0.02
    assert np.mean(grows) - np.mean(on_grid) > 0.2
    assert np.mean(on_grid) == pytest.approx((np.pi - 2 * np.arcsin(eta)) / (2 * np.pi), abs=2e-3)


def test_the_median_growth_rate_per_unit_strain_splits_the_grids_strain_with_a_pair_in_half(closed_form):
    """The median v over the strain with a pair: the grid's share of that strain with sigma <= v
    is 1/2 within the rule's error (of the strain with a pair, and of that below v: the states
    misplace at most half of each step across which either changes) and the quantile's own (half
    the heaviest state's weight)."""
    grid = even_grid()
    sigma = sigma_of(grid)[b_of(grid) > 0]
    w, pairs = state_weights(closed_form), closed_form.n_complex > 0
    state_sigma = np.array([fastest_pair(e)[1] for e in closed_form.eigenvalues])
    median = strain_statistics(closed_form).growth_median[0]
    assert median == pytest.approx(strain_quantile(state_sigma[pairs], w[pairs], 0.5), rel=1e-12)
    with_pair = float(np.sum(w[pairs]))
    below = pairs & (state_sigma <= median)
    on_grid = b_of(grid) > 0
    on_grid_below = on_grid & (sigma_of(grid) <= median)
    grid_with_pair = np.mean(on_grid) * strain_covered(closed_form)
    bound = ((rule_error(closed_form, pairs) + rule_error(closed_form, below)) / with_pair
             + 0.5 * w.max() / with_pair + (grid_error(on_grid) + grid_error(on_grid_below)) / grid_with_pair)
    assert bound < 0.07
    assert abs(np.mean(sigma <= median) - 0.5) <= bound
    assert np.mean(sigma <= np.median(state_sigma[pairs])) - 0.5 > 0.2  # the states' median: near the peaks
    assert np.median(sigma) == pytest.approx(float(sigma_of(PERIOD / 8)), rel=1e-3)  # b = 1/sqrt 2 halves it


def test_the_samples_figures_are_the_grids_to_their_spacing(closed_form):
    grid = even_grid()
    covered = strain_covered(closed_form)
    sampled = strain_statistics(closed_form, (0.0, 0.3), sampled=True)
    for fraction, on_grid in ((sampled.complex_fraction, b_of(grid) > 0),
                              (sampled.unstable_fraction[1], b_of(grid) > 0.3)):
        changes = int(np.sum(on_grid[1:] != on_grid[:-1]))
        assert abs(fraction - np.mean(on_grid)) <= (changes * 0.5e-5 + grid_error(on_grid)) / covered
    assert sampled.strain == pytest.approx(covered, rel=1e-12)
    assert sampled.growth_max[0] == pytest.approx(float(sigma_of(PERIOD / 4)), rel=1e-6)  # a sample at a peak


def test_a_quantile_of_equal_weights_is_numpys_hazen_and_weight_moves_it():
    values = np.random.default_rng(1).normal(size=101)
    q = np.array([0.1, 0.5, 0.9])
    assert np.allclose(strain_quantile(values, np.full(101, 0.3), q), np.quantile(values, q, method="hazen"))
    assert strain_quantile(values, np.ones(101), 0.5) == np.median(values)
    heavy = np.ones(101)
    heavy[np.argmax(values)] = 1000.0
    assert np.sort(values)[-2] < strain_quantile(values, heavy, 0.5) < values.max()  # its share holds 1/2
    assert np.isnan(strain_quantile(values, np.zeros(101), 0.5))


def test_rounding_grows_no_mode_and_a_negative_eigenvalue_grows_at_any_drag():
    lam = np.array([0.0, 1e-14j, 2.0 + 1e-12j, 2.0 - 1e-12j, 3.0])
    assert fastest_damped(lam, 0.0) == 0.0 and fastest_damped(lam, 0.5) == -0.25  # the zeros are no mode
    assert fastest_damped(np.array([-4.0, 1.0]), 10.0) == pytest.approx((-10 + np.sqrt(116)) / 2)
    assert fastest_damped(np.array([np.nan, 1 + 2j, 1 - 2j]), 0.0) == pytest.approx(abs(np.sqrt(1 + 2j).imag))


def test_a_branch_without_spectra_at_its_states_is_refused(closed_form):
    none = replace(closed_form, n_complex=np.full(len(closed_form), -1), labelled={})
    with pytest.raises(ValueError, match="carry no spectrum"):
        strain_statistics(none)
    with pytest.raises(ValueError, match="no samples"):
        strain_statistics(none, sampled=True)


@pytest.fixture(scope="module")
def gridded(packing, branch):
    """The shared 24-disk branch with its spectrum solved again every 1e-5 of strain (201
    equilibria at fixed strain, sampled.sampled_spectra: 0.6 s)."""
    network = network_of(SCENE, packing)
    mass = mass_diagonal(network, SCENE.m, SCENE.inertia)
    return with_samples(branch, sampled_spectra(network, mass, branch, 1e-5, None, SCENE.matrix, 1e-11, 1e-9))


def pair_changes(branch: Branch) -> tuple[list[int], list[float]]:
    """Per step of the branch, how often the presence of a complex pair changes within it (its
    located births and deaths in order), and where."""
    changes, where = [], []
    for k in range(len(branch) - 1):
        n, count = int(branch.n_complex[k]), 0
        for c in sorted((c for c in branch.collisions if c.step == k), key=lambda c: c.p):
            m = n + (1 if str(c.kind) == "birth" else -1)
            if (m > 0) != (n > 0):
                count += 1
                where.append(c.p)
            n = m
        assert n == branch.n_complex[k + 1]  # every change is a located collision
        changes.append(count)
    return changes, where


def pairs_at(branch: Branch, g: float) -> int:
    """The complex pairs at strain g: those at the last state at or before it, plus the
    births less the deaths located in between."""
    k = int(np.searchsorted(branch.p, g, side="right")) - 1
    return int(branch.n_complex[k]) + sum(1 if str(c.kind) == "birth" else -1 for c in branch.collisions
                                          if branch.p[k] < c.p <= g)


@pytest.mark.slow
def test_a_shears_strain_statistics_are_its_spectrum_on_an_even_grid(gridded):
    """The states' complex fraction against the grid's, within the rule's error from the
    collisions (half a step holding one change, a whole step holding more) and the grid's
    (half its spacing at each change); the grid's against the exact figure the located
    collisions give, to its spacing; the fastest growth rate at eta = 0 is fastest_pair's."""
    branch, gamma = gridded, gridded.p
    changes, where = pair_changes(branch)
    h = np.diff(gamma)
    rule = float(np.sum(np.where(np.array(changes) == 1, 0.5 * h, h)[np.array(changes) > 0]))
    covered = strain_covered(branch)
    assert covered == float(gamma[-1] - gamma[0]) and len(branch.of_kind("segment")) == 1
    states = strain_statistics(branch, (0.0, SCENE.omega_0 * 0.01))
    samples = strain_statistics(branch, (0.0, SCENE.omega_0 * 0.01), sampled=True)
    grid = 0.5e-5 * len(where)
    assert abs(states.complex_fraction - samples.complex_fraction) <= (rule + grid) / covered
    edges = np.concatenate([[gamma[0]], where, [gamma[-1]]])  # exact: pairs between the changes
    with_pair = [pairs_at(branch, 0.5 * (a + b)) > 0 for a, b in zip(edges, edges[1:])]
    exact = float(np.sum(np.diff(edges)[with_pair])) / covered
    assert abs(samples.complex_fraction - exact) <= grid / covered
    assert abs(states.complex_fraction - exact) <= rule / covered
    assert states.unstable_fraction[0] == states.complex_fraction  # no real eigenvalue below 0
    assert samples.strain == pytest.approx(covered, rel=1e-12)
    assert states.collisions_per_disk_strain == len(branch.collisions) / (SCENE.N * covered)
    sigma = [fastest_pair(e)[1] for e in branch.eigenvalues]
    assert np.allclose([fastest_damped(e, 0.0) for e in branch.eigenvalues], sigma, rtol=1e-12, atol=0)
    assert states.growth_max[0] == max(sigma)
    assert states.unstable_fraction[1] < states.unstable_fraction[0]  # the drag damps some pairs
