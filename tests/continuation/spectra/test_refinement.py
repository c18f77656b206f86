"""Eigenpair continuation (issue 26 item 1): the periodic block-tridiagonal kernel, the
refinement's certificate, and sweeps whose full spectra are refined finding the collisions of
sweeps whose spectra are all decomposed."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from diskfriction.continuation.linalg import block_tridiagonal as bt
from diskfriction.continuation.spectra import eigenpairs, rayleigh
from diskfriction.continuation.spectra import refinement
from diskfriction.continuation.linalg.solves import dense, measured
from diskfriction.continuation.spectra.tracking import Eigensystem, eigensystem, track
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


def random_blocks(N: int, b: int, seed: int = 0) -> bt.PeriodicBlocks:
    rng = np.random.default_rng(seed)
    return bt.PeriodicBlocks(*(rng.standard_normal((N, b, b)) for _ in range(3)))


def chain_matrix(N: int, F_x: float):
    """J of the paper's scene with N disks, eps = 1e-4, relaxed from rest to F_x (sparse)."""
    system = System.from_scene(Scene(N=N, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), F_x)
    return DiskEquilibria(system, q, xi, F_x, "J").stability_matrix(q, F_x), system


def test_periodic_blocks_are_the_matrix_and_solve_with_it():
    """from_matrix in an order (and back: original), traces, sparse, and (A - sigma I)^-1 and its transpose against
    numpy; an entry outside the pattern is refused."""
    N, b = 7, 3
    blocks = random_blocks(N, b)
    A = blocks.dense()
    assert np.array_equal(blocks.sparse().toarray(), A)
    trace, trace2 = blocks.traces()
    assert trace == pytest.approx(np.trace(A), rel=1e-13) and trace2 == pytest.approx(np.trace(A @ A), rel=1e-13)
    order = np.random.default_rng(1).permutation(N * b)
    shuffled = np.empty_like(A)
    shuffled[np.ix_(order, order)] = A  # shuffled[order[i], order[j]] = A[i, j]
    again = bt.PeriodicBlocks.from_matrix(sp.csr_array(shuffled), b, order)
    assert np.array_equal(again.dense(), A) and np.array_equal(again.order, order)
    assert np.array_equal(again.original().toarray(), shuffled) and np.array_equal(blocks.original().toarray(), A)
    sigma, rhs = 0.3 + 0.2j, np.random.default_rng(2).standard_normal(N * b)
    M = A - sigma * np.eye(N * b)
    assert np.allclose(blocks.solve(sigma, rhs), np.linalg.solve(M, rhs), rtol=1e-12, atol=1e-12)
    assert np.allclose(blocks.solve(sigma, rhs, transpose=True), np.linalg.solve(M.T, rhs), rtol=1e-12, atol=1e-12)
    far = A.copy()
    far[0, 3 * b] = 1.0  # block row 0 to block column 3: not a neighbour
    with pytest.raises(ValueError, match="pattern"):
        bt.PeriodicBlocks.from_matrix(far, b)


@pytest.mark.parametrize("N", [3, 4, 5, 12])
@pytest.mark.parametrize("sigma", [0.3, 0.3 + 0.2j])
def test_shifted_solves_are_numpys_for_every_chain_length(N, sigma):
    """The bordered block LU (the border's fill-in by forward recurrences) solves with M =
    A - sigma I and M^T for short chains, where the corners' block rows 0 and N - 2 are
    neighbours or one apart (N = 3, 4), for real and complex shifts; and _rqi_many's batched
    factorization of K shifts side by side gives each shift's solves."""
    b = 3
    blocks = random_blocks(N, b, seed=N)
    A, rng = blocks.dense(), np.random.default_rng(7)
    rhs = rng.standard_normal(N * b) + 1j * rng.standard_normal(N * b)
    M = A - sigma * np.eye(N * b)
    assert np.allclose(blocks.solve(sigma, rhs), np.linalg.solve(M, rhs), rtol=1e-11, atol=1e-11)
    assert np.allclose(blocks.solve(sigma, rhs, transpose=True), np.linalg.solve(M.T, rhs), rtol=1e-11, atol=1e-11)
    shifts = np.array([sigma, -0.4, 1.1 - 0.3j], complex)
    factors, scratch, columns = bt.work_arrays(N, b, shifts.size, shifts)
    bt.factor_shifted(blocks.diag, blocks.lower, blocks.upper, shifts, *factors, *scratch)
    x, many = rng.standard_normal((N, b, shifts.size)) + 0j, np.empty((N, b, shifts.size), complex)
    for transpose in (False, True):
        bt.solve_shifted(blocks.lower, blocks.upper, x, transpose, many, *factors, *columns)
        for k, shift in enumerate(shifts):
            M = A - shift * np.eye(N * b)
            want = np.linalg.solve(M.T if transpose else M, x[:, :, k].ravel())
            assert np.allclose(many[:, :, k].ravel(), want, rtol=1e-11, atol=1e-11)


def test_the_pivoted_iteration_keeps_a_real_pair_real(monkeypatch):
    """_pivoted_rqi refines a pair whose value and vectors are real with the real banded LU
    (dgbtrf), to LAPACK's eigenvalue and the complex iteration's (the same vectors with a
    complex phase) within 1e-13 R."""
    N, b = 8, 3
    blocks = random_blocks(N, b, seed=11)
    exact, right, left, residual, scale = unit_eigensystem(blocks)
    i = int(np.flatnonzero(exact.values.imag == 0.0)[0])
    rng = np.random.default_rng(2)
    v, r, lft = exact.values[[i]] + 1e-6 * scale, right[:, [i]].real.copy(), left[[i]].real.copy()
    r[:, 0] += 1e-6 * rng.standard_normal(N * b)
    used = []
    real_lu = rayleigh.dgbtrf
    monkeypatch.setattr(rayleigh, "dgbtrf", lambda *args: used.append(1) or real_lu(*args))
    one = (v.copy() + 0j, r + 0j, lft + 0j)
    res = rayleigh.pivoted_rqi(blocks, *one, 4, 1e-13 * scale)
    assert used and one[0].imag[0] == 0.0 and not np.any(one[1].imag)
    phase = np.exp(0.7j)
    other = (v.copy() + 0j, r * phase, lft / phase)
    calls = len(used)
    res_c = rayleigh.pivoted_rqi(blocks, *other, 4, 1e-13 * scale)
    assert len(used) == calls  # complex vectors: the complex LU
    assert res[0] <= 1e-13 * scale and res_c[0] <= 1e-13 * scale
    assert abs(one[0][0] - exact.values[i]) <= 1e-13 * scale and abs(one[0][0] - other[0][0]) <= 1e-13 * scale


@pytest.mark.parametrize("N", [3, 4, 5, 8, 9])
def test_the_folded_order_makes_the_periodic_matrix_banded(N):
    b = 2
    order = bt.folded(N)
    assert sorted(order) == list(range(N))
    perm = (b * order[:, None] + np.arange(b)).ravel()
    rows, cols = np.nonzero(random_blocks(N, b).dense()[np.ix_(perm, perm)])
    assert np.abs(rows - cols).max() <= 3 * b - 1


def test_refined_eigenpairs_are_lapacks_at_the_next_point():
    """N = 30: the eigensystem at F_x = 0.05 refined from the one at 0.0499 (first-order
    prediction, the old vectors) equals LAPACK's within 1e-12 of the spectral radius, every
    residual within 1e-13 of it, and the certificate passes."""
    A0, system = chain_matrix(30, 0.0499)
    A1 = chain_matrix(30, 0.05)[0]
    old = eigensystem(dense(A0), vectors=True)
    N, b = 30, system.ndof // 30
    blocks = bt.PeriodicBlocks.from_matrix(A1, b, bt.block_major(N, b))
    slopes = np.sum(old.left * (dense(A1 - A0) @ old.right).T, axis=1)  # l^H dA r
    scale = np.abs(old.values).max()
    values, right, left, residual = eigenpairs.refine_eigenpairs(blocks, old.values + slopes, old.right, old.left, 6,
                                                         1e-13 * scale)
    exact = np.linalg.eigvals(dense(A1))
    assert np.abs(track(exact, values) - exact).max() <= 1e-12 * scale
    assert residual.max() <= 1e-13 * scale
    assert np.allclose(np.sum(left * right.T, axis=1), 1.0, atol=1e-12)  # l^H r = 1
    assert refinement.certified(blocks, values, right, left, residual, scale) is not None


def test_a_real_eigenvalue_with_complex_phased_vectors_is_refined_in_real_arithmetic(monkeypatch):
    """The N = 30 refinement above from guesses whose real eigenvalues carry vectors times a
    phase e^{0.7 i} and an imaginary part of 1e-17 (as complex arithmetic leaves them): refined
    in real arithmetic (Guesses.made_real), the simple ones come out real, vectors with no
    imaginary part, and all are LAPACK's values; with NEAR_REAL = 0 they stay complex."""
    A0, system = chain_matrix(30, 0.0499)
    A1 = chain_matrix(30, 0.05)[0]
    old = eigensystem(dense(A0), vectors=True)
    N, b = 30, system.ndof // 30
    blocks = bt.PeriodicBlocks.from_matrix(A1, b, bt.block_major(N, b))
    scale = np.abs(old.values).max()
    real = np.flatnonzero(old.values.imag == 0.0)
    values, right, left = old.values.astype(complex), old.right.astype(complex), old.left.astype(complex)
    values[real] += 1e-17j * scale
    right[:, real] *= np.exp(0.7j)
    left[real] *= np.exp(-0.7j)  # l^H r unchanged
    exact = np.linalg.eigvals(dense(A1))

    def refined():
        return eigenpairs.refine_eigenpairs(blocks, values, right, left, 6, 1e-13 * scale)

    out = refined()
    # a simple eigenvalue (a degenerate one's pairs are refined again together, in complex arithmetic)
    gap = np.sort(np.abs(old.values[real][:, None] - old.values[None, :]), axis=1)[:, 1]
    alone = real[gap > 1e-9 * scale]
    assert alone.size > 0.8 * real.size
    assert np.all(out[0][alone].imag == 0.0) and not np.any(out[1][:, alone].imag) and not np.any(out[2][alone].imag)
    assert np.abs(track(exact, out[0]) - exact).max() <= 1e-12 * scale
    assert refinement.certified(blocks, *out, scale) is not None
    monkeypatch.setattr(eigenpairs, "NEAR_REAL", 0.0)
    assert np.any(refined()[1][:, real].imag)


def test_a_shift_that_breaks_the_blocks_lu_is_refined_with_pivoting():
    """A pair whose eigenvalue is also one of the first diagonal block's (e_0 an exact
    eigenvector): the blocks' LU without pivoting between blocks meets a singular pivot block,
    the pivoted banded LU does not."""
    N, b, mu = 6, 3, 0.7
    blocks = random_blocks(N, b, seed=3)
    blocks.diag[0][:, 0] = [mu, 0.0, 0.0]
    blocks.lower[1][:, 0] = 0.0  # nothing else couples into unknown 0: A e_0 = mu e_0
    blocks.upper[N - 1][:, 0] = 0.0
    A = blocks.dense()
    exact = eigensystem(A, vectors=True)
    i = int(np.argmin(np.abs(exact.values - mu)))
    assert abs(exact.values[i] - mu) <= 1e-12
    guess = exact.values.copy()
    guess[i] = mu  # the exact eigenvalue: the pivot block diag[0] - mu I is singular
    values, right, left = guess[[i]].copy(), exact.right[:, [i]].copy(), exact.left[[i]].copy()
    one, n = np.zeros(1, np.int64), N * b
    out_r, out_l = np.full((n, 1), np.nan, complex), np.full((1, n), np.nan, complex)  # as if never zeroed
    residual = rayleigh.rqi_many(blocks.diag, blocks.lower, blocks.upper, values.copy(), right, left, np.arange(n),
                                 one, one, one - 1, values, out_r, out_l, 3, 0.0)[0]
    assert np.isinf(residual[0])
    assert not np.any(out_r) and not np.any(out_l)  # a failed pair's vectors are written as zeros
    values, right, left, residual = eigenpairs.refine_eigenpairs(blocks, guess, exact.right, exact.left, 4, 1e-14)
    assert residual[i] <= 1e-13 and abs(values[i] - mu) <= 1e-13


def test_pairs_of_a_degenerate_eigenvalue_are_refined_again_together(monkeypatch):
    """A symmetric block-circulant matrix (every block row the same, lower = upper^T): the
    Fourier modes k and N - k share each eigenvalue. Guesses for one double eigenvalue span its
    eigenspace but are not biorthogonal (|l_i^H r_j| = 0.45): alone, each is an eigenpair at
    once and the certificate refuses them; their meeting discs send them to the cluster
    refinement, whose projected problem makes them biorthogonal, and the result is certified.
    With groups of at most one pair refined again, it is not."""
    N, b = 6, 2
    rng = np.random.default_rng(5)
    D, U = rng.standard_normal((b, b)), rng.standard_normal((b, b))
    blocks = bt.PeriodicBlocks(np.repeat([D + D.T], N, 0), np.repeat([U.T], N, 0), np.repeat([U], N, 0))
    values, vectors = np.linalg.eigh(blocks.dense())
    i = int(np.argmin(np.diff(values)))  # a double eigenvalue: values[i] = values[i + 1]
    assert values[i + 1] - values[i] <= 1e-12
    v1, v2 = vectors[:, i], vectors[:, i + 1]
    right, left = vectors.astype(complex), vectors.T.astype(complex)  # l_i^H r_i = 1
    right[:, i + 1] = left[i + 1] = (v1 + 2.0 * v2) / np.sqrt(5.0)
    scale = np.abs(values).max()

    def refined():
        out = eigenpairs.refine_eigenpairs(blocks, values.astype(complex), right, left, 6, 1e-13 * scale)
        return out, refinement.certified(blocks, *out, scale)

    (_, r, lft, residual), system = refined()
    assert residual.max() <= 1e-13 * scale and system is not None
    assert abs(lft[i] @ r[:, i + 1]) <= 1e-12 and abs(lft[i + 1] @ r[:, i]) <= 1e-12
    monkeypatch.setattr(eigenpairs, "LARGEST_CLUSTER", 1)
    assert refined()[1] is None


def unit_eigensystem(blocks: bt.PeriodicBlocks):
    """(LAPACK's eigensystem, its right vectors scaled to |r| = 1, its left ones to l^H r = 1,
    the residuals, the spectral radius) of the blocks' matrix."""
    exact = eigensystem(blocks.dense(), vectors=True)
    right = exact.right / np.linalg.norm(exact.right, axis=0)
    left = exact.left * np.linalg.norm(exact.right, axis=0)[:, None]
    residual = np.linalg.norm(blocks.dense() @ right - right * exact.values, axis=0)
    return exact, right, left, residual, np.abs(exact.values).max()


def born_pair_blocks(N: int, t: float, crowded: bool) -> bt.PeriodicBlocks:
    """N random 2 x 2 blocks weakly coupled (0.01), block 0 [[10, 1], [-t, 10]]: the real pair
    10 +- sqrt(-t) for t < 0, the complex pair 10 +- sqrt(t) i for t > 0; crowded: block 2
    diag(10.018, 9.982), two more eigenvalues near the pair (not a neighbour of block 0)."""
    blocks = random_blocks(N, 2, seed=6)
    blocks.lower[:] *= 0.01
    blocks.upper[:] *= 0.01
    blocks.diag[0] = [[10.0, 1.0], [-t, 10.0]]
    if crowded:
        blocks.diag[2] = [[10.018, 0.0], [0.0, 9.982]]
    return blocks


@pytest.mark.parametrize("crowded", [False, True])
def test_a_pair_born_in_the_step_is_refined_together(crowded):
    """Two real eigenvalues 10 +- 0.01 that become the complex pair 10 +- 0.01 i between the
    guess and the matrix (a 2 x 2 block [[10, 1], [-t, 10]], t from -1e-4 to 1e-4, weakly
    coupled to the rest): alone, a real guess stays real and never converges; each pair above
    tol is refined again with the pairs whose guesses are nearest, and the two span the
    invariant subspace in which the projected problem finds the pair. The result is LAPACK's
    and is certified; with groups of at most one pair it is not. crowded: two more eigenvalues,
    10 +- 0.018, each nearer one member's guess than its partner is (as in the chain of 400
    disks, where the partner was 1.5 to 2.9 times farther): with only the nearest guess
    (PARTNERS = 1) neither group spans the pair and the result is not certified."""
    old, new = eigensystem(born_pair_blocks(5, -1e-4, crowded).dense(), vectors=True), born_pair_blocks(5, 1e-4, crowded)
    exact = np.linalg.eigvals(new.dense())
    near = np.abs(exact.real - 10.0) < 0.015
    assert near.sum() == 2 and np.all(np.abs(exact[near].imag) > 5e-3)
    pair = np.abs(old.values - 10.0) < 0.015
    assert np.all(old.values[pair].imag == 0.0)
    if crowded:  # each member's nearest other guess is a bystander
        for z in old.values[pair]:
            assert not pair[np.argsort(np.abs(old.values - z))[1]]
    scale = np.abs(old.values).max()

    def refined():
        return eigenpairs.refine_eigenpairs(new, old.values, old.right, old.left, 6, 1e-13 * scale)

    values, right, left, residual = refined()
    assert np.abs(track(exact, values) - exact).max() <= 1e-12 * scale
    assert refinement.certified(new, values, right, left, residual, scale) is not None
    monkey = pytest.MonkeyPatch()
    with monkey.context() as m:
        m.setattr(eigenpairs, "LARGEST_CLUSTER", 1)
        assert refinement.certified(new, *refined(), scale) is None
    if crowded:
        with monkey.context() as m:
            m.setattr(eigenpairs, "PARTNERS", 1)
            assert refinement.certified(new, *refined(), scale) is None


def test_pairs_the_groups_leave_rough_are_repaired_by_shift_invert(monkeypatch):
    """The crowded pair born in the step (above) with only the nearest guess in each group
    (PARTNERS = 1), on 12 blocks (ARPACK needs k < n - 1): the refinement fails the
    certificate at the two members, left real; repaired gives them the two eigenvalues of the
    pair that the certified pairs near them do not hold, and the whole is certified and
    LAPACK's."""
    old, new = eigensystem(born_pair_blocks(12, -1e-4, True).dense(), vectors=True), born_pair_blocks(12, 1e-4, True)
    scale = np.abs(old.values).max()
    monkeypatch.setattr(eigenpairs, "PARTNERS", 1)
    out = eigenpairs.refine_eigenpairs(new, old.values, old.right, old.left, 6, 1e-13 * scale)
    assert refinement.certified(new, *out, scale) is None
    bad = refinement.failing(*out, scale)
    members = np.flatnonzero(np.abs(old.values - 10.0) < 0.015)
    assert bad.tolist() == members.tolist() and np.all(out[0][bad].imag == 0.0)
    fixed = refinement.repaired(new, old.values, *out, scale)
    assert refinement.certified(new, *fixed, scale) is not None
    exact = np.linalg.eigvals(new.dense())
    assert np.abs(track(exact, fixed[0]) - exact).max() <= 1e-12 * scale
    assert np.all(np.abs(fixed[0][members].imag) > 5e-3)


def test_a_pair_found_twice_is_repaired_and_a_wrong_trace_is_not():
    """An exact eigensystem of 20 random blocks with pair j replaced by a copy of pair i (one
    eigenvalue found twice, one lost): both fail (meeting discs, |l_i^H r_j| = 1), and the
    repair gives one of them the lost eigenvalue; certified, the values LAPACK's. A value moved
    off its eigenvalue with a small claimed residual fails only the traces: no pair to repair
    (None)."""
    blocks = random_blocks(20, 3, seed=4)
    exact, right, left, residual, scale = unit_eigensystem(blocks)
    real = np.flatnonzero(exact.values.imag == 0.0)
    i, j = real[0], real[np.argmin(np.abs(exact.values[real[1:]] - exact.values[real[0]])) + 1]
    values, r2, l2, res2 = exact.values.copy(), right.copy(), left.copy(), residual.copy()
    values[j], r2[:, j], l2[j], res2[j] = values[i], right[:, i], left[i], residual[i]
    assert refinement.certified(blocks, values, r2, l2, res2, scale) is None
    assert refinement.failing(values, r2, l2, res2, scale).tolist() == sorted([i, j])
    fixed = refinement.repaired(blocks, exact.values, values, r2, l2, res2, scale)
    assert refinement.certified(blocks, *fixed, scale) is not None
    assert np.abs(np.sort_complex(fixed[0]) - np.sort_complex(exact.values)).max() <= 1e-12 * scale
    moved = exact.values.copy()
    moved[i] += 0.5 * np.min(np.abs(np.delete(exact.values, i) - exact.values[i]))
    assert refinement.certified(blocks, moved, right, left, residual, scale) is None
    assert refinement.repaired(blocks, moved, moved, right, left, residual, scale) is None


def test_the_repairs_parts_left_over_and_polish():
    """left_over: of the eigenvalues found, those no held pair holds within its tolerance (a
    held pair just outside the disc's edge still holds; a pair not held holds nothing).
    polish: a pair in the matrix's order 1e-6 off its eigenvector (the order shuffled) comes
    back to a residual within 1e-13 R and LAPACK's value; one that does not improve is left."""
    found = np.array([1.0, 2.0, 3.0 + 1e-16])
    values = np.array([1.0 + 1e-15, 3.0 + 2e-16, 2.0])
    near = np.full(3, 1e-12)
    assert refinement.left_over(found, values, np.array([True, True, False]), near, 2.0, 1.0).tolist() == [1]
    assert refinement.left_over(found, values, np.ones(3, bool), near, 2.0, 1.0 - 1e-13).tolist() == []
    N, b = 8, 3
    blocks = random_blocks(N, b, seed=5)
    order = np.random.default_rng(3).permutation(N * b)
    shuffled = bt.PeriodicBlocks.from_matrix(blocks.original()[order][:, order], b, np.argsort(order))
    exact, right, left, residual, scale = unit_eigensystem(shuffled)
    i = int(np.argmax(exact.values.real))
    v, r, lft = exact.values.copy(), right.copy(), left.copy()
    r[:, i] += 1e-6 * np.random.default_rng(4).standard_normal(N * b)
    r[:, i] /= np.linalg.norm(r[:, i])
    v[i] += 1e-6 * scale
    A = shuffled.original()
    rough = np.linalg.norm(A @ r[:, [i]] - v[i] * r[:, [i]], axis=0)
    assert rough[0] > 1e-8 * scale
    res = rayleigh.polish(shuffled, np.array([i]), v, r, lft, rough, 1e-13 * scale)
    assert res[0] <= 1e-13 * scale and abs(v[i] - exact.values[i]) <= 1e-12 * scale
    assert np.linalg.norm(A @ r[:, i] - v[i] * r[:, i]) == pytest.approx(res[0], rel=1e-6, abs=1e-15 * scale)
    kept = v.copy()
    assert rayleigh.polish(shuffled, np.array([i]), v, r, lft, np.zeros(1), 1e-13 * scale)[0] == 0.0
    assert np.array_equal(v, kept)


def test_a_group_that_does_not_converge_replaces_only_the_members_it_improved(monkeypatch):
    """A pair above tol (a far guess) is refined again with its nearest guesses; where the
    group's iteration leaves a member above tol, only the members whose residual fell are
    written: a group returning worse pairs (here a stand-in for refine_cluster that moves
    every value and reports residual 1e3 R) leaves the result as without groups, and one
    that improves only the rough pair writes that pair alone."""
    blocks = random_blocks(6, 2, seed=3)
    exact = eigensystem(blocks.dense(), vectors=True)
    scale = np.abs(exact.values).max()
    tol = 1e-13 * scale
    values, right, left = exact.values.copy(), exact.right.copy(), exact.left.copy()
    rough = int(np.argmin(np.abs(values.imag)))
    assert values[rough].imag == 0.0
    # a guess far from its eigenpair (value and vectors): one Rayleigh step leaves it above tol
    values[rough] += 0.3 * scale
    rng = np.random.default_rng(0)
    right[:, rough] = rng.standard_normal(values.size)
    left[rough] = rng.standard_normal(values.size)
    right[:, rough] /= np.linalg.norm(right[:, rough])
    left[rough] /= left[rough] @ right[:, rough]
    refine = lambda: eigenpairs.refine_eigenpairs(blocks, values, right, left, 1, tol)  # noqa: E731
    with monkeypatch.context() as m:
        m.setattr(eigenpairs, "LARGEST_CLUSTER", 1)
        alone = refine()
    assert alone[3][rough] > tol

    def worse(blocks, v, r, lft, iterations, tol):
        v += 0.01 * scale
        return np.full(v.size, 1e3 * scale)  # above any unit vector's residual

    monkeypatch.setattr(eigenpairs, "refine_cluster", worse)
    kept = refine()
    assert np.array_equal(kept[0], alone[0]) and np.array_equal(kept[3], alone[3])

    def rough_only(blocks, v, r, lft, iterations, tol):
        v += 0.01 * scale
        return np.where(np.arange(v.size) == 0, 0.0, 1e3 * scale)  # member 0: the lowest index

    monkeypatch.setattr(eigenpairs, "refine_cluster", rough_only)
    groups = eigenpairs.refinement_groups(values, alone[0], alone[3], np.ones(values.size), tol)
    first = min(g[0] for g in groups if rough in g)
    mixed = refine()
    changed = np.flatnonzero(mixed[0] != alone[0])
    assert changed.tolist() == [first]


def test_the_groups_refined_again_are_meeting_discs_and_pairs_left_above_tol():
    """refinement_groups: two converged pairs whose discs kappa rho meet form a group; a pair
    above tol joins the pairs whose guesses are nearest its own although their discs are far apart
    (the chain of 1000 disks declined three spectra for such pairs near a collision, with
    residuals 1e-8 to 1e-4 of the spectral radius); a converged pair alone is in none."""
    guess = np.array([0.0, 1.0, 1.001, 5.0, 7.0, 7.0 + 1e-9])
    values = guess + np.array([0.0, 2e-4, -3e-4, 0.0, 0.0, 0.0])
    residual = np.array([1e-16, 1e-6, 1e-16, 1e-16, 1e-9, 1e-9])
    kappa = np.ones(guess.size)
    groups = eigenpairs.refinement_groups(guess, values, residual, kappa, 1e-13)
    assert [g.tolist() for g in groups] == [[1, 2], [4, 5]]  # 0 is 1000 times farther than 2
    # the second nearest guess joins within PARTNER_REACH times the nearest one's distance
    guess[0] = 1.0 - 0.003
    groups = eigenpairs.refinement_groups(guess, values, residual, kappa, 1e-13)
    assert [g.tolist() for g in groups] == [[0, 1, 2], [4, 5]]
    assert eigenpairs.refinement_groups(guess, values, np.full(guess.size, 1e-16), kappa, 1e-13) == []


def test_row_norms_are_numpys():
    """linalg.row_norms against np.linalg.norm(axis=1): complex in C and Fortran order (the
    column norms of right vectors: row_norms(right.T)), and real."""
    from diskfriction.continuation.linalg.solves import row_norms

    rng = np.random.default_rng(7)
    a = rng.standard_normal((40, 30)) + 1j * rng.standard_normal((40, 30))
    for x in (a, np.asfortranarray(a), a.T, a.real):
        assert np.allclose(row_norms(x), np.linalg.norm(x, axis=1), rtol=1e-14, atol=0.0)


def test_the_certificate_refuses_a_duplicate_and_a_wrong_eigenvalue():
    """Two pairs converged to one eigenvalue (overlapping discs), and a value moved away from
    its eigenvalue with small claimed residuals (disjoint discs, but the traces disagree)."""
    blocks = random_blocks(5, 3, seed=4)
    exact, right, left, residual, scale = unit_eigensystem(blocks)
    assert refinement.certified(blocks, exact.values, right, left, residual, scale) is not None
    real = np.flatnonzero(exact.values.imag == 0.0)
    i, j = real[0], real[1]
    values, r2, l2 = exact.values.copy(), right.copy(), left.copy()
    values[j], r2[:, j], l2[j] = values[i], right[:, i], left[i]
    assert refinement.certified(blocks, values, r2, l2, residual, scale) is None
    moved = exact.values.copy()
    moved[i] += 0.5 * np.min(np.abs(np.delete(exact.values, i) - exact.values[i]))
    assert refinement.certified(blocks, moved, right, left, residual, scale) is None


@pytest.mark.parametrize("N", [10, 20, 40])
@pytest.mark.slow
def test_sweeps_with_refined_spectra_find_the_same_collisions(N, chain_sweep, monkeypatch):
    """The paper's scene with N disks from rest to 0.12, every full spectrum refined where
    certified (REFINE_FROM = 0): the same collisions as with every spectrum decomposed, within
    1e-9 in F_x, with most full spectra refined and the declined ones counted."""
    scene = Scene(N=N, eps=1e-4)
    decomposed = chain_sweep(scene)[0]
    monkeypatch.setattr(refinement, "REFINE_FROM", 0)
    from diskfriction.models.chain.sweep import sweep

    with measured() as work:
        refined = sweep(System.from_scene(scene), 0.0, 0.12)
    assert len(refined.collisions) == len(decomposed.collisions) > 0
    assert [c.kind for c in refined.collisions] == [c.kind for c in decomposed.collisions]
    assert np.abs(np.array([c.p for c in refined.collisions]) - [c.p for c in decomposed.collisions]).max() <= 1e-9
    assert work.spectra_refined >= 0.8 * (work.spectra_refined + work.spectra)
    assert work.spectra >= work.refinements_declined  # a declined refinement takes a dense spectrum


def test_refinement_applies_only_where_the_whole_spectrum_is_refined(monkeypatch):
    """The chain's stability matrix is periodic block-tridiagonal (3 x 3 blocks) but for free
    disks; RefinedSpectra refines from REFINE_FROM (or its own refine_from) on, not where the
    dense spectra run on a GPU; DenseSpectra and a spectral window never refine."""
    from diskfriction.continuation.detection.samples import sample_at
    from diskfriction.continuation.spectra.eigensolvers import DenseSpectra, RefinedSpectra
    from diskfriction.continuation.spectra.window import SpectralWindow

    system = System.from_scene(Scene(N=6, eps=1e-4))
    q, xi = relax(system, *system.rest_state(), 0.01)
    problem = DiskEquilibria(system, q, xi, 0.01)
    assert problem.stability_structure(q, 0.01).block_size == 3
    free = System.from_scene(Scene(N=6, eps=0.0))
    assert not DiskEquilibria(free, *free.rest_state(), 0.0).stability_structure(free.rest_state()[0], 0.0).block_size
    x = np.append(q, 0.01)
    tangent = np.zeros(x.size)
    tangent[-1] = 1.0
    reference = sample_at(problem, 0.0, x, 1e-9, None, tangent)
    n = reference.eigvals.size
    monkeypatch.setattr(refinement, "REFINE_FROM", n + 1)
    assert not refinement.refinable(reference) and RefinedSpectra().refined(problem, x, reference) is None
    assert RefinedSpectra(refine_from=n).refined(problem, x, reference) is not None
    monkeypatch.setattr(refinement, "REFINE_FROM", n)
    assert refinement.refinable(reference)
    assert DenseSpectra().refined(problem, x, reference) is None
    assert SpectralWindow(-1.0, 0.0).refined(problem, x, reference) is None
    monkeypatch.setattr(refinement, "on_gpu", lambda n, device=None: True)
    assert not refinement.refinable(reference)
    monkeypatch.setattr(refinement, "on_gpu", lambda n, device=None: False)
    with measured() as work:
        again = sample_at(problem, 0.0, x, 1e-9, reference, tangent)
    assert work.spectra_refined == 1 and work.spectra == 0
    assert np.abs(again.eigvals - reference.eigvals).max() <= 1e-12 * np.abs(reference.eigvals).max()
    assert isinstance(again.system, Eigensystem)
