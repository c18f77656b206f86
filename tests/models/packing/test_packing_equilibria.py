"""A sheared packing's equilibrium problem (models/packing/equilibria.py, assembly.py): the
tracked spectrum is the network's without its zero modes, the matrices are the products of the
gauge they replace, the bordered systems and the deflated shift-invert solve as the plain ones,
a restored state is the state set afresh, and loose disks are found and give way."""
from __future__ import annotations


import numpy as np
import pytest
import scipy.sparse as sp
from sheared_packing import SCENE, problem_at_start

from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.models.packing.assembly import Assembly
from diskfriction.models.packing.equilibria import Gauge
from diskfriction.models.packing.shear import ShearParams


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
