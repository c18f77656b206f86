"""The gallery (examples/, docs/gallery.md): each example against its closed form or the
literature, at the tolerance the gallery states."""
from __future__ import annotations

import mpmath as mp
import numpy as np
import pytest
import sympy as sp

from gallery import EXAMPLES, load_example
from invariants import unaccounted_pair_changes

pytestmark = pytest.mark.slow  # whole runs of commands or examples: the slow tier (README, Tests)

TOL_P = 1e-10  # DetectionParams.tol_p: every collision and Hopf point is located to this


# ---- Ziegler's double pendulum --------------------------------------------------------------

def test_ziegler_derived_matrices_and_their_flutter_loads_are_the_closed_forms():
    """The example's Lagrangian derivation gives M = m l^2 [[3, 1], [1, 1]] and
    K = [[2k - P l, P l - k], [-k, k]]; det(K - s M) has a double root s exactly at
    P = (7/2 -+ sqrt 2) k/l."""
    z = load_example("ziegler")
    P, k, l, m = z.P, z.k, z.l, z.m
    assert sp.simplify(z.M - m * l**2 * sp.Matrix([[3, 1], [1, 1]])) == sp.zeros(2, 2)
    assert sp.simplify(z.K - sp.Matrix([[2 * k - P * l, P * l - k], [-k, k]])) == sp.zeros(2, 2)
    s = sp.Symbol("s")
    char = sp.Poly(sp.expand((z.K - s * z.M).det().subs({k: 1, l: 1, m: 1})), s)
    roots = sp.solve(sp.discriminant(char, s), P)
    assert sorted(roots, key=float) == [sp.Rational(7, 2) - sp.sqrt(2), sp.Rational(7, 2) + sp.sqrt(2)]


def test_ziegler_collisions_are_located_to_1e10_of_the_closed_form():
    """Flutter starts (birth) at P = 7/2 - sqrt 2 and ends (death) at 7/2 + sqrt 2 [k/l], the
    double squared frequency s = (7 - 2P)/4 = +-sqrt(2)/2 [k/(m l^2)] a Jordan block."""
    result = load_example("ziegler").problem.solve()
    assert result.success and not result.folds and not result.hopf
    births, deaths = 3.5 - np.sqrt(2), 3.5 + np.sqrt(2)
    (birth, death) = result.collisions
    assert (birth.kind, death.kind) == ("birth", "death")
    assert abs(birth.p - births) <= TOL_P and abs(death.p - deaths) <= TOL_P
    assert birth.eigenvalue == pytest.approx(np.sqrt(2) / 2, abs=1e-7)
    assert death.eigenvalue == pytest.approx(-np.sqrt(2) / 2, abs=1e-7)
    assert max(birth.left_right_overlap, death.left_right_overlap) <= 1e-6


# ---- Beck's column --------------------------------------------------------------------------

def beck_continuous() -> float:
    """The flutter load of the continuous column, P L^2 / EI, independent of the elements:
    w = C1 cosh(beta x) + C2 sinh(beta x) + C3 cos(alpha x) + C4 sin(alpha x) solves
    w'''' + lam w'' - Omega w = 0 (alpha^2, -beta^2 the roots in r^2); the four boundary
    conditions leave a 2 x 2 determinant D(Omega, lam), and flutter is where two frequencies
    merge: D = dD/dOmega = 0 (30 digits, mpmath)."""
    mp.mp.dps = 30

    def D(Om, lam):
        s = mp.sqrt(lam**2 + 4 * Om)
        a, b = mp.sqrt((lam + s) / 2), mp.sqrt((s - lam) / 2)
        return ((b**2 * mp.cosh(b) + a**2 * mp.cos(a)) * (b**3 * mp.cosh(b) + a**2 * b * mp.cos(a))
                - (b**2 * mp.sinh(b) + a * b * mp.sin(a)) * (b**3 * mp.sinh(b) - a**3 * mp.sin(a)))

    Om, lam = mp.findroot([D, lambda Om, lam: mp.diff(lambda o: D(o, lam), Om)], (120, 20))
    return float(lam)


def test_beck_first_collision_converges_to_20_05_at_fourth_order():
    """n = 2, 4, 8, 16 Hermite elements: one collision below P = 25 EI/L^2, converging to the
    continuous 20.0509536 (Beck's 20.05) with errors falling by 2^4 per halving (observed order
    3.82, 3.96 between the last two pairs); 16 elements are within 2.2e-4 of it."""
    reference = beck_continuous()
    assert round(reference, 2) == 20.05
    beck = load_example("beck")
    loads = []
    for n in (2, 4, 8, 16):
        result = beck.beck(n).solve()
        assert result.success and [c.kind for c in result.collisions] == ["birth"]
        loads.append(result.collisions[0].p)
    errors = np.array(loads) - reference
    assert np.all(errors > 0) and np.all(np.diff(errors) < 0)
    order = np.log2(errors[:-1] / errors[1:])
    assert order[-2:] == pytest.approx([4.0, 4.0], abs=0.25)
    assert abs(loads[-1] - reference) <= 2.2e-4 and abs(loads[-1] - 20.05) <= 0.005


# ---- FitzHugh-Nagumo ------------------------------------------------------------------------

def test_fitzhugh_nagumo_folds_hopf_points_and_collisions_match_the_closed_forms():
    """Folds at v^2 = 1 - 1/b, Hopf points at v^2 = 1 - eps b with omega^2 = eps (1 - eps b^2),
    collisions at v^2 = 1 + eps b -+ 2 sqrt(eps), I = I(v): folds to 1e-12 (the fold locator
    reaches |dx| <= 1e-9, so |dI| ~ 1e-18), Hopf points and collisions to tol_p = 1e-10, each
    at the v of its closed form, and the kinds as the branch runs from v = -2 to 2."""
    f = load_example("fitzhugh_nagumo")
    a, b, eps = f.a, f.b, f.eps
    result = f.problem.solve()
    assert result.success
    v_fold, v_hopf = np.sqrt(1 - 1 / b), np.sqrt(1 - eps * b)
    v_near, v_far = np.sqrt(1 + eps * b - 2 * np.sqrt(eps)), np.sqrt(1 + eps * b + 2 * np.sqrt(eps))
    # along the branch v rises: node -> focus (birth) -> Hopf -> node (death) -> fold -> ...
    expected = [("birth", -v_far), ("death", -v_near), ("birth", v_near), ("death", v_far)]
    assert [c.kind for c in result.collisions] == [kind for kind, _ in expected]
    for c, (_, v) in zip(result.collisions, expected):
        assert abs(c.p - f.current(v)) <= TOL_P and abs(c.u[0] - v) <= 1e-8
    assert [s.p for s in result.folds] == pytest.approx([f.current(-v_fold), f.current(v_fold)], abs=1e-12)
    assert [s.p for s in result.hopf] == pytest.approx([f.current(-v_hopf), f.current(v_hopf)], abs=TOL_P)
    for s in result.hopf:
        assert s.value == pytest.approx(1j * np.sqrt(eps * (1 - eps * b * b)), abs=1e-8)
        assert s.u[1] == pytest.approx((s.u[0] + a) / b, abs=1e-10)


# ---- Lorenz: a pitchfork, a collision and a Hopf point ---------------------------------------

LORENZ = {"sigma": 10.0, "b": 8.0 / 3.0}


def lorenz_collision() -> float:
    """The r > 1 where two real eigenvalues of the Jacobian on C+- collide: the root of the
    discriminant of lambda^3 + (sigma + b + 1) lambda^2 + b (sigma + r) lambda + 2 b sigma (r - 1)
    (sympy, then 30 digits by mpmath)."""
    lam, r = sp.symbols("lambda r")
    sigma, b = sp.Integer(10), sp.Rational(8, 3)
    cubic = lam**3 + (sigma + b + 1) * lam**2 + b * (sigma + r) * lam + 2 * b * sigma * (r - 1)
    roots = sp.Poly(sp.discriminant(cubic, lam), r).nroots(n=30)
    (root,) = [v for v in roots if v.is_real and 1 < v < 2]
    return float(root)


def test_lorenz_origin_passes_its_pitchfork_at_r_1_a_branch_point_not_a_fold():
    result = load_example("lorenz").problem.solve()
    assert result.success and not result.folds and not result.hopf and not result.collisions
    (point,) = result.branch_points
    assert point.kind == "branch" and abs(point.p - 1.0) <= 1e-12
    assert np.abs(point.u).max() <= 1e-12  # on the origin's branch


@pytest.mark.parametrize("side", [1, -1])
def test_lorenz_switched_branch_is_c_plus_or_minus_with_its_collision_and_hopf_point(side):
    """From the branch point to r = 30: x = y = side sqrt(b (r - 1)), z = r - 1 at every point;
    the birth at the discriminant's root and the Hopf point at 470/19, both to 1e-10."""
    from diskfriction.continuation import switch_branch

    example = load_example("lorenz").problem
    first = example.solve()
    new = switch_branch(example.problem, first, 0, 30.0, example.options, side=side)
    assert new.success and new.p[0] > 1.0 and new.p[-1] == 30.0
    x, y, z = new.u.T
    expected = side * np.sqrt(LORENZ["b"] * (new.p - 1.0))
    assert np.abs(x - expected).max() <= 1e-9 and np.abs(y - x).max() <= 1e-9
    assert np.abs(z - (new.p - 1.0)).max() <= 1e-9
    (birth,) = new.collisions
    assert birth.kind == "birth" and abs(birth.p - lorenz_collision()) <= TOL_P
    (hopf,) = new.hopf
    assert abs(hopf.p - 470 / 19) <= TOL_P and not new.folds and not new.branch_points


def test_lorenz_pitchfork_seen_from_c_plus_is_a_branch_point():
    """C+ followed down from r = 2 turns back at r = 1 (onto C-): a branch point, no fold."""
    from diskfriction.continuation import Options, solve_branch

    example = load_example("lorenz").problem
    x0 = np.sqrt(LORENZ["b"])
    result = solve_branch(example.problem, [x0, x0, 1.0], (2.0, 0.5), Options(ds_max=0.05))
    (point,) = result.branch_points
    assert abs(point.p - 1.0) <= 1e-12 and not result.folds


# ---- Brusselator and Bratu ------------------------------------------------------------------

def test_brusselator_birth_hopf_and_death_are_the_closed_forms():
    """A = 1.5: complex for (1 - A)^2 < B < (1 + A)^2, Hopf at 1 + A^2 with omega = A."""
    a = load_example("brusselator").a
    result = load_example("brusselator").problem.solve()
    assert result.success and not result.folds and not result.branch_points
    birth, death = result.collisions
    assert (birth.kind, death.kind) == ("birth", "death")
    assert abs(birth.p - (1 - a) ** 2) <= TOL_P and abs(death.p - (1 + a) ** 2) <= TOL_P
    (hopf,) = result.hopf
    assert abs(hopf.p - (1 + a * a)) <= TOL_P and abs(hopf.value - 1j * a) <= 1e-9


def test_brusselator_chain_finds_every_closed_form_point_at_about_one_spectrum_each():
    """The reaction-diffusion chain on N = 20 points (40 unknowns): its 5 collisions, 2 Hopf
    points and 17 branch points (Turing points, two of them 0.0056 apart; the determinant at the
    steps' ends alone finds 9) at the closed forms of
    its decoupled modes within 1e-10, and at most 1.5 dense spectra per accepted point (the
    modes' real eigenvalues cross each other hundreds of times; splitting at each crossing
    cost 2.9 spectra per point at N = 100, the older rule 8.7)."""
    from diskfriction.continuation import Options, solve_branch
    from diskfriction.continuation.linalg.solves import measured

    chain = load_example("brusselator_chain")
    spec = chain.brusselator_chain(20)
    with measured() as spent:
        result = solve_branch(spec.problem, spec.u0(chain.SPAN[0]), chain.SPAN, Options(workers=0))
    assert result.success and not result.folds
    for got, exact in (([c.p for c in result.collisions], chain.collision_points(20)),
                       ([h.p for h in result.hopf], chain.hopf_points(20)),
                       ([b.p for b in result.branch_points], chain.turing_points(20))):
        assert np.sort(got) == pytest.approx(exact, abs=1e-10)
    assert spent.spectra <= 1.5 * len(result.p), (spent.spectra, len(result.p))


def test_bratu_discrete_folds_converge_at_second_order_to_the_continuous_one():
    """lambda_n on n = 9, 19, 39 interior points (h = 1/10, 1/20, 1/40) against
    lambda* = 3.513830719125162: errors shrinking as h^2 (observed order within 0.05 of 2).
    These meshes suffice: the order is already 2.003 and 2.0008 there (2.0005, 2.0001 on
    n = 24, 49, 99), and n = 99 alone took 1.6 s."""
    folds = [load_example("bratu").bratu(n).solve().folds for n in (9, 19, 39)]
    assert all(len(f) == 1 for f in folds)
    errors = np.array([3.513830719125162 - f[0].p for f in folds])
    orders = np.log2(errors[:-1] / errors[1:])
    assert (errors > 0).all() and np.abs(orders - 2).max() <= 0.05


# ---- the disk chain -------------------------------------------------------------------------

def test_disk_chain_through_the_public_api_is_bifurcate_in_fewer_than_30_lines():
    """The example's branch and its 22 collisions are bit-identical to the sweep that
    `diskfriction bifurcate` runs on the paper's scene."""
    from diskfriction.models.chain.sweep import sweep

    assert len((EXAMPLES / "disk_chain.py").read_text().splitlines()) < 30
    spec = load_example("disk_chain").problem
    result = spec.solve()
    reference = sweep(spec.problem.system, 0.0, 0.12)
    assert result.success and result.collisions
    assert unaccounted_pair_changes(result.p, result.branch.n_complex, [(c.p, c.kind) for c in result.collisions]) == []
    assert np.array_equal(result.p, reference.F_x)
    assert [(c.p, c.kind) for c in result.collisions] == [(c.p, c.kind) for c in reference.collisions]
