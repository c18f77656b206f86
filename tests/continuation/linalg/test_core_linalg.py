"""The core's linear algebra and the memory a run keeps (continuation/linalg/solves.py,
detection/spill.py): sparse factorizations, solves refined on a nearby factorization, bordered
matrices, freed memory reused, spilled files reused."""
from __future__ import annotations

import numpy as np
import pytest


def test_sparse_factorization_names_an_empty_row_or_column():
    """A sparse matrix with a row or column of no nonzero value (an explicitly stored zero
    included) is refused before SuperLU sees it, saying which; a full one factorizes."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import SingularMatrix, factorize

    full = np.array([[2.0, 1.0, 0.0], [0.0, 3.0, 1.0], [1.0, 0.0, 4.0]])
    assert np.allclose(factorize(sp.csc_array(full)).solve(np.ones(3)), np.linalg.solve(full, np.ones(3)))
    no_column = full.copy()
    no_column[:, 1] = 0.0
    with pytest.raises(SingularMatrix, match="empty column"):
        factorize(sp.csc_array(no_column))
    stored_zero = sp.csc_array(full)
    stored_zero.data[stored_zero.indices == 2] = 0.0  # row 2 stored, all zero
    with pytest.raises(SingularMatrix, match="empty row"):
        factorize(stored_zero)


def test_same_matrix_compares_values_whatever_the_pattern_stores():
    """linalg.same_matrix: a sparse matrix with an explicitly stored zero is the same as one
    without it; one value off by a rounding unit, another shape, or dense against sparse is
    not the same matrix."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import same_matrix

    full = np.array([[2.0, 1.0, 0.0], [0.0, 3.0, 1.0], [1.0, 0.0, 4.0]])
    stored = sp.csr_array((np.array([2.0, 1.0, 0.0, 3.0, 1.0, 1.0, 4.0]),
                           np.array([0, 1, 2, 1, 2, 0, 2]), np.array([0, 3, 5, 7])), shape=(3, 3))
    assert same_matrix(sp.csr_array(full), stored) and same_matrix(full, full.copy())
    off = full.copy()
    off[1, 1] = np.nextafter(3.0, 4.0)
    assert not same_matrix(sp.csr_array(full), sp.csr_array(off)) and not same_matrix(full, off)
    assert not same_matrix(full, full[:2]) and not same_matrix(full, sp.csr_array(full))


def test_solve_near_refines_to_a_fresh_solve_or_gives_up():
    """linalg.solve_near on the LU of a matrix 1e-8 away reaches the fresh solve to 1e-13 in
    a few corrections, for M and for M^T; on one 10 % away it gives up (None) after one."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import factorize, solve_near

    rng = np.random.default_rng(7)
    M = sp.random_array((60, 60), density=0.1, random_state=rng) + 4.0 * sp.eye_array(60)
    M = sp.csr_array(M)
    r = rng.standard_normal(60)
    exact, exact_t = np.linalg.solve(M.toarray(), r), np.linalg.solve(M.toarray().T, r)
    E = sp.random_array((60, 60), density=0.1, random_state=rng)
    near = factorize(M + 1e-8 * E)
    assert np.allclose(solve_near(near, lambda y: M @ y, r), exact, rtol=0.0, atol=1e-13)
    assert np.allclose(solve_near(near, lambda y: M.T @ y, r, transpose=True), exact_t, rtol=0.0, atol=1e-13)
    far = factorize(M + 0.4 * E)
    assert solve_near(far, lambda y: M @ y, r) is None


def test_bordered_sparse_matrix_is_canonical_and_keeps_stored_zeros():
    """linalg.bordered of a sparse K (CSR or CSC, with duplicate entries and a stored zero):
    [[K, c], [b^T, d]] in CSC with sorted row indices, duplicates summed, the stored zero and
    every border entry kept (the pattern depends on K's pattern alone)."""
    import scipy.sparse as sp
    from diskfriction.continuation.linalg.solves import bordered

    rows, cols = np.array([0, 2, 2, 1, 0, 3, 1]), np.array([1, 0, 0, 3, 1, 2, 1])
    values = np.array([1.0, 2.0, 3.0, 0.0, 4.0, 5.0, 6.0])
    c, b = np.array([1.0, 0.0, 2.0, 3.0]), np.array([0.5, 0.0, -1.0, 2.0])
    expected = np.zeros((5, 5))
    np.add.at(expected, (rows, cols), values)
    expected[:4, 4], expected[4, :4], expected[4, 4] = c, b, 7.0
    order = np.lexsort((cols, rows))  # CSR arrays as given, the duplicates (2, 0) unsummed
    raw = sp.csr_array((values[order], cols[order], np.searchsorted(rows[order], np.arange(5))),
                       shape=(4, 4))
    assert raw.nnz == 7
    for K in (raw, sp.coo_array((values, (rows, cols)), shape=(4, 4)).asformat("csc")):
        M = bordered(K, c, b, 7.0)
        assert M.format == "csc" and np.array_equal(M.toarray(), expected)
        for j in range(5):
            column = M.indices[M.indptr[j]:M.indptr[j + 1]]
            assert np.all(np.diff(column) > 0)
        assert M.nnz == 5 + 4 + 5  # K's 5 positions (the stored zero too), b's 4, [c; d]


def test_heap_kept_reuses_freed_memory():
    """Inside linalg.heap_kept (the continuation runs in it) a large array freed and allocated
    again reuses the process's memory: no page faults, where glibc's default unmaps it and the
    kernel hands out fresh (zeroed) pages; nested contexts restore the default only at the
    outermost exit."""
    import resource

    from diskfriction.continuation.linalg import solves as linalg

    if linalg._glibc() is None:
        pytest.skip("the C library is not glibc: heap_kept changes nothing")

    def faults_of_a_second_allocation() -> int:
        a = np.ones(8 << 20)  # 64 MB, above glibc's largest mmap threshold (32 MiB)
        del a
        before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
        a = np.ones(8 << 20)
        del a
        return resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before

    with linalg.heap_kept():
        with linalg.heap_kept():
            kept = faults_of_a_second_allocation()
        assert linalg._kept[0] == 1
    assert linalg._kept[0] == 0
    default = faults_of_a_second_allocation()
    assert kept < 16 <= default, (kept, default)


def test_spilled_files_are_reused_in_place_but_never_under_a_live_mapping():
    """Inside spill.files_kept (the continuation runs in it) the file of a spilled array whose
    views are all gone is overwritten by the next spill (the same file, new values), while a
    mapping still alive keeps its values; a file still mapped when the process forks is closed,
    not reused, so the child's inherited view keeps its values while the parent spills on;
    leaving the context closes the idle files, and outside it nothing is kept."""
    import os

    from diskfriction.continuation.detection import spill

    if not hasattr(os, "fork"):
        pytest.skip("no fork on this platform")
    a = np.arange(24.0).reshape(4, 6) * (1 + 1j)
    with spill.files_kept():
        x = spill.on_disk(a)
        y = spill.on_disk(2 * a)
        view = x[:, 2]
        del x
        assert spill._idle == []  # a view keeps the mapping
        del view
        assert len(spill._idle) == 1
        idle = spill._idle[0]
        z = spill.on_disk(3 * a)  # into x's file
        assert spill._idle == [] and np.array_equal(z, 3 * a) and np.array_equal(y, 2 * a)
        del z
        assert spill._idle == [idle]

        read, write = os.pipe()
        pid = os.fork()
        if pid == 0:  # the child holds y's inherited mapping while the parent spills over
            os.close(write)
            os.read(read, 1)
            os._exit(0 if np.array_equal(y, 2 * a) and spill._idle == [] else 1)
        os.close(read)
        del y  # mapped before the fork: closed, not kept
        assert len(spill._idle) == 1
        w = [spill.on_disk(k * a) for k in (5, 6)]
        os.write(write, b"x")
        os.close(write)
        assert os.waitpid(pid, 0)[1] == 0
        assert np.array_equal(w[0], 5 * a) and np.array_equal(w[1], 6 * a)
        del w
        assert len(spill._idle) == 2
        u = spill.on_disk(np.arange(5.0))  # an idle file of another size, cut to this one
        assert np.array_equal(u, np.arange(5.0)) and len(spill._idle) == 1
    assert spill._idle == [] and spill._kept[0] == 0
    x = spill.on_disk(a)
    del x
    assert spill._idle == []
