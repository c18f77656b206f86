"""Eigenvalue condition numbers (issue 26 item 3): Branch.condition and collisions.json's
condition and condition_amplitude, against closed forms and direct decompositions."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from diskfriction.continuation import Options, problem_from_functions, solve_branch
from diskfriction.continuation.records import collision_records, pair_condition

P1 = 0.3


def jordan_family():
    """A(p) = [[-0.7, 1], [c, -0.7]], c = P1 - p: eigenvalues -0.7 +- sqrt(c), real before P1
    and complex after; each eigenvalue's kappa = (1 + |c|) / (2 sqrt|c|) on both sides (right
    vectors (1, +-sqrt c), left vectors (+-sqrt c, 1))."""
    return problem_from_functions(lambda u, p: u - p, dG_du=lambda u, p: np.eye(1),
                                  dG_dp=lambda u, p: -np.ones(1),
                                  A=lambda u, p: np.array([[-0.7, 1.0], [P1 - p, -0.7]]))


def test_condition_numbers_are_the_closed_form_on_both_sides_of_a_collision():
    result = solve_branch(jordan_family(), [0.0], (0.0, 1.0), Options(workers=0))
    c = np.abs(P1 - result.p)
    exact = (1.0 + c) / (2.0 * np.sqrt(c))
    kappa = result.branch.condition
    assert kappa.shape == (len(result.p), 2)
    assert np.abs(kappa / exact[:, None] - 1.0).max() <= 1e-12
    (birth,) = result.collisions
    around, amplitude = pair_condition(result.p, kappa, birth, result.collisions)
    k = int(np.flatnonzero(result.p < birth.p)[-1])
    assert around == pytest.approx(exact[k:k + 2], rel=1e-12)
    assert amplitude == pytest.approx((1.0 + c[k:k + 2]) / 2.0, rel=1e-10)  # -> 1/2 at P1


def test_the_chains_condition_numbers_match_a_direct_decomposition(chain_sweep):
    """The paper's scene: at every fifth accepted point each tracked eigenvalue's kappa equals
    |l| |r| / |l^H r| from scipy's eig of the stability matrix (matched by value) within
    1e-6; each collision's pair has a finite amplitude on both sides, of one order."""
    from diskfriction.scenes import Scene
    from diskfriction.symbolic import System

    system = System.from_scene(Scene())
    branch = chain_sweep(Scene())[0]  # conftest: the paper's sweep, shared
    for k in range(0, len(branch), 5):
        xi = branch.xi[k]
        A = system.stability_matrix(system.jacobian(branch.q[k], xi), str(branch.matrix))
        lam, vl, vr = sla.eig(A, left=True, right=True)
        kappa = np.linalg.norm(vl, axis=0) * np.linalg.norm(vr, axis=0) / np.abs(
            np.einsum("ij,ij->j", vl.conj(), vr))
        tracked, known = branch.eigenvalues[k], np.isfinite(branch.condition[k])
        nearest = np.argmin(np.abs(tracked[known][:, None] - lam[None, :]), axis=1)
        assert np.abs(branch.condition[k][known] / kappa[nearest] - 1.0).max() <= 1e-6
    records = collision_records(branch)
    assert len(records) == 22
    interval = lambda c: int(np.searchsorted(branch.F_x, c.p))  # noqa: E731  (the leg loads)
    for c, r in zip(branch.collisions, records):
        shared = any(o is not c and interval(o) == interval(c) and set(o.pair) & set(c.pair)
                     for o in branch.collisions)
        assert np.isfinite(r["condition"]).all()
        if shared:  # kappa at the interval's ends follows two collisions: no amplitude
            assert r["condition_amplitude"] is None, r
        else:
            before, after = r["condition_amplitude"]
            assert np.isfinite([before, after]).all() and 0.5 <= before / after <= 2.0, r
    assert sum(r["condition_amplitude"] is None for r in records) >= 2  # the y-mode cluster near 0.004
