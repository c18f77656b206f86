"""Fast collision detection (issue 8) against the exhaustive one, the Newton locator's
convergence, free disks at eps = 0, and sparse against dense linear algebra."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation import ContinuationParams, DetectionParams, FunctionProblem, continuation
from diskfriction.continuation.branch import Stop, StopCode
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.continuation.linalg.solves import measured
from diskfriction.continuation.detection.locate import locate_double_eigenvalue
from diskfriction.continuation.stepping.newton import bordered_newton, tangent
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.continuation.spectra.tracking import eigenvalue_slopes
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.scenes import Scene
from diskfriction.symbolic import System

AGREE = 1e-9  # the tolerance between the two detections


def locations(branch):
    return [(c.kind, c.p) for c in branch.collisions]


def assert_same_collisions(fast, exhaustive):
    assert [k for k, _ in fast] == [k for k, _ in exhaustive]
    assert np.max(np.abs(np.array([p for _, p in fast]) - [p for _, p in exhaustive])) <= AGREE



@pytest.mark.parametrize("scene, matrix, count", [(Scene(), "J", 22), (Scene(), "M^-1 J", 17),
                                                  (Scene(N=20, eps=1e-4), "J", 50)],
                         ids=["paper-J", "paper-M^-1J", "N20-eps1e-4"])
@pytest.mark.slow
def test_fast_detection_finds_the_exhaustive_collisions(scene, matrix, count, chain_sweep):
    """Same kinds in the same order, locations within 1e-9, on one branch (the detection does
    not change the steps); the counts are the version 0.1 lists (docs/continuation.md)."""
    runs = {mode: chain_sweep(scene, matrix, params=SweepParams(detection=DetectionParams(mode=mode)))[0]
            for mode in ("fast", "exhaustive")}  # conftest: run once, shared with the tests below
    assert np.array_equal(runs["fast"].F_x, runs["exhaustive"].F_x)
    assert len(runs["fast"].collisions) == count
    assert_same_collisions(locations(runs["fast"]), locations(runs["exhaustive"]))
    assert all(c.resolved for c in runs["fast"].collisions)


def cluster_problem(v=10.0, c=1e-3):
    """A fast eigenvalue v p sweeps past 1 (exact crossing), 2 (bubble: skew coupling) and 3
    (avoided crossing): A(p) = diag(v p, 1, 2, 3) + couplings; G = A(p) u, u = 0."""
    def A(p):
        M = np.diag([v * p, 1.0, 2.0, 3.0])
        M[0, 2], M[2, 0] = c, -c
        M[0, 3] = M[3, 0] = c
        return M

    dA = np.diag([v, 0.0, 0.0, 0.0])
    return FunctionProblem(lambda u, p: A(p) @ u, lambda u, p: A(p), lambda u, p: dA @ u)


@pytest.mark.parametrize("ds", [0.1, 0.13])
def test_fast_and_exhaustive_agree_on_a_core_problem_with_a_bubble(ds):
    """The bubble of a fast eigenvalue passing a cluster, with steps 250x its width."""
    problem = cluster_problem()
    par = ContinuationParams(ds=ds, ds_min=1e-9, ds_max=ds, newton_tol=1e-12, p_min=0.0, p_max=0.4)
    runs = [continuation(problem, np.zeros(4), 0.0, par, DetectionParams(mode=mode))
            for mode in ("fast", "exhaustive")]
    assert len(runs[0].collisions) == 2
    assert_same_collisions(locations(runs[0]), locations(runs[1]))


def test_fast_detection_spends_about_one_spectrum_per_point(chain_sweep):
    """The fast detection's point: full eigendecompositions per accepted point on the paper
    scene, against the exhaustive one's (measured: 2.1 and 14)."""

    spent = {}
    for mode in ("fast", "exhaustive"):  # the sweeps of test_fast_detection_finds_...[paper-J]
        detection = SweepParams(detection=DetectionParams(mode=mode))
        branch, spectra = chain_sweep(Scene(), "J", params=detection)
        spent[mode] = spectra / len(branch)
    assert spent["fast"] <= 3.0 and spent["exhaustive"] >= 4 * spent["fast"]


def test_locator_converges_quadratically_to_a_closed_form_collision():
    """u in R^2 on the curved branch u = (p^2, sin p); A = [[a, 1], [c, a]] with
    c = (u_2 - sin p0) + (u_1 - p^2): on the branch c = sin p - sin p0, a double eigenvalue a
    with a Jordan block at p0 exactly. Newton from 3e-3 away (eigenvalue guess 0.01 off, as
    the cubic model of the pair's mean gives): each correction |dp| is at most 20 times the
    square of the one before, and it lands within 1e-12 of p0."""
    a, p0 = -0.7, 0.4

    def A(u, p):
        return np.array([[a, 1.0], [(u[1] - np.sin(p0)) + (u[0] - p * p), a]])

    problem = FunctionProblem(G=lambda u, p: u - np.array([p * p, np.sin(p)]),
                              G_u=lambda u, p: np.eye(2),
                              G_p=lambda u, p: -np.array([2 * p, np.cos(p)]), A=A)
    p = p0 + 3e-3
    x0 = np.array([p * p, np.sin(p), p])
    t0 = np.array([2 * p, np.cos(p), 1.0])
    found = locate_double_eigenvalue(problem, x0, a + 0.01, np.array([1.0, 0.0]),
                                     np.array([0.0, 1.0]), t0, tol_p=1e-10, newton_tol=1e-12)
    assert abs(found.x[-1] - p0) <= 1e-12 and abs(found.lam - a) <= 1e-9
    assert len(found.history) >= 3
    for d0, d1 in zip(found.history, found.history[1:]):
        assert d1 <= 20.0 * d0 * d0  # quadratic: e_(k+1) <= C e_k^2
    assert found.overlap <= 1e-8  # a Jordan block: left and right eigenvectors orthogonal


@pytest.mark.parametrize("sparse", [True, False])
@pytest.mark.parametrize("offset", [0.0, 1e-9, 1e-7])
def test_jordan_chain_near_a_double_eigenvalue_dense_or_sparse(sparse, offset, monkeypatch):
    """jordan_chain_near at a Jordan block [[a, 1], [0, a]] inside a 400 x 400 block-diagonal
    matrix: v = e_0, w = e_1 and overlap 0 to rounding at lambda = a, and within about the
    offset (as least squares on the dense matrix gives them) with lambda off by 1e-9 or 1e-7
    (an interpolated collision). No dense matrix for a sparse one: eps = 0 at N = 3000 spent
    minutes in a dense SVD for such collisions."""
    import scipy.sparse as sps

    from diskfriction.continuation.detection.locate import jordan_chain_near

    a, n = -0.7, 400
    rng = np.random.default_rng(3)
    A = sps.diags_array(np.concatenate([[a, a], 1.0 + rng.random(n - 2)])).tolil()
    A[0, 1] = 1.0
    for i in range(2, n - 1, 2):  # 2 x 2 blocks with real eigenvalues away from a
        A[i, i + 1] = 0.3
    A = sps.csr_array(A) if sparse else A.toarray()
    if sparse:
        def no_dense(self, *args, **kwargs):
            raise AssertionError("a sparse matrix made dense")

        monkeypatch.setattr(sps.csr_array, "toarray", no_dense)
        monkeypatch.setattr(sps.csc_array, "toarray", no_dense)
    v, w, overlap = jordan_chain_near(A, a + offset)
    tol = 1.5 * offset + 1e-12
    e0, e1 = np.eye(n)[0], np.eye(n)[1]
    assert np.allclose(v, e0, atol=tol) and overlap <= 2 * tol
    assert np.allclose(w / np.linalg.norm(w), e1, atol=tol)


def test_jordan_chain_refined_on_the_locators_last_factorization(monkeypatch):
    """jordan_chain with near = the LU of B at lambda 1e-9 away (the locator's last iterate):
    the same v, w and overlap as with a factorization of its own, to 1e-12, without one."""
    import scipy.sparse as sps

    from diskfriction.continuation.linalg import solves as linalg
    from diskfriction.continuation.detection.locate import _identity, jordan_chain

    a, n = -0.7, 400
    rng = np.random.default_rng(3)
    A = sps.diags_array(np.concatenate([[a, a], 1.0 + rng.random(n - 2)])).tolil()
    A[0, 1] = 1.0
    A = sps.csr_array(A)
    b, c = 1e-6 * np.eye(n)[1], 1e-6 * np.eye(n)[0]
    own = jordan_chain(A, a, b, c)
    near = linalg.factorize(linalg.bordered(A - (a + 1e-9) * _identity(A), b, c))
    factorized, original = [], linalg.factorize
    monkeypatch.setattr(linalg, "factorize", lambda *args: factorized.append(1) or original(*args))
    refined = jordan_chain(A, a, b, c, near=near)
    assert factorized == []
    assert np.allclose(refined[0], own[0], rtol=0, atol=1e-12)
    assert np.allclose(refined[1], own[1], rtol=0, atol=1e-12)
    assert abs(refined[2] - own[2]) <= 1e-12


def test_eps_zero_runs_to_the_end_with_free_rolling_modes_excluded(chain_sweep):
    """N = 20 at eps = 0: disks beyond the load front touch their neighbours at overlaps of
    rounding size and are held by the substrate alone. Their rolling modes are counted at
    every point, their modes are excluded from detection (3 per disk), the rolling one is
    below the stiffness a rounding-size overlap can give, their number falls as the load
    spreads, and the branch reaches F_x = 0.12."""
    system = System.from_scene(Scene(N=20))
    branch = chain_sweep(Scene(N=20), "J")[0]
    assert branch.status == Stop(StopCode.REACHED) and branch.F_x[-1] == 0.12
    assert branch.free[0] > 0 and branch.free[-1] < branch.free[0]
    problem = DiskEquilibria(system, branch.q[0], branch.xi[0], branch.F_x[0], "J")
    assert problem.free_count == branch.free[0]
    modes = DenseSpectra().eigensystem(problem, branch.q[0], branch.F_x[0])
    assert modes.excluded.sum() == 3 * branch.free[0]
    s = system.scene
    rolling = np.sort(np.abs(modes.values[modes.excluded]))[:branch.free[0]]
    assert np.all(rolling <= s.k_t * np.sqrt(problem.delta_join) * (1 + s.R**2))
    assert branch.residual.max() <= 1e-10 and len(branch.collisions) > 0


@pytest.mark.slow
def test_eps_zero_long_sparse_chain_finds_the_collisions_of_the_short_one(chain_sweep):
    """At eps = 0 the load reaches about 29 disks by F_x = 0.12, so N = 100 (sparse J, 70 and
    more disks free throughout) and N = 20 (dense J) find the same collisions, kind by kind,
    within 1e-9 in F_x; N = 100 runs to 0.12 with its free modes counted and falling."""
    branches = {N: chain_sweep(Scene(N=N), "J")[0] for N in (20, 100)}
    long, short = branches[100], branches[20]
    assert long.status == Stop(StopCode.REACHED) and long.F_x[-1] == 0.12
    assert long.free[-1] > 0 and long.free[-1] < long.free[0]
    assert [c.kind for c in long.collisions] == [c.kind for c in short.collisions]
    assert max(abs(a.p - b.p) for a, b in zip(long.collisions, short.collisions)) <= 1e-9


@pytest.mark.parametrize("sparse", [False, True])
def test_free_disks_spectrum_is_the_matrix_spectrum_with_vectors_on_the_coupled_chain_alone(sparse):
    """N = 30 at eps = 0 just after rest, most disks free: the eigenvalues are those of the
    whole matrix (LAPACK on the dense J), only the coupled chain's carry vectors (n x n_c, no
    n x n array), those are left and right eigenvectors with l^H r = 1, and the slopes are
    l^H dA r for them and 0 for the free disks' modes."""
    system = System.from_scene(Scene(N=30))
    q, xi = relax(system, *system.rest_state(), 1e-5)  # where sweeps start (sweep.START_FRACTION)
    problem = DiskEquilibria(system, q, xi, 1e-5, "J", sparse=sparse)
    A = problem.stability_matrix(q, 1e-5)
    A = A.toarray() if hasattr(A, "toarray") else A
    n, free = A.shape[0], 3 * len(problem.free)
    assert free >= n // 2
    modes = DenseSpectra().eigensystem(problem, q, 1e-5, vectors=True)
    whole = np.linalg.eigvals(A)
    assert np.max(np.abs(np.sort_complex(modes.values) - np.sort_complex(whole))) <= 1e-9 * np.abs(whole).max()
    assert modes.right.shape == (n, n - free) and modes.left.shape == (n - free, n)
    assert np.array_equal(modes.columns < 0, modes.excluded) and modes.excluded.sum() == free
    for i in np.flatnonzero(~modes.excluded):
        r, l = modes.vectors(i)
        scale = np.abs(modes.values[i]) + 1.0
        assert np.linalg.norm(A @ r - modes.values[i] * r) <= 1e-9 * scale * np.linalg.norm(r)
        assert np.linalg.norm(l.conj() @ A - modes.values[i] * l.conj()) <= 1e-9 * scale * np.linalg.norm(l)
        assert abs(l.conj() @ r - 1.0) <= 1e-9
    dA = np.diag(np.arange(n, dtype=float))
    slopes = eigenvalue_slopes(modes, dA)
    assert np.all(slopes[modes.excluded] == 0.0)
    i = int(np.flatnonzero(~modes.excluded)[0])
    r, l = modes.vectors(i)
    assert abs(slopes[i] - l.conj() @ dA @ r) <= 1e-12 * np.abs(l).max() * np.abs(r).max() * n * n


def test_sparse_and_dense_solves_agree_at_N40():
    """The same problem assembled dense (LAPACK) and sparse (SuperLU): residual, a Newton
    correction, the tangent and the spectrum agree."""
    system = System.from_scene(Scene(N=40, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), 0.01)
    dense, sparse = (DiskEquilibria(system, q, xi, 0.01, "J", sparse=s) for s in (False, True))
    x = np.append(q + 1e-7 * np.sin(np.arange(q.size)), 0.0101)
    e_p = np.zeros(x.size)
    e_p[-1] = 1.0
    steps = [bordered_newton(pr, x, e_p, 1e-11, 8) for pr in (dense, sparse)]
    assert all(s.converged for s in steps)
    assert np.max(np.abs(steps[0].x - steps[1].x)) <= 1e-12
    t = [tangent(pr, steps[0].x, e_p) for pr in (dense, sparse)]
    assert np.max(np.abs(t[0] - t[1])) <= 1e-10
    ev = [np.sort_complex(DenseSpectra().eigensystem(pr, steps[0].x[:-1], 0.0101).values) for pr in (dense, sparse)]
    assert np.max(np.abs(ev[0] - ev[1])) <= 1e-9 * np.abs(ev[0]).max()


def test_compiled_substitution_solves_like_superlu():
    """A factorization solved with repeatedly switches from SuperLU's solve to substitution over
    its copied factors (triangular.py): on the bordered A - sigma I of the N = 40 chain (near an
    eigenvalue, so ill-conditioned) both give the same x and A^-T x to rounding, for vectors
    and for the columns of a matrix."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from diskfriction.continuation.linalg.solves import COPY_FACTORS_AT, bordered, factorize

    system = System.from_scene(Scene(N=40, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), 0.01)
    A = DiskEquilibria(system, q, xi, 0.01, "J", sparse=True).stability_matrix(q, 0.01)
    n = A.shape[0]
    sigma = np.sort(np.linalg.eigvals(A.toarray()).real)[n // 2] * (1 + 1e-6)
    rng = np.random.default_rng(3)
    M = bordered(A - sigma * sp.identity(n, format="csr"), rng.standard_normal(n), rng.standard_normal(n))
    reference = spla.splu(sp.csc_array(M))
    lu = factorize(M)
    rhs = rng.standard_normal((n + 1, 3))
    for k in range(COPY_FACTORS_AT + 2):
        transpose = k % 2 == 1
        x = lu.solve(rhs[:, k % 3], transpose)
        expected = reference.solve(rhs[:, k % 3], trans="T" if transpose else "N")
        assert np.max(np.abs(x - expected)) <= 1e-10 * np.max(np.abs(expected))
    assert lu.triangular is not None
    X = lu.solve(rhs)
    assert np.max(np.abs(M @ X - rhs)) <= 1e-9 * np.max(np.abs(X))
    assert np.max(np.abs(M.T @ lu.solve(rhs, transpose=True) - rhs)) <= 1e-9 * np.max(np.abs(X))


@pytest.mark.parametrize("symmetric", [False, True], ids=["partial-pivoting", "symmetric-mode"])
def test_a_repeated_pattern_reuses_its_ordering_and_solves_alike(symmetric):
    """A second matrix of the same pattern (the bordered A - sigma I of the N = 40 chain at
    another sigma, near an eigenvalue) is factorized in the column order of the first
    (orderings.py) and solves like SuperLU's own factorization of it, with SuperLU's solve and
    after the factors are copied (triangular.py), with and without transpose: bit for bit with
    partial pivoting, to rounding with SymmetricMode; the log-determinant from its factors
    (sign and value) is that of the matrix; another pattern is ordered afresh, and solves bit
    for bit as it does once its pattern is known (with SymmetricMode its first factors are
    those of the reordered matrix: a result must not depend on what the process factorized
    before)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla
    from diskfriction.continuation.linalg import orderings
    from diskfriction.continuation.linalg.solves import COPY_FACTORS_AT, bordered, factorize
    from diskfriction.continuation.spectra.nearest import SHIFT_INVERT_ORDERING

    options = SHIFT_INVERT_ORDERING if symmetric else None
    system = System.from_scene(Scene(N=40, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), 0.01)
    A = DiskEquilibria(system, q, xi, 0.01, "J", sparse=True).stability_matrix(q, 0.01)
    n = A.shape[0]
    eigenvalues = np.sort(np.linalg.eigvals(A.toarray()).real)
    rng = np.random.default_rng(5)
    c, b = rng.standard_normal(n), rng.standard_normal(n)
    matrix = lambda sigma: sp.csc_array(bordered(A - sigma * sp.identity(n, format="csr"), c, b))  # noqa: E731
    first, second = matrix(eigenvalues[n // 3]), matrix(eigenvalues[n // 2] * (1 + 1e-6))
    factorize(first, options)
    lu = factorize(second, options)
    assert isinstance(lu.lu, orderings.Reordered)
    reference = spla.splu(second, **(options or {}))
    rhs = rng.standard_normal((n + 1, 2))
    for k in range(COPY_FACTORS_AT + 4):
        transpose = k % 2 == 1
        x = lu.solve(rhs[:, (k // 2) % 2], transpose)
        expected = reference.solve(rhs[:, (k // 2) % 2], trans="T" if transpose else "N")
        if symmetric:
            assert np.max(np.abs(x - expected)) <= 1e-10 * np.max(np.abs(expected))
        elif lu.triangular is None:
            assert np.array_equal(x, expected)
        residual = (second.T if transpose else second) @ x - rhs[:, (k // 2) % 2]
        assert np.max(np.abs(residual)) <= 1e-9 * np.max(np.abs(x))
    assert lu.triangular is not None
    diagonal = lu.lu.U.diagonal()
    sign = np.prod(np.sign(diagonal)) * linalg_parity(lu.lu.perm_r) * linalg_parity(lu.lu.perm_c)
    assert (sign, np.sum(np.log(np.abs(diagonal)))) == pytest.approx(np.linalg.slogdet(second.toarray()), rel=1e-9)
    coupled = sp.lil_array(A)
    coupled[0, n - 5] = 1e-3  # one more nonzero
    other = sp.csc_array(bordered(sp.csr_array(coupled) - 0.5 * sp.identity(n, format="csr"), c, b))
    fresh = factorize(other, options)
    assert isinstance(fresh.lu, orderings.Reordered) == symmetric
    again = factorize(other, options)
    assert isinstance(again.lu, orderings.Reordered)
    assert np.array_equal(fresh.solve(rhs[:, 0]), again.solve(rhs[:, 0]))


def linalg_parity(permutation):
    from diskfriction.continuation.linalg.solves import _parity

    return _parity(permutation)


@pytest.mark.parametrize("partial_from", [None, 0], ids=["default", "partial-splits"])
@pytest.mark.slow
def test_a_spectral_window_lists_the_full_detection_s_collisions_in_it(partial_from, chain_sweep):
    """N = 40, eps = 1e-4: tracking only 0.0553 <= Re lambda / k_n <= 0.0562 by shift-invert
    gives the collisions of the full detection whose eigenvalue lies in the window, within
    1e-9, and counts the complex pairs there; also with every split sample partial where it
    can be (partial_from = 0: at N = 40 the default, n >= 240, takes none), which then takes
    partial samples."""

    system = System.from_scene(Scene(N=40, eps=1e-4))
    lo, hi = 0.0553 * system.scene.k_n, 0.0562 * system.scene.k_n
    full = chain_sweep(Scene(N=40, eps=1e-4), "J")[0]  # the same for both cases
    detection = DetectionParams() if partial_from is None else DetectionParams(partial_from=partial_from)
    with measured() as work:
        window = sweep(system, 0.0, 0.12, "J", SweepParams(window=(lo, hi), detection=detection))
    expected = [(c.kind, c.p) for c in full.collisions if lo <= c.eigenvalue <= hi]
    assert len(expected) >= 2 and window.window == (lo, hi)
    assert window.eigenvalues.shape[1] < system.ndof
    assert_same_collisions(locations(window), expected)
    assert (work.spectra_partial > 0) == (partial_from == 0)


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


@pytest.mark.parametrize("scene, matrix, k_max", [(Scene(), "J", 16), (Scene(), "M^-1 J", 16),
                                                  (Scene(), "J", 8), (Scene(N=20, eps=1e-4), "J", 16)],
                         ids=["paper-J", "paper-M^-1J", "paper-J-k8", "N20-eps1e-4"])
@pytest.mark.slow
def test_partial_split_samples_find_the_collisions_of_full_ones(scene, matrix, k_max):
    """Split samples as partial spectra (forced at every size: partial_from = 0) give the same
    collisions as full ones, to 1e-9, on the same branch, with fewer full spectra; k_max = 8
    sends more splits to the fallbacks (a full sample, upgrading the partial ones)."""

    system = System.from_scene(scene)
    runs, spent = {}, {}
    for partial_from in (0, 10**9):
        detection = DetectionParams(partial_from=partial_from, partial_max_k=k_max)
        with measured() as work:
            runs[partial_from] = sweep(system, 0.0, 0.12, matrix, SweepParams(detection=detection))
        spent[partial_from] = (work.spectra, work.spectra_partial)
    assert np.array_equal(runs[0].F_x, runs[10**9].F_x)
    assert_same_collisions(locations(runs[0]), locations(runs[10**9]))
    assert all(c.resolved for c in runs[0].collisions)
    assert spent[10**9][1] == 0 < spent[0][1] and spent[0][0] < spent[10**9][0]


def test_arpacks_tolerance_leaves_the_projected_eigenvalues_exact():
    """ARPACK stops at ARPACK_TOL, not at the machine precision; the two-sided Rayleigh-Ritz
    projection that follows still gives the 30 eigenvalues nearest sigma to 1e-13 of the
    largest (a dense decomposition's), and both vectors' residuals within 1e-10 of it."""
    import scipy.sparse as sp

    from diskfriction.continuation.spectra.nearest import ARPACK_TOL, nearest_eigensystem

    assert ARPACK_TOL > 0.0
    rng = np.random.default_rng(7)
    n, sigma, k = 240, 20.3, 30
    A = sp.csr_array(sp.random(n, n, density=0.05, random_state=rng) * 4.0 + sp.diags(np.arange(n, dtype=float)))
    exact = np.linalg.eigvals(A.toarray())
    scale = np.abs(exact).max()
    system, _ = nearest_eigensystem(A, sigma, k)
    nearest = exact[np.argsort(np.abs(exact - sigma))[:k]]
    assert np.abs(nearest[:, None] - system.values[None, :]).min(axis=1).max() <= 1e-13 * scale
    R, L = system.right, system.left
    assert np.abs(A @ R - R * system.values).max() <= 1e-10 * scale * np.abs(R).max()
    assert np.abs(L @ A - system.values[:, None] * L).max() <= 1e-10 * scale * np.abs(L).max()


@pytest.mark.parametrize("sparse, k", [(True, 7), (False, 7), (True, 90)])
def test_nearest_eigensystem_gives_the_k_nearest_with_normalised_vectors(sparse, k):
    """Shift-invert against a dense eigendecomposition: the k eigenvalues nearest sigma (real
    and complex ones), the radius they cover, residuals of both vectors, l^H r = 1. For k = 7
    the edge of the disc splits a conjugate pair (either member may be returned), for k = 90
    the Krylov space is cut to k + KRYLOV_EXTRA (krylov_size)."""
    import scipy.sparse as sp

    from diskfriction.continuation.spectra.nearest import KRYLOV_EXTRA, krylov_size, nearest_eigensystem

    rng = np.random.default_rng(7)
    n, sigma = 240, 20.3
    assert (krylov_size(k, n) < 2 * k + 1) == (k > KRYLOV_EXTRA + 1)
    A = sp.random(n, n, density=0.05, random_state=rng) * 4.0 + sp.diags(np.arange(n, dtype=float))
    A = sp.csr_array(A)
    exact = np.linalg.eigvals(A.toarray())
    nearest = exact[np.argsort(np.abs(exact - sigma))[:k]]
    system, radius = nearest_eigensystem(A if sparse else A.toarray(), sigma, k)
    assert np.any(np.abs(exact.imag) > 1e-3)  # the matrix has complex pairs too
    split = np.count_nonzero(nearest.imag > 1e-9) != np.count_nonzero(nearest.imag < -1e-9)
    assert split == (k == 7)
    found = np.minimum(np.abs(nearest[:, None] - system.values[None, :]),
                       np.abs(nearest.conj()[:, None] - system.values[None, :]))
    assert np.max(np.min(found, axis=1)) <= 1e-9 * n
    assert radius == pytest.approx(np.max(np.abs(nearest - sigma)), rel=1e-9)
    R, L = system.right, system.left
    assert np.max(np.abs(A @ R - R * system.values)) <= 1e-8 * n * np.max(np.abs(R))
    assert np.max(np.abs(L @ A - system.values[:, None] * L)) <= 1e-8 * n * np.max(np.abs(L))
    assert np.allclose(np.einsum("ij,ji->i", L, R), 1.0, atol=1e-10)


def test_the_two_sided_projection_solves_the_pencil_or_hands_it_to_qz():
    """nearest._two_sided on subspaces of a dense matrix with known eigenvectors: right and
    left subspaces of the same 8 eigenvalues (perturbed within the subspace) give them to
    1e-13 with residuals at rounding and l^H r = 1, as the QZ algorithm on the pencil does;
    a left vector that is mostly another eigenvalue's (orthogonal to V) makes W^H V ill
    conditioned, and the pencil then goes to QZ (the values of scipy's eig of the pencil)."""
    import scipy.linalg as sla

    from diskfriction.continuation.spectra.nearest import B_RCOND, _two_sided

    rng = np.random.default_rng(11)
    n, k = 60, 8
    A = rng.standard_normal((n, n))
    values, vl, vr = sla.eig(A, left=True, right=True)
    near = np.argsort(np.abs(values - 0.3))
    V = vr[:, near[:k]] @ (np.eye(k) + 0.05 * rng.standard_normal((k, k)))
    W = vl[:, near[:k]] @ (np.eye(k) + 0.05 * rng.standard_normal((k, k)))
    system = _two_sided(A, V, W)
    qz = sla.eigvals(W.conj().T @ A @ V, W.conj().T @ V)
    def apart(got, expected):  # each expected value's distance to the nearest one got, and back
        d = np.abs(got[:, None] - expected[None, :])
        return max(d.min(axis=0).max(), d.min(axis=1).max())

    for expected in (values[near[:k]], qz):
        assert apart(system.values, expected) <= 1e-13 * n
    assert np.max(np.abs(A @ system.right - system.right * system.values)) <= 1e-12 * n
    assert np.max(np.abs(system.left @ A - system.values[:, None] * system.left)) <= 1e-12 * n
    assert np.allclose(np.einsum("ij,ji->i", system.left, system.right), 1.0, atol=1e-12)
    W[:, 0] = 1e-7 * W[:, 0] + vl[:, near[k + 5]]  # l_(k+5) is orthogonal to every right vector of V
    B = W.conj().T @ V
    assert 1.0 / np.linalg.cond(B, 1) < B_RCOND
    system = _two_sided(A, V, W)
    qz = sla.eig(W.conj().T @ (A @ V), B, left=True, right=True)[0]
    assert np.array_equal(system.values, qz.astype(complex))
    assert apart(system.values, values[near[:k]]) <= 1e-7


def test_a_partial_sample_matches_the_full_one_on_its_labels_or_declines():
    """partial_sample_at on a problem with a known spectrum: the labels asked for carry the
    full sample's eigenvalues, slopes and status, the others nan; gaps never exceed the true
    ones; a disc that cannot cover the labels (k too small) gives None."""
    from diskfriction.continuation.detection.samples import partial_sample_at, sample_at

    n = 12
    base = np.diag(np.arange(1.0, n + 1.0))
    skew = np.zeros((n, n))
    skew[4, 5], skew[5, 4] = 0.3, -0.3  # the pair 5, 6 moves towards a collision at p = 0.5/0.6
    problem = FunctionProblem(lambda u, p: (base + p * skew) @ u, lambda u, p: base + p * skew,
                              lambda u, p: skew @ u)
    t = np.zeros(n + 1)
    t[-1] = 1.0
    x0, x1 = np.append(np.zeros(n), 0.5), np.append(np.zeros(n), 0.6)
    left = sample_at(problem, 0.0, x0, 1e-9, None, t)
    full = sample_at(problem, 1.0, x1, 1e-9, left, t)
    labels = np.flatnonzero(np.abs(left.eigvals - 5.5) < 1.0)
    assert labels.size == 2
    part = partial_sample_at(problem, 1.0, x1, left, [(labels, 5.5, 6)], t)
    assert part is not None and part.known.sum() == 2
    assert np.allclose(part.eigvals[labels], full.eigvals[labels], atol=1e-10)
    assert np.allclose(part.dlam[labels], full.dlam[labels], atol=1e-6)
    assert np.array_equal(part.status, full.status)
    assert np.all(np.isnan(part.eigvals[part.known == 0]))
    assert np.all(part.gaps[labels] <= full.gaps[labels] + 1e-12)
    assert partial_sample_at(problem, 1.0, x1, left, [(labels, 5.5, 2)], t) is None


@pytest.mark.slow
def test_settled_samples_drop_their_vectors_and_the_scan_finds_the_same(monkeypatch):
    """A scan drops the eigenvectors of inner samples whose two intervals are settled (clean,
    narrow or with every event located; full neighbours): at the end of every scan of the
    N = 20 sweep no inner sample between two full ones holds vectors (an interval with a
    located collision kept them to the scan's end until stop 40), and without the release
    (monkeypatched away) the branch and its collisions are exactly the same."""
    from diskfriction.continuation.detection.collisions import StepScan

    system = System.from_scene(Scene(N=20, eps=1e-4))
    released, inner, held = [], [], []
    run = StepScan.run

    def counting_run(self):
        found = run(self)
        S = self.samples
        inner.append(len(S) - 2)
        released.append(sum(s.system is None and s.tangent is not None for s in S[1:-1]))
        held.extend(k for k in range(1, len(S) - 1) if S[k].system is not None
                    and not (S[k - 1].partial or S[k].partial or S[k + 1].partial))
        return found

    monkeypatch.setattr(StepScan, "run", counting_run)
    lean = sweep(system, 0.0, 0.12, "J", SweepParams(workers=0))
    assert 0 < sum(released) <= sum(inner)
    assert held == []
    assert len(lean.collisions) > 0
    monkeypatch.setattr(StepScan, "release_vectors", lambda self: None)
    released.clear()
    kept = sweep(system, 0.0, 0.12, "J", SweepParams(workers=0))
    assert sum(released) == 0
    assert np.array_equal(lean.F_x, kept.F_x) and np.array_equal(lean.eigenvalues, kept.eigenvalues)
    assert [(c.p, c.kind, c.pair) for c in lean.collisions] == [(c.p, c.kind, c.pair) for c in kept.collisions]


@pytest.mark.slow
def test_samples_spilled_to_disk_leave_the_scan_unchanged(monkeypatch):
    """With no memory for inner samples' vectors (SCAN_MEMORY = 0) a scan keeps in memory only
    the ends of the interval it works on and maps the others from disk (Sample.spilled): the
    N = 20 sweep (partial samples forced) spills samples, and its branch and collisions are
    exactly those of the sweep that keeps them all in memory, and so are they where the disk
    refuses (OSError: the samples stay in memory). on_disk keeps values and memory order,
    read-only."""
    from diskfriction.continuation.detection import collisions
    from diskfriction.continuation.detection.samples import Sample
    from diskfriction.continuation.detection.spill import is_on_disk, on_disk

    a = np.asfortranarray(np.arange(12.0).reshape(3, 4) * (1 + 2j))
    for x in (a, np.ascontiguousarray(a)):
        y = on_disk(x)
        assert np.array_equal(x, y) and y.flags.f_contiguous == x.flags.f_contiguous
        assert is_on_disk(y) and is_on_disk(y[:, 1]) and not is_on_disk(x) and not y.flags.writeable

    system = System.from_scene(Scene(N=20, eps=1e-4))
    params = SweepParams(detection=DetectionParams(partial_from=0), workers=0)  # partial samples too
    kept = sweep(system, 0.0, 0.12, "J", params)
    spilled = []
    spill = Sample.spilled

    def counting(self):
        spilled.append(self.s)
        return spill(self)

    monkeypatch.setattr(collisions, "SCAN_MEMORY", 0)
    monkeypatch.setattr(Sample, "spilled", counting)
    lean = sweep(system, 0.0, 0.12, "J", params)
    assert len(spilled) > 10
    assert np.array_equal(lean.F_x, kept.F_x) and np.array_equal(lean.eigenvalues, kept.eigenvalues)
    assert [(c.p, c.kind, c.pair) for c in lean.collisions] == [(c.p, c.kind, c.pair) for c in kept.collisions]

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("tempfile.TemporaryFile", full_disk)  # the samples stay in memory
    refused = sweep(system, 0.0, 0.12, "J", params)
    assert np.array_equal(refused.eigenvalues, kept.eigenvalues) and len(refused.collisions) == len(kept.collisions)


@pytest.mark.slow
def test_a_failing_locator_costs_partial_samples_and_finds_the_same_collisions(monkeypatch):
    """Where the locator fails, the event's interval is split by a partial sample of the event
    pairs' labels (with partial samples forced, partial_from = 0): with every locator call
    failing, the N = 10 sweep brackets each collision to tol_p and reports the same collisions
    within 1e-9, with at most 3 full spectra per collision beyond the sweep whose locator
    works. (With full splits, as until stop 40, it took 1225 full spectra against 95 at N = 20,
    and 572 against 116 here, about 22 more for each of its 21 collisions; a partial sample of the first event pair's labels alone missed
    a death: the labels split for must be all the events' with their partners. Until stop 55
    the bound was 1.5 times the working sweep's spectra, 135 against 91; a split's labels then
    became the union of every refusing test's (verdicts.hermite_split), which took the working
    sweep to 84 and the failing one to 138, 2.6 more per collision for 21.)"""
    from diskfriction.continuation.detection.detectors import fast
    from diskfriction.continuation.detection.locate import LocatorFailed

    system = System.from_scene(Scene(N=10, eps=1e-4))
    params = SweepParams(detection=DetectionParams(partial_from=0), workers=0)
    with measured() as working:
        located = sweep(system, 0.0, 0.12, "J", params)

    def failing(*args, **kwargs):
        raise LocatorFailed("forced")

    monkeypatch.setattr(fast, "locate_double_eigenvalue", failing)
    with measured() as failed:
        bracketed = sweep(system, 0.0, 0.12, "J", params)
    assert len(located.collisions) > 10
    assert [c.kind for c in bracketed.collisions] == [c.kind for c in located.collisions]
    assert np.max(np.abs([a.p - b.p for a, b in zip(bracketed.collisions, located.collisions)])) <= 1e-9
    assert failed.spectra_partial > working.spectra_partial
    assert failed.spectra - working.spectra <= 3 * len(located.collisions)


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
def test_a_chain_window_that_crowds_is_widened_and_finds_the_same_collisions(monkeypatch):
    """N = 20, eps = 1e-4, window [0, 0.02] k_n sized with one eigenvalue to spare: it crowds
    along the sweep, is sized anew, wider, at the last certified point and the sweep goes on
    (before: an exception that lost the sweep). The same 20 collisions as a generous window, of
    the same kinds, within 1e-9: the steps after the restart differ, and the history makes the
    branch depend on its steps by up to 5.9e-10 (docs/continuation.md)."""
    from diskfriction.continuation.spectra import window as spectral_window
    from diskfriction.models.chain.sweep import SweepParams, sweep

    system = System.from_scene(Scene(N=20, eps=1e-4))
    window = SweepParams(window=(0.0, 40.0))
    generous = sweep(system, 0.0, 0.12, params=window)
    sized = spectral_window.sized

    def tightly_sized(w, problem, u, p):  # at the start; widened with the window's own margins
        return w if w.k else sized(w, problem.stability_structure(u, p).shifted(), 1.0, 1)

    monkeypatch.setattr(spectral_window.SpectralWindow, "prepared", tightly_sized)
    tight = sweep(system, 0.0, 0.12, params=window)
    assert generous.widenings == 0 and tight.widenings >= 1
    assert tight.status.reached and np.all(np.diff(tight.F_x) > 0)
    assert [c.kind for c in tight.collisions] == [c.kind for c in generous.collisions]
    assert len(generous.collisions) == 20
    assert np.abs(np.array([c.p for c in tight.collisions])
                  - [c.p for c in generous.collisions]).max() <= 1e-9


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
