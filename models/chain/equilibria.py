"""Equilibria of the disk chain as a continuation problem, with the tangential history carried
(the base it shares with a packing's: models/equilibria.py).

u = q (docs/model.md#history layout) [length, rad], p = F_x [force]. The committed state (q_c,
xi_c) is the last accepted point. The residual of a trial q is the quasistatic step from it:

    G(q, F_x) = F(q, xi(q); F_x),  xi(q) = history rule from (q_c, xi_c) to q, Coulomb cap included,

dG/dq = -J(q, xi(q)) (the total stiffness, history following q), dG/dF_x = e_(x_1).
docs/model.md#history solves with the uncapped history and caps afterwards; the smoothed law beyond t* falls
(phi(u) decreases for u > 1), so that problem has no equilibrium once a contact must slide.
Capping inside the residual (return mapping) is the limit of docs/model.md's procedure for small steps
and equal to it while nothing slides. For the smoothed law J stays exact at the cap: there
dF_t/dxi = 0 and dF_t/ddelta is the same at fixed xi and at fixed u = xi / t*. For the linear
law J is the sticking tangent at a sliding contact, and Newton converges only linearly there.

Contact events (event_functions): a contact opening or closing (delta changes sign), a history
reaching its Coulomb limit (t* - |xi| changes sign), and a free disk joining (below). The core
ends the step on the first event (arclength.py), and commit() commits the state exactly there
(reset, first contact, cap); the committed history is integrated piecewise straight between
events and accepted points, with the midpoint rule's O(|dq|^3) error per piece.

Free disks (eps = 0). A disk held by the substrate alone is decoupled from the chain and its
block of J is singular: the substrate contact's force depends on q only through delta_w = R - y
and the history increment w . dq (d xi = dx + R dtheta, docs/model.md#contacts), so every direction
orthogonal to e_y and w costs no force (rolling without slip, dx = -R dtheta: an exact zero
mode), and the disk's generalized force lies in span(e_y, w), so its equations have the same
exact redundancy (T_i - R F_x,i = 0). Physically the rolling position of such a disk is
arbitrary. Its gauge is fixed at the committed value: for each null direction m, one of the
disk's equations (the one the null direction weighs most, redundant there) is replaced by
kappa m . (q_i - q_c,i) = 0, with kappa the scale of the disk's stiffness.
A disk counts as free when both its pair overlaps are at most delta_join = 8 eps_mach L (eps_mach
the double-precision epsilon, L the ring length, the largest coordinate): a few units in the
last place of the positions. At eps = 0 the load transmitted along the chain decays
geometrically (about 0.37 per disk on the paper's scene), and the disks beyond the front touch at
overlaps of rounding size, which open and close under Newton's updates and whose stiffness
k_n delta^(1/2) (1e-4 of the substrate's) is set by rounding, not by the load: below delta_join
an overlap is noise, and such a disk is treated as free (its dropped equation has a residual of
at most the pair forces, k_n delta_join^(3/2) ~ 1e-17). The stability
matrix keeps the physical J; its spectrum is the coupled chain's plus each free disk's block,
which the problem declares decoupled (stability_structure), and the free disks' modes are
excluded from collision detection (decoupled, they cannot form a complex pair with anything;
identical free disks even share their eigenvalues). A free disk joins the chain when one of its
pairs reaches delta_join (a join event); its gauge row is dropped. The number of free disks
falls as the load spreads (tests/continuation/detection/test_free_disks.py).
"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import scipy.sparse as sp

from diskfriction.continuation.linalg.block_tridiagonal import block_major
from diskfriction.continuation.linalg.solves import SingularMatrix, solve
from diskfriction.continuation.spectra.structure import StructuredMatrix
from diskfriction.matrices import Matrix
from diskfriction.models.equilibria import Equilibria, GaugeRows
from diskfriction.symbolic import System

SPARSE_FROM = 240
"""Chains with at least this many degrees of freedom (N = 80 with rotation) use sparse J and
SuperLU; below, dense LAPACK is faster (benchmarks/scaling.py)."""

DELTA_JOIN_ULPS = 8
"""A pair overlap of at most this many units in the last place of the ring length is rounding:
a disk whose two pairs are that small is free (module docstring)."""


class EquilibriumError(RuntimeError):
    """No equilibrium could be converged."""


@dataclass(frozen=True)
class FreeDisk:
    """A disk held by the substrate alone: its disk index, its dofs, its null directions
    (orthonormal columns of `modes`, in the dofs' order), the equation rows they replace
    (`rows`), and the stiffness scale kappa of the gauge rows."""

    disk: int
    dofs: np.ndarray
    modes: np.ndarray
    rows: np.ndarray
    kappa: float


def free_modes(w: np.ndarray, friction: bool, disk: int, dofs: np.ndarray, kappa: float) -> FreeDisk:
    """Null directions of a disk held by the substrate alone: the orthogonal complement of e_y
    and (with substrate friction) the history increment coefficients w, in the disk's D local
    dofs (x, y[, theta]); each replaces the equation row it weighs most."""
    D = w.size
    span = [np.eye(D)[1]] + ([w / np.linalg.norm(w)] if friction else [])
    Q = np.linalg.qr(np.column_stack(span), mode="complete")[0]
    modes = Q[:, len(span):]
    rows = []
    for k in range(modes.shape[1]):
        weights = np.abs(modes[:, k])
        weights[rows] = -1.0
        rows.append(int(np.argmax(weights)))
    return FreeDisk(disk, dofs, modes, np.array(rows, dtype=int), kappa)


class DiskEquilibria(Equilibria):
    """The continuation problem of one System (see the module docstring). sparse: J as a CSR
    matrix (SuperLU's solves; a spectral window's shift-invert needs it) or dense (LAPACK's);
    None: sparse from SPARSE_FROM degrees of freedom."""

    def __init__(self, system: System, q: np.ndarray, xi: np.ndarray, F_x: float,
                 matrix: str | None = None, newton_tol: float = 1e-11, sparse: bool | None = None,
                 gauge: bool = True):
        self.system = system
        self.gauge = gauge  # False: no disk is treated as free (relax: its mass term regularises)
        self.matrix = Matrix(matrix or system.scene.matrix)
        self.newton_tol = newton_tol
        self.sparse = system.ndof >= SPARSE_FROM if sparse is None else sparse
        self._pattern = _pattern(system.rows, system.cols, system.ndof, self.sparse)
        self.e_x1 = np.zeros(system.ndof)
        self.e_x1[0] = 1.0
        s = system.scene
        self.delta_join = DELTA_JOIN_ULPS * np.finfo(float).eps * s.L
        w = np.empty(2 * system.kernels.D)
        system.kernels.wall_increment_coeffs(s.R, w)
        self._wall_w = w[:system.kernels.D].copy()
        self._kappa = system.kernels.normal_stiffness(s.delta_w0, s.k_n)  # the substrate's, at rest
        D = system.kernels.D  # every free disk has the same null directions and gauge rows:
        self._free_template = free_modes(self._wall_w, bool(system.kernels.WALL_FRICTION), 0,
                                         np.arange(D), self._kappa)
        self._set_committed(q, xi, F_x)

    # -- the committed state
    def _set_committed(self, q: np.ndarray, xi: np.ndarray, F_x: float) -> None:
        self.q_c, self.xi_c, self.p_c = q.copy(), xi.copy(), float(F_x)
        self._forget_trial()
        self.free = self._free_disks(q) if self.gauge else ()
        self.gauge_rows = _FreeDiskRows.of(self.free, self.system.rows, self.system.cols, self.system.ndof,
                                           self.sparse) if self.free else None

    @property
    def F_c(self) -> float:
        """The committed load F_x [force]."""
        return self.p_c

    def _free_disks(self, q: np.ndarray) -> tuple[FreeDisk, ...]:
        """Disks (other than disk 1, which carries F_x) whose pairs both have delta <= delta_join."""
        N, D = self.system.N, self.system.kernels.D
        loose = self.system.overlaps(q)[:N] <= self.delta_join
        t = self._free_template
        if not t.modes.shape[1]:
            return ()
        return tuple(replace(t, disk=i, dofs=np.arange(D) * N + i)
                     for i in range(1, N) if loose[i - 1] and loose[i])

    @property
    def free_count(self) -> int:
        """Free rolling (zero) modes at the committed point, excluded from detection."""
        return sum(d.modes.shape[1] for d in self.free)

    # -- the history and its stiffness at a trial q
    def trial(self, q: np.ndarray, F_x: float | None = None, cap: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """History at q reached by a straight step from the committed state, and slid flags (the
        chain's history rule does not depend on the load F_x)."""
        return self.system.history_step(self.q_c, q, self.xi_c, cap=cap)

    def _xi(self, q: np.ndarray) -> np.ndarray:
        """Trial history at q, kept for the last q (Newton asks residual then jacobian)."""
        return self._at_trial(q, None, "xi", lambda: self.trial(q)[0])

    def _values(self, q: np.ndarray) -> np.ndarray:
        """Values of the physical J = -dF/dq at q (pattern system.rows, system.cols)."""
        xi = self._xi(q)
        return self._at_trial(q, None, "J", lambda: self.system.jacobian_values(q, xi))

    def _physical(self, q: np.ndarray, xi: np.ndarray | None = None, row_scale=None):
        """The physical J at q (trial history unless xi is given), dense or sparse; with
        row_scale, diag(row_scale) J."""
        vals = self._values(q) if xi is None else self.system.jacobian_values(q, xi)
        return self._pattern.matrix(vals, row_scale)

    # -- Problem protocol
    def residual(self, q, F_x):
        return self._gauged(self.system.forces(q, self._xi(q), F_x), q)

    def jacobian(self, q, F_x):
        """dG/dq = -J with the free disks' gauge rows."""
        vals = -self._values(q)
        if self.gauge_rows is not None:
            return self.gauge_rows.jacobian(vals)
        return self._pattern.matrix(vals)

    def dG_dp(self, q, F_x):
        return self.e_x1

    def stability_matrix(self, q, F_x):
        """J or M^-1 J of the physical J (no gauge rows)."""
        return self._physical(q, row_scale=None if self.matrix is Matrix.J else 1.0 / self.system.mass_diagonal())

    def stability_structure(self, q, F_x) -> StructuredMatrix:
        """The stability matrix with its structure: each free disk's D x D block decoupled (its
        modes excluded from collision detection: decoupled, they cannot form a complex pair
        with anything; only the coupled chain's modes carry vectors, so that a sample of a long
        chain at eps = 0 is not as large as a full one); without free disks and from N = 3,
        periodic block-tridiagonal with one D x D block per disk (each disk couples to its
        neighbours, disk N to disk 1: symbolic/system.py), for refined full spectra."""
        A = self.stability_matrix(q, F_x)
        if self.free:
            return StructuredMatrix(A, decoupled=np.stack([d.dofs for d in self.free]))
        N = self.system.scene.N
        if N < 3:
            return StructuredMatrix(A)
        D = self.system.ndof // N
        return StructuredMatrix(A, block_size=D, block_order=block_major(N, D))

    def acting_overlaps(self, x) -> np.ndarray:
        """Every contact's overlap at x = (q, F_x): pairs, then substrate."""
        return self.system.overlaps(x[:-1])

    def event_functions(self, q, F_x):
        """Per contact: delta, then t* - |xi| of the uncapped history of active contacts (1 for
        open ones), then delta - delta_join of the pairs of free disks (join events), at q. The
        joins belong to the committed free disks, so the array keeps its length over a step."""
        delta = self.system.overlaps(q)
        xi = self.trial(q, cap=False)[0]
        margin = self.system.coulomb_limit(delta) - np.abs(xi)
        g = np.concatenate([delta, np.where(delta > 0, margin, 1.0)])
        N = self.system.N
        joins = [k % N for d in self.free for k in (d.disk - 1, d.disk)]
        return np.concatenate([g, delta[joins] - self.delta_join])

    def root_events(self) -> np.ndarray:
        """The overlaps delta among the event functions (their first block): a Hertz
        contact's stiffness goes as delta^(1/2) where it opens or closes."""
        m = 2 * self.system.N  # pairs, then substrate (symbolic/system.py, overlaps)
        return np.concatenate([np.ones(m, bool), np.zeros(m + 2 * len(self.free), bool)])

    def state(self) -> tuple:
        """(q, xi, F_x) committed."""
        return self.q_c.copy(), self.xi_c.copy(), self.p_c

    def restore(self, snapshot: tuple) -> None:
        self._set_committed(*snapshot)

    def commit(self, q_old, F_old, q_new, F_new) -> bool:
        """Commit the state at (q_new, F_new). True asks the core to re-solve there: when the
        Coulomb cap changed a history, or the set of free disks (and so the gauge) changed."""
        xi, slid = self.trial(q_new)
        before = {d.disk for d in self.free}
        self._set_committed(q_new, xi, F_new)
        return bool(slid.any()) or before != {d.disk for d in self.free}


@dataclass(frozen=True)
class _FreeDiskRows(GaugeRows):
    """The free disks' gauge rows, stacked once per set of free disks (a chain of 1000 disks
    has up to 999): the disks' dofs (f, D), the equation rows their null directions replace
    (f, k), the gauge rows' coefficients kappa m^T (f, k, D); and dG/dq's pattern: the entries
    of -J outside those rows (keep, a mask over J's pattern) followed by the gauge rows'."""

    keep: np.ndarray
    pattern: object

    @classmethod
    def of(cls, free: tuple, j_rows: np.ndarray, j_cols: np.ndarray, n: int, sparse: bool) -> "_FreeDiskRows":
        dofs = np.stack([d.dofs for d in free])
        rows = np.stack([d.dofs[d.rows] for d in free])
        weights = np.stack([d.kappa * d.modes.T for d in free])
        keep = ~np.isin(j_rows, rows.ravel())
        D, k = dofs.shape[1], rows.shape[1]
        all_rows = np.concatenate([j_rows[keep], np.repeat(rows, D, axis=1).ravel()])  # (disk, row, dof)
        all_cols = np.concatenate([j_cols[keep], np.tile(dofs, (1, k)).ravel()])
        return cls(dofs, rows, weights, keep, _pattern(all_rows, all_cols, n, sparse))

    def jacobian(self, vals: np.ndarray):
        """dG/dq from the values of -J on its pattern."""
        return self.pattern.matrix(np.concatenate([vals[self.keep], self.weights.ravel()]))


def _pattern(rows: np.ndarray, cols: np.ndarray, n: int, sparse: bool):
    """The assembly of a fixed triplet pattern: CSR (SuperLU's solves) or dense (LAPACK's)."""
    return _CsrPattern(rows, cols, n) if sparse else _DensePattern(rows, cols, n)


class _DensePattern:
    """Dense assembly of a fixed triplet pattern (duplicates summed): a bincount of the values
    into the flat n x n array."""

    def __init__(self, rows: np.ndarray, cols: np.ndarray, n: int):
        self.keys, self.n = rows * n + cols, n

    def matrix(self, vals: np.ndarray, row_scale=None) -> np.ndarray:
        J = np.bincount(self.keys, weights=vals, minlength=self.n * self.n).reshape(self.n, self.n)
        return J if row_scale is None else J * row_scale[:, None]


class _CsrPattern:
    """CSR assembly of a fixed triplet pattern (rows, cols, duplicates summed), computed once:
    a new matrix is a bincount of the values into the pattern's slots."""

    def __init__(self, rows: np.ndarray, cols: np.ndarray, n: int):
        keys = rows * n + cols
        unique, self.slot = np.unique(keys, return_inverse=True)
        self.rows, self.indices = unique // n, unique % n
        self.indptr = np.searchsorted(self.rows, np.arange(n + 1))
        self.n = n

    def matrix(self, vals: np.ndarray, row_scale=None) -> sp.csr_array:
        data = np.bincount(self.slot, weights=vals, minlength=self.rows.size)
        if row_scale is not None:
            data *= row_scale[self.rows]
        return sp.csr_array((data, self.indices, self.indptr), shape=(self.n, self.n))


def relax(system: System, q: np.ndarray, xi: np.ndarray, F_x: float, tol: float = 1e-11,
          max_iter: int = 500) -> tuple[np.ndarray, np.ndarray]:
    """Equilibrium at F_x reached in one quasistatic step from (q, xi), by pseudo-transient
    continuation: (J + M / dt^2) dq = F with dt grown by the residual ratio (switched evolution
    relaxation). It converges where Newton cannot start: at the paper's rest state the pairs
    touch at delta = 0 and J has N zero (rolling) modes. Returns (q1, xi1) with xi1 committed."""
    problem = DiskEquilibria(system, q, xi, 0.0, gauge=False)  # the mass term regularises the zero modes
    M = system.mass_diagonal()
    q1, dt = q.copy(), 1.0
    G = problem.residual(q1, F_x)
    r0 = np.linalg.norm(G)
    for _ in range(max_iter):
        if np.abs(G).max() <= tol:
            return q1, problem.trial(q1)[0]
        K = problem._physical(q1)
        K = K + (sp.diags_array(M / dt**2) if sp.issparse(K) else np.diag(M / dt**2))
        try:
            q1 = q1 + solve(K, G)
        except SingularMatrix:
            break
        G = problem.residual(q1, F_x)
        r = np.linalg.norm(G)
        dt = min(dt * max(r0 / r, 0.5), 1e12)
        r0 = r
    raise EquilibriumError(f"relaxation did not converge at F_x = {F_x:.12g} (residual {np.abs(G).max():.3g})")
