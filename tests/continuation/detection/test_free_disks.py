"""The chain at eps = 0: disks beyond the load front are held by the substrate alone (free
disks); their rolling modes are counted and left out of detection, the spectrum is the whole
matrix's with vectors on the coupled chain alone, and a long sparse chain finds the collisions
of a short dense one."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation.branch import Stop, StopCode
from diskfriction.continuation.spectra.eigensolvers import DenseSpectra
from diskfriction.continuation.spectra.tracking import eigenvalue_slopes
from diskfriction.models.chain.equilibria import DiskEquilibria, relax
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


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
