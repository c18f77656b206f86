"""The pair certifier (detection/certify.py): the pairs of eigenvalues whose model dips are
flagged and split where they cross or come closest, the others certified; modes that do not
interact are decoupled and cost no spectrum; the far pairs it skips pass the full test."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation.linalg.solves import measured


def test_pair_certifier_flags_exactly_the_pairs_whose_model_dips():
    """certify.worst_uncertified_pair against a brute-force reading of its own rule on a fine
    grid: the Hermite cubic of y = |lambda_i - lambda_j|^2 from the end data, its minimum, and
    the margin rho min(y_a, y_b) - floor after a quarter of the cubic term; a flagged pair that
    crosses transversally (the signed gap's cubic monotone, slope >= rho |g_b - g_a|) is split
    where that cubic crosses zero, any other at the minimum."""
    from diskfriction.continuation.detection import certify
    rng = np.random.default_rng(3)
    t = np.linspace(0.0, 1.0, 200001)
    flagged = crossings = 0
    for _ in range(200):
        lam_a, lam_b = rng.normal(size=2), rng.normal(size=2)
        d_a, d_b = 0.3 * rng.normal(size=2), 0.3 * rng.normal(size=2)
        g, dg = lam_a[0] - lam_a[1], d_a[0] - d_a[1]
        h, dh = lam_b[0] - lam_b[1], d_b[0] - d_b[1]
        c = certify.hermite_coefficients(g * g, h * h, 2 * g * dg, 2 * h * dh)
        H = certify.cubic_at(c, t)
        margin = H.min() - 0.25 * abs(c[3]) - (0.5 * min(g * g, h * h) - 1e-12)
        if abs(margin) < 1e-6:
            continue  # too close to the threshold for the grid to decide
        got = certify.worst_uncertified_pair(lam_a.astype(complex), lam_b.astype(complex),
                                             d_a.astype(complex), d_b.astype(complex),
                                             np.arange(2), np.zeros(0, np.int64),
                                             np.zeros(0, np.int64), 0.5, 1e-12)
        assert np.isnan(got[0]) == (margin > 0)
        assert got[1].tolist() == [margin < 0] * 2
        if margin < 0:
            flagged += 1
            G = certify.cubic_at(certify.hermite_coefficients(g, h, dg, dh), t)
            slope = np.diff(G) / np.diff(t)
            transversal = g * h < 0 and (np.sign(slope) == np.sign(h - g)).all() and \
                np.abs(slope).min() >= 0.5 * abs(h - g) * (1 + 1e-6)
            if transversal:  # a crossing: split where the signed gap's model crosses zero
                crossings += 1
                assert got[2] and got[0] == pytest.approx(t[np.argmin(np.abs(G))], abs=1e-4)
            elif np.abs(slope).min() < 0.5 * abs(h - g) * (1 - 1e-6) or g * h > 0:
                assert not got[2] and got[0] == pytest.approx(t[np.argmin(H)], abs=1e-4)
    assert 20 < flagged < 180, flagged  # both outcomes exercised
    assert crossings >= 1, crossings


def test_two_real_eigenvalues_crossing_are_split_at_the_crossing_then_certified():
    """lambda = (t, 1 - t) over [0, 1]: they cross at 0.5 (modes that do not interact), so the
    split goes there, not 1/8 off an end; over [0, 0.5], whose end has them equal to within the
    resolution sqrt(floor), the pair is certified; a pair that turns back is not a crossing."""
    from diskfriction.continuation.detection import certify
    none, real, d = np.zeros(0, np.int64), np.arange(2), np.array([1.0, -1.0], complex)
    crossing = certify.worst_uncertified_pair(np.array([0.0, 1.0], complex), np.array([1.0, 0.0], complex),
                                              d, d, real, none, none, 0.5, 1e-12)
    assert crossing[0] == pytest.approx(0.5, abs=1e-12) and crossing[2] and crossing[1].all()
    resolved = certify.worst_uncertified_pair(np.array([0.0, 1.0], complex),
                                              np.array([0.5, 0.5 + 1e-7], complex),
                                              0.5 * d, 0.5 * d, real, none, none, 0.5, 1e-12)
    assert np.isnan(resolved[0]) and not resolved[1].any()
    touching = certify.worst_uncertified_pair(np.array([0.0, 1.0], complex), np.array([0.0, 1.0], complex),
                                              d, -d, real, none, none, 0.5, 1e-12)
    assert not touching[2] and touching[1].all()  # they approach and part: no crossing


def test_pair_certifier_covers_conjugate_and_complex_real_pairs():
    """A conjugate pair whose imaginary part closes, and a complex eigenvalue that sweeps over a
    real one, are flagged; the same eigenvalues moving apart are certified."""
    from diskfriction.continuation.detection import certify
    none = np.zeros(0, np.int64)
    # conjugate pair 1 +- 0.5 i -> 1 +- 0.5 i with Im slopes -1 then +1: Im dips to ~0.25
    lam = np.array([1 + 0.5j, 1 - 0.5j])
    closing = certify.worst_uncertified_pair(lam, lam, np.array([-1j, 1j]), np.array([1j, -1j]),
                                             none, np.array([0]), np.array([1]), 0.5, 0.0)
    opening = certify.worst_uncertified_pair(lam, lam * 1.5, np.array([0.5 + 0.25j, 0.5 - 0.25j]),
                                             np.array([0.5 + 0.25j, 0.5 - 0.25j]), none, np.array([0]),
                                             np.array([1]), 0.5, 0.0)
    assert closing[0] == pytest.approx(0.5) and np.isnan(opening[0])
    assert closing[1].tolist() == [True, True] and not opening[1].any()
    # complex 0 + 0.1 i moving from Re -1 to +1 over the real eigenvalue 0
    a, b = np.array([-1 + 0.1j, -1 - 0.1j, 0.0]), np.array([1 + 0.1j, 1 - 0.1j, 0.0])
    d = np.array([2.0, 2.0, 0.0], complex)
    sweep_over = certify.worst_uncertified_pair(a, b, d, d, np.array([2]), np.array([0]),
                                                np.array([1]), 0.5, 0.0)
    assert sweep_over[0] == pytest.approx(0.5, abs=1e-6)
    assert sweep_over[1].tolist() == [True, False, True]  # the conjugate partner stays apart


def test_modes_that_cross_without_interacting_cost_no_extra_spectrum():
    """Twelve real eigenvalues k p and 3 - k p (k = 1..6), decoupled, cross each other 33
    times inside p in (0, 1) (at p = 3 / (k + k'), 9 values): no collision, and no spectrum
    beyond one per point (their coupling l_i^H dA r_j is 0: certify.decoupled). Splitting at
    each crossing's root cost 9 extra spectra, the older rule (1/8 off the ends down to tol_p)
    74."""
    from diskfriction.continuation import Options, problem_from_functions, solve_branch

    k = np.arange(1, 7, dtype=float)
    problem = problem_from_functions(lambda u, p: u - p, dG_du=lambda u, p: np.eye(1),
                                     dG_dp=lambda u, p: -np.ones(1),
                                     A=lambda u, p: np.diag(np.concatenate([k * p, 3.0 - k * p])))
    with measured() as spent:
        result = solve_branch(problem, [0.0], (0.0, 1.0), Options(workers=0))
    assert result.success and result.collisions == () and result.branch.n_complex.max() == 0
    assert spent.spectra == len(result.p), spent.spectra - len(result.p)


def test_decoupled_bounds_the_imaginary_part_of_the_pairs_two_by_two_model():
    """certify.decoupled against the exact eigenvalues of diag(g, 0) + tau M on a fine grid of
    tau: where it says decoupled, the largest |Im| stays within thr; where the model's largest
    |Im| exceeds thr, it says coupled (the bound |g| sqrt|c| / sqrt(g'^2 - 4|c|) is exact for
    the linear model, c = m_12 m_21, g' = m_11 - m_22)."""
    from diskfriction.continuation.detection import certify
    rng = np.random.default_rng(5)
    tau = np.linspace(-40.0, 40.0, 400001)
    thr, said = 1e-3, {True: 0, False: 0}
    for _ in range(300):
        g = rng.normal()
        m = rng.normal(size=(2, 2)) * np.array([[1.0, 10.0 ** rng.uniform(-5, 0)],
                                                 [10.0 ** rng.uniform(-5, 0), 1.0]])
        m[0, 1] *= rng.choice([-1.0, 1.0])
        c, dg = m[0, 1] * m[1, 0], m[0, 0] - m[1, 1]
        D = (g + tau * dg) ** 2 + 4.0 * tau * tau * c  # the model's discriminant
        top = 0.5 * np.sqrt(np.maximum(-D, 0.0)).max()
        verdict = bool(certify.decoupled(np.array([g]), np.array([dg]), np.array([c]), thr)[0])
        said[verdict] += 1
        if verdict:
            assert top <= thr * (1 + 1e-6), (g, m, top)
        if top > 1.01 * thr and dg * dg > 4.0 * abs(c):
            assert not verdict, (g, m, top)
    assert min(said.values()) >= 30, said  # both outcomes exercised


def test_a_crossing_through_a_narrow_complex_bubble_is_not_taken_for_decoupled():
    """[[p - p0, e], [-e, p0 - p]] has eigenvalues +-sqrt((p - p0)^2 - e^2): from afar two real
    eigenvalues that cross (the labels p - p0 and p0 - p), but complex on |p - p0| < e. Their
    coupling is not zero, so the pair is split, not certified: the birth at p0 - e and the
    death at p0 + e are found with steps 700 times the bubble's width."""
    from diskfriction.continuation import Options, problem_from_functions, solve_branch

    p0, e = 0.4123, 1e-5
    problem = problem_from_functions(lambda u, p: u - p, dG_du=lambda u, p: np.eye(1),
                                     dG_dp=lambda u, p: -np.ones(1),
                                     A=lambda u, p: np.array([[p - p0, e], [-e, p0 - p]]))
    result = solve_branch(problem, [0.0], (0.0, 1.0), Options(workers=0))
    assert result.success and np.diff(result.p).max() >= 500 * 2 * e
    kinds = [(c.kind, c.p) for c in result.collisions]
    assert [k for k, _ in kinds] == ["birth", "death"]
    assert [p for _, p in kinds] == pytest.approx([p0 - e, p0 + e], abs=1e-10)


@pytest.mark.slow
def test_pairs_beyond_their_reaches_pass_the_pair_test():
    """certify.reaches: any two eigenvalues whose real parts lie r_i + r_j apart at the start
    pass the pair test (certify._pair_margin, the full test uncertified_pairs skips for them),
    however they move and turn within their bounds; drawn at the bound itself, where the skip
    is tightest, with every end datum at its extreme."""
    from diskfriction.continuation.detection import certify
    rng = np.random.default_rng(11)
    rho, doubt, tested = 0.5, 0.25, 0
    for _ in range(20000):
        lam_a = rng.normal(size=2) + 1j * rng.normal(size=2) * (rng.random() < 0.3)
        moved = rng.exponential(size=2) * 10.0 ** rng.uniform(-6, 0)
        lam_b = lam_a + moved * np.exp(2j * np.pi * rng.random(2))
        slopes = rng.exponential(size=2) * 10.0 ** rng.uniform(-6, 1)
        d_a = slopes * np.exp(2j * np.pi * rng.random(2))
        d_b = slopes * np.exp(2j * np.pi * rng.random(2)) * rng.choice([1.0, rng.random()])
        r = certify.reaches(lam_a, lam_b, d_a, d_b, np.arange(2), rho, doubt)
        shift = r.sum() * (1.0 + rng.choice([0.0, 1e-3, 1.0])) - (lam_a[1] - lam_a[0]).real
        lam_a[1], lam_b[1] = lam_a[1] + shift, lam_b[1] + shift  # |Re gap| >= r_0 + r_1 at a
        bad, _, _ = certify._pair_margin(lam_a[0] - lam_a[1], lam_b[0] - lam_b[1], d_a[0] - d_a[1],
                                         d_b[0] - d_b[1], rho, 0.0, doubt)
        assert not bad
        tested += 1
    assert tested == 20000


@pytest.mark.slow
def test_uncertified_pairs_skip_only_pairs_that_pass():
    """uncertified_pairs with its far-pair skips (certify._uncertified_real_pairs, and
    _uncertified_mixed_pairs for an upper complex label with a real one) returns what the plain
    double loops over every pair return, in the same order: a crowded spectrum with crossings,
    near misses and a fast eigenvalue sweeping through it, a few complex ones, and one label
    that is not finite (then every pair is tested)."""
    from diskfriction.continuation.detection import certify
    rng = np.random.default_rng(5)
    mixed = 0
    for case in range(60):
        n = int(rng.integers(2, 300))
        lam_a = np.sort(rng.uniform(0, 10, n)) + 0j
        d_a = rng.normal(scale=10.0 ** rng.uniform(-4, 0), size=n) + 0j
        d_b = d_a + rng.normal(scale=1e-3, size=n)
        lam_b = lam_a + 0.5 * (d_a + d_b) + rng.normal(scale=1e-4, size=n)
        lam_b[0] = lam_a[0] + 8.0  # a fast one through the whole crowd
        d_a[0] = d_b[0] = 8.0
        upper = np.flatnonzero(rng.random(n) < 0.05)
        lam_a[upper] += 0.3j
        lam_b[upper] += 0.3j
        real = np.setdiff1d(np.arange(n), upper)
        if case % 10 == 9:
            lam_b[real[-1]] = np.nan
        rho, floor, doubt = 0.5, 1e-12, 0.25
        got = certify.uncertified_pairs(lam_a, lam_b, d_a, d_b, real, upper, np.zeros(0, np.int64),
                                        rho, floor, doubt)
        want = [[], [], [], [], []]
        resolution = np.sqrt(floor)
        for a in range(real.size):
            for b in range(a + 1, real.size):
                i, j = real[a], real[b]
                bad, y, t = certify._pair_margin(lam_a[i] - lam_a[j], lam_b[i] - lam_b[j], d_a[i] - d_a[j],
                                                 d_b[i] - d_b[j], rho, floor, doubt)
                if bad:
                    passed, root = certify._crossing((lam_a[i] - lam_a[j]).real, (lam_b[i] - lam_b[j]).real,
                                                     (d_a[i] - d_a[j]).real, (d_b[i] - d_b[j]).real, rho,
                                                     resolution)
                    if not passed:
                        for k, v in enumerate((i, j, y, t if np.isnan(root) else root, not np.isnan(root))):
                            want[k].append(v)
        for i in upper:  # then each upper one with each real one (_uncertified_mixed_pairs)
            for j in real:
                bad, y, t = certify._pair_margin(lam_a[i] - lam_a[j], lam_b[i] - lam_b[j], d_a[i] - d_a[j],
                                                 d_b[i] - d_b[j], rho, floor, doubt)
                if bad:
                    mixed += 1
                    for k, v in enumerate((i, j, y, t, False)):
                        want[k].append(v)
        for k in range(5):
            assert got[k].tolist() == want[k]
    assert mixed > 0  # the fast eigenvalue meets complex ones
