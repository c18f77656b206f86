"""Equilibria of a sheared packing as a continuation problem, with the tangential history carried
(docs/packings.md#shear).

u = q = (x, y, theta) of every disk (models/packing/network.py) [length, rad], p = gamma, the
Lees-Edwards strain [1]. The committed state (q_c, xi_c, gamma_c) is the last accepted point; the
residual of a trial (q, gamma) is the quasistatic step from it, as for the chain
(models/equilibria.py, the base both share):

    G(q, gamma) = F(q, xi(q, gamma); gamma),  xi = history rule from the committed state,

dG/dq = -J (the total stiffness, history following q), dG/dgamma = dF/dgamma (history following
gamma). Contact rows: every pair within REACH of touching at the committed point; a row keeps its
image and its history while it lasts, and the rows are found again at every commit (the history
carried over by (i, j, cx, cy)); a pair that was not a row cannot close within one step
(commit checks that it did not).

Three kinds of exact zero modes are handled explicitly, their equations replaced by gauge rows
kappa (q - q_c) = 0 (kappa the Hertz stiffness at the median overlap [force / length]):
- **Translations.** A uniform shift of every disk changes no force: J T = 0 for T = the x and y
  translations, and the forces sum to zero (Newton's third law), so two equations are
  redundant. The reference disk (the one with most contacts) has its x and y equations
  replaced by gauge rows.
- **Loose disks** (rattlers): a disk with fewer than LOOSE_BELOW contacts that hold it
  (delta > delta_hold, LOOSE_OVERLAP of the median overlap at the start) with disks that are
  not loose themselves (Gauge.of) carries no load. Its contacts are left out of the forces
  (their rows stay as watched rows: no events, no history), its three equations are replaced
  by gauge rows holding it at its committed place. At a commit, a loose disk a neighbour
  pushed into gives way (_release_pushed), pushing on any loose disk in its way, and one
  caught between facing contacts with the network joins it. The forces its own slight
  overlaps would exert (below delta_hold, or of the preparation's force tolerance) are
  dropped.
- **Rotations without tangential forces** (mu = 0, or the tangential law "none":
  Network.frictional). No torque acts on a disk, so every theta is a zero mode: the rotations'
  equations are gauge rows, and the unknowns are the positions. J on them is the Hessian of the
  Hertz energy, symmetric, and the tracked spectrum of M^-1 J is real (similar to M^-1/2 J
  M^-1/2): its StructuredMatrix has a symmetric form (SymmetricNetwork), so no complex pair can
  arise from rounding. No history is charged (Network.history_step) and no contact slides.
  Loose disks follow the frictional rule (LOOSE_BELOW).

The tracked matrix is the network's stability matrix A (J or M^-1 J) in coordinates relative to
the reference disk, A_g: with P the map q -> (q_k - q_ref for x and y dofs, theta as it is) on
the kept dofs (not the reference's x, y, not a loose disk's, and without tangential forces no
rotation) and E the kept columns, A_red = P A E has exactly the spectrum of A without its two
translation zeros (and the rotations' zeros) (A T = 0 makes A block triangular in the basis
(T, E)); A_g (stability_matrix, sparse) is A_red at the kept dofs and a constant far below
A_red's spectrum on the gauge rows' diagonal (assembly.PARKED), so that every sample has n
eigenvalues; those of the gauge rows are reported as 0 and excluded from detection. The problem
declares this to the eigensolvers (stability_structure, NetworkMatrix): A_red is the coupled
part; a spectral window (continuation/spectra/window.py) takes the k eigenvalues of A_red
nearest its centre by sparse shift-invert (the translations and loose disks never crowd a
window at 0), and for their vectors factorizes A itself, the loose disks' dofs parked on its
diagonal, with its two translation zeros projected out (the deflation, nearest.Deflated); the
eigenvectors found are mapped to A_g's (right: P, left: the kept dofs), on which the
Rayleigh-Ritz projection is taken. Within a committed state dG/dq, A_red, A_g and the
deflation's A are fixed linear maps of J's values (models/packing/assembly.py), set up at the
first use after a commit.
"""
from __future__ import annotations

import hashlib
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from diskfriction.continuation.linalg.solves import LinearSolver
from diskfriction.errors import OneLineError
from diskfriction.matrices import Matrix
from diskfriction.models.equilibria import Equilibria, GaugeRows
from diskfriction.models.packing.assembly import GaugeMaps, NetworkMatrix, StateMaps, state_maps
from diskfriction.models.packing.network import D, Network

REACH = 0.1
"""Pairs within this fraction of the small radius R of touching are contact rows [R]."""

LOOSE_BELOW = 2
"""A disk with fewer holding contacts than this is loose: with friction two contacts hold a
disk, and so does the frictionless rule: with one contact a disk carries no force in
equilibrium, while two facing contacts can carry the load of a force chain, which the network's
equations must not drop (held by two, a disk buckles out across them once a third contact's
stiffness falls below their F / r: the branch is lost there, a plastic event)."""

LOOSE_OVERLAP = 1e-3
"""A contact counts towards holding its disks when its overlap exceeds this fraction of the
median overlap at the start, delta_hold [1]. A disk whose second-last such contact unloads is
near a singular point (the Hertz stiffness k_n delta^(1/2) of its contacts vanishes with their
forces: a disk held by two contacts unloads both together); counting from delta_hold makes it
loose, by an event, while its stiffness is still 3 % of a typical contact's."""

RELEASE_GAP = 1e-2
"""A pushed loose disk gives way this fraction of R beyond first contact, when nothing is in the
way: a rattler's place in its cage is arbitrary, and without a gap the pusher would reach it again
after every strain step of delta_hold / L."""

RELEASE_PASSES = 50
"""At most this many passes of the pushed loose disks giving way at one commit
(_release_pushed): a push travels one disk further along a chain of loose disks per pass, and
a disk caught in a cage by a loose disk is freed once that one moved. 24 disks, seed 3, at mu =
0.3 and 1 took up to 8 and 18 passes (a disk and a loose neighbour giving way by turns)."""

WINDOW_MARGIN, WINDOW_EXTRA = 1.2, 4
"""A shear's spectral window's k at the start of a segment: WINDOW_MARGIN times the eigenvalues
within its reach there, plus WINDOW_EXTRA (window.SpectralWindow's margin and extra; the
chain's are 1.5 and 8): a window sample costs about as k, and where shear softens the low
spectrum and the window crowds, it is sized anew and the run goes on (models/packing/shear.py;
measured in docs/notes/packings-speed.md, "What made the shear faster")."""

SLIP_BAND = 1e-3
"""A contact that the cap held at a commit is sliding while its history lies within this
fraction of t* of the cap (a problem started from a state: every contact within it), and it
sticks again when its uncapped history falls further inside [1]. The re-solve after a
commit leaves sliding contacts slightly inside the cap (up to 1.8e-4 t* seen: 24 disks,
mu = 0.3), and a smaller band fired a stick event, then a slip event, at the start of every
step they slid through (64 disks at mu = 0.3 advanced 1e-12 in strain per step). Within the
band the smoothed law's force is within 2 b^2 = 2e-6 of mu F_n (it peaks at the cap); the
linear law's within b."""

LINEAR_SOLVER = LinearSolver("MMD_AT_PLUS_A")
"""How a shear's bordered systems are solved (ShearParams.linear_solver): SuperLU's LU ordered
by minimum degree on the pattern of A + A^T (the contact network's Jacobian is structurally
symmetric), with partial pivoting: about half the fill of its default ordering (COLAMD) on the
corrector's matrices (docs/notes/packings-speed.md, "What made the shear faster")."""


class NotJammed(OneLineError):
    """Every disk of the packing is loose: there is no contact network to shear. reason: why,
    as words; where: the state, as the sentence's subject (the state a problem starts from:
    "the packing")."""

    def __init__(self, reason: str, where: str = "the packing"):
        super().__init__(f"{where} is not jammed ({reason}): there is no contact network to "
                         "shear")
        self.reason, self.where = reason, where


class MissedContact(RuntimeError):
    """A pair that was no contact row overlaps after a step: the step was longer than REACH."""


@dataclass(frozen=True)
class Gauge:
    """The gauge of one committed state: the reference disk, the loose disks, the equation rows
    replaced by gauge rows, the kept dofs of the tracked matrix and its reduction P."""

    ref: int
    loose: np.ndarray  # bool (N,)
    rows: np.ndarray  # equation rows replaced by kappa (q - q_c) = 0
    kept: np.ndarray  # dofs of A_red
    P: sp.csr_array  # (kept, n): q -> coordinates relative to the reference disk

    @classmethod
    def of(cls, N: int, holding: np.ndarray, frictional: bool = True) -> "Gauge":
        """The gauge of N disks whose contacts (i, j) in `holding` hold them (delta >
        delta_hold): loose are the disks with fewer than LOOSE_BELOW holding contacts with
        disks that are not loose, found by removing such disks until none is left (a contact
        with a loose disk carries no force, so it holds nothing); the reference disk has the
        most holding contacts. Without tangential forces (not `frictional`) every rotation is a
        gauge row too."""
        loose = np.zeros(N, bool)
        while True:
            kept = holding[~(loose[holding[:, 0]] | loose[holding[:, 1]])]
            counts = np.bincount(kept.ravel(), minlength=N)
            if not (~loose & (counts < LOOSE_BELOW)).any():
                break
            loose |= counts < LOOSE_BELOW
        if loose.all():
            raise NotJammed(f"every disk is loose: none has {LOOSE_BELOW} contacts holding it")
        ref = int(np.argmax(counts))
        loose_dofs = (np.arange(D)[:, None] * N + np.flatnonzero(loose)[None, :]).ravel()
        rotations = np.arange(2 * N, D * N) if not frictional else np.zeros(0, int)
        rows = np.union1d(np.union1d([ref, N + ref], loose_dofs), rotations)
        kept = np.setdiff1d(np.arange(D * N), rows)
        coupling = np.where(kept < N, ref, np.where(kept < 2 * N, N + ref, -1))
        r = np.arange(kept.size)
        data = np.concatenate([np.ones(kept.size), -np.ones(int((coupling >= 0).sum()))])
        P = sp.csr_array((data, (np.concatenate([r, r[coupling >= 0]]),
                                 np.concatenate([kept, coupling[coupling >= 0]]))),
                         shape=(kept.size, D * N))
        return cls(ref, loose, rows, kept, P)


class PackingEquilibria(Equilibria):
    """The continuation problem of a packing's Network in the strain (module docstring)."""

    def __init__(self, network: Network, q: np.ndarray, xi: np.ndarray, rows: np.ndarray,
                 gamma: float, mass: np.ndarray, matrix: str = "M^-1 J",
                 newton_tol: float = 1e-11):
        self.network, self.mass = network, mass
        self.matrix = Matrix(matrix)
        self.newton_tol = newton_tol
        self.reach = REACH * network.constants[0]
        delta = network.overlaps(q, rows, gamma)
        if not (delta > 0).any():
            raise NotJammed("no two disks overlap")
        self.delta_hold = LOOSE_OVERLAP * float(np.median(delta[delta > 0]))
        self._kept: dict = {}
        self._fixed = None
        self._set_committed(q, xi, rows, gamma)

    # -- the committed state
    def _set_committed(self, q, xi, rows, gamma, sliding=None) -> None:
        """Commit (q, xi, rows, gamma). sliding: the rows capped at this commit or sliding at the
        last one (a contact approaching its cap from inside is not sliding), or None where the
        state is all there is (a start): every row within the band of its cap."""
        self.q_c, self.xi_c, self.rows_c, self.p_c = q.copy(), xi.copy(), rows, float(gamma)
        delta = self.network.overlaps(q, rows, gamma)
        self.gauge = Gauge.of(self.network.N, rows[delta > self.delta_hold, :2],
                              self.network.frictional)
        on_loose = self.gauge.loose[rows[:, 0]] | self.gauge.loose[rows[:, 1]]
        self.active = ~on_loose  # rows whose forces act; the others are watched
        t_star = self.coulomb_limit(delta)
        near = (delta > 0) & (t_star - np.abs(xi) <= SLIP_BAND * t_star) & self.network.frictional
        self.sliding = near if sliding is None else near & sliding
        self._band = np.where(self.sliding, SLIP_BAND * t_star, 0.0)
        scale = np.median(delta[delta > 0]) if (delta > 0).any() else self.network.constants[0]
        self.kappa = float(self.network.kernels.normal_stiffness(scale, self.network.constants[1]))
        self.gauge_rows = GaugeRows.diagonal(self.gauge.rows, self.kappa)
        self._forget_trial()
        self._maps = None
        self._key = _digest((self.q_c, self.xi_c, self.rows_c, self.p_c, self.sliding))
        self._keep(self._key)

    @property
    def gamma_c(self) -> float:
        """The committed strain."""
        return self.p_c

    def _keep(self, key: bytes) -> None:
        """Remember the committed state's derived part under its snapshot's digest (the most
        recent KEPT_STATES): the continuation restores the states of pending steps (to record a
        point, or after a failed scan), and assembling one anew costs as much as a few
        corrector steps."""
        self._kept[key] = tuple(getattr(self, name) for name in _DERIVED)
        while len(self._kept) > KEPT_STATES:
            del self._kept[next(iter(self._kept))]

    @property
    def maps(self) -> StateMaps:
        """The committed state's matrices as fixed linear maps of J's values (assembly.py),
        assembled at their first use after the state is set: a state restored only to record a
        point (arclength._record) needs none."""
        if self._maps is None:
            fixed = self._gauge_maps()
            pattern = self.network.jacobian_pattern(self.rows_c[self.active])
            self._maps = state_maps(pattern, fixed, self.gauge, self.network.N, self.kappa,
                                    lambda: self._evaluate(self.q_c, self.p_c)[1])
            if self._key in self._kept:
                self._kept[self._key] = tuple(getattr(self, name) for name in _DERIVED)
        return self._maps

    def _gauge_maps(self) -> GaugeMaps:
        """GaugeMaps of the committed gauge, kept for the last one (it changes only where a
        disk turns loose or the reference disk changes)."""
        key = (self.gauge.ref, self.gauge.loose.tobytes())
        if self._fixed is None or self._fixed[0] != key:
            self._fixed = (key, GaugeMaps.of(self.gauge, self.network.N, self.mass, self.matrix))
        return self._fixed[1]

    def coulomb_limit(self, delta: np.ndarray) -> np.ndarray:
        """t* of every row at overlaps delta (0 where open) [length]."""
        return self.network.kernels.coulomb_limit(np.maximum(delta, 0.0),
                                                  *self.network.constants[1:])

    def trial(self, q, gamma, cap: bool = True) -> tuple[np.ndarray, np.ndarray]:
        """History of every row at (q, gamma), reached by a straight step from the committed
        state, and the rows the cap acted on."""
        return self.network.history_step(self.q_c, q, self.p_c, gamma, self.xi_c,
                                         self.rows_c, cap=cap)

    def _evaluate(self, q, gamma):
        """(F, J's values on its pattern, dF/dgamma) of the active rows at the trial (q, gamma),
        kept for the last one."""
        def evaluated():
            xi = self.trial(q, gamma)[0]
            return self.network.evaluate_values(q, xi[self.active], self.rows_c[self.active], gamma)
        return self._at_trial(q, gamma, "F, J, dF/dgamma", evaluated)

    # -- Problem protocol
    def residual(self, q, gamma):
        """The network's forces, the gauge rows kappa (q - q_c) in place of theirs."""
        return self._gauged(self._evaluate(q, gamma)[0].copy(), q)

    def jacobian(self, q, gamma):
        """dG/dq = -J with the gauge rows (sparse)."""
        return self.maps.dG_dq(self._evaluate(q, gamma)[1])

    def dG_dp(self, q, gamma):
        F_gamma = self._evaluate(q, gamma)[2].copy()
        F_gamma[self.gauge.rows] = 0.0
        return F_gamma

    def physical(self, q, gamma):
        """The network's J or M^-1 J at (q, gamma), sparse (loose disks' rows and columns 0)."""
        n = self.network.ndof
        J = sp.csr_array((self._evaluate(q, gamma)[1], self.maps.pattern), shape=(n, n))
        return J if self.matrix is Matrix.J else sp.diags_array(1.0 / self.mass) @ J

    def reduced(self, q, gamma) -> sp.csr_array:
        """A_red = P A E: the tracked spectrum without the translations and the loose disks."""
        return self.maps.reduced(self._evaluate(q, gamma)[1])

    def stability_matrix(self, q, gamma) -> sp.csr_array:
        """A_g (sparse): A_red at the kept dofs, the committed state's PARKED constant on the
        gauge rows' diagonal, zeros elsewhere (module docstring)."""
        return self.maps.stability(self._evaluate(q, gamma)[1])

    def stability_structure(self, q, gamma) -> NetworkMatrix:
        """A_g with its structure (NetworkMatrix): the coupled part A_red on the kept dofs, the
        gauge rows' zero modes, the deflation and, without tangential forces, the symmetric
        form."""
        return NetworkMatrix(self, q, gamma)

    def acting_overlaps(self, x) -> np.ndarray:
        """The overlaps of the active rows at x = (q, gamma)."""
        return self.network.overlaps(x[:-1], self.rows_c[self.active], float(x[-1]))

    def event_functions(self, q, gamma):
        """Per active row: delta (a contact of the network opening or closing), delta -
        delta_hold (a contact starting or ending to hold its disks: a disk turning loose), then
        the Coulomb margin t* - |xi| of the uncapped history (a contact reaching its limit;
        SLIP_BAND inside it for one sliding at the committed state: sticking again), where
        delta > 0; where delta <= 0 the margin keeps the sign the row had at the commit
        (opening is delta's event: no second event there). 1 for the watched rows, whose
        contacts carry no force (a loose disk joins or gives way at the commit:
        _release_pushed), and for every margin without tangential forces (no Coulomb limit)."""
        delta = self.network.overlaps(q, self.rows_c, gamma)
        xi = self.trial(q, gamma, cap=False)[0]
        t_star = self.coulomb_limit(delta)
        margin = np.where(delta > 0, t_star - np.abs(xi) - self._band,
                          np.where(self.sliding, -1.0, 1.0))
        return np.concatenate([np.where(self.active, delta, 1.0),
                               np.where(self.active, delta - self.delta_hold, 1.0),
                               np.where(self.active & self.network.frictional, margin, 1.0)])

    def root_events(self) -> np.ndarray:
        """The overlaps delta among the event functions (event_functions' first block): a
        Hertz contact's stiffness goes as delta^(1/2) where it opens or forms."""
        m = self.rows_c.shape[0]
        return np.concatenate([np.ones(m, bool), np.zeros(2 * m, bool)])

    def state(self) -> tuple:
        return self.q_c.copy(), self.xi_c.copy(), self.rows_c.copy(), self.p_c, self.sliding

    def restore(self, snapshot: tuple) -> None:
        """Back to a state() snapshot: its derived part (gauge, matrices' assemblies) from the
        last few states set (KEPT_STATES), else computed again."""
        key = _digest(snapshot)
        kept = self._kept.pop(key, None)
        if kept is None:
            self._set_committed(*snapshot)
            return
        q, xi, rows, gamma, _ = snapshot
        self.q_c, self.xi_c, self.rows_c, self.p_c = q.copy(), xi.copy(), rows, float(gamma)
        for name, value in zip(_DERIVED, kept):
            setattr(self, name, value)
        self._forget_trial()
        self._key = key
        self._keep(key)

    def commit(self, q_old, gamma_old, q_new, gamma_new) -> bool:
        """Commit at (q_new, gamma_new): the rows found again (histories carried by row), the
        loose disks pushed into given way (_release_pushed), then the gauge. True (re-solve
        there) when the cap acted, a loose disk moved or the loose disks changed.
        MissedContact if a pair that was no row overlaps; NotJammed where every disk turned
        loose (a packing near jamming can unjam under shear at fixed area)."""
        xi, slid = self.trial(q_new, gamma_new)
        rows = self.network.contacts(q_new, gamma_new, self.reach)
        xi_rows = carried(self.rows_c, xi, rows)
        fresh = ~np.isin(row_keys(rows), row_keys(self.rows_c))
        if fresh.any() and (self.network.overlaps(q_new, rows[fresh], gamma_new) > 0).any():
            raise MissedContact(f"a pair closed within one step at gamma = {gamma_new:.12g} "
                                f"without being a contact row: the step was longer than the "
                                f"reach {self.reach:g}")
        loose, capped = self.gauge.loose, bool(slid[self.active].any())  # watched rows carry no force
        xi_rows[loose[rows[:, 0]] | loose[rows[:, 1]]] = 0.0  # nor any history: a disk joins afresh
        moved = self._release_pushed(q_new, rows, gamma_new)
        sliding = carried(self.rows_c, (slid | self.sliding) & self.active, rows) > 0
        try:
            self._set_committed(q_new if moved is None else moved, xi_rows, rows, gamma_new, sliding)
        except NotJammed as error:  # the shear unloaded every contact: the packing unjammed
            raise NotJammed(error.reason, f"sheared to gamma = {gamma_new:.9g}, the packing") from None
        return capped or moved is not None or not np.array_equal(loose, self.gauge.loose)

    def resolve_start(self, u_new: np.ndarray) -> np.ndarray:
        """The committed q: u_new with the loose disks that gave way at the commit moved
        (_release_pushed). The network's equations hold there as they did at u_new, so the
        core's re-solve takes no update and the stability matrix is the same (arclength._moved);
        from u_new, Newton moved the whole packing by about 1e-12 to put the loose disks back."""
        return self.q_c.copy()

    def _release_pushed(self, q: np.ndarray, rows: np.ndarray, gamma: float) -> np.ndarray | None:
        """A loose disk (of the committed gauge) that a neighbour pushes into (a contact with
        delta > delta_hold among `rows` at gamma) carries no load, so it gives way
        (_give_way). A loose disk moved into another pushes it in turn: passes over the pushed
        loose disks are repeated while one of them moved (at most RELEASE_PASSES), so that a
        push travels along a chain of loose disks. Only a disk caught between
        contacts whose normal forces balance stays where two of them hold it, and joins the
        network at this commit if both are with disks of the network (Gauge.of; a disk held by
        two contacts that do not face each other would escape as soon as the equations hold it:
        no equilibrium near, a failed commit). Returns the moved q, or None."""
        loose = np.flatnonzero(self.gauge.loose)
        moved = None
        for _ in range(RELEASE_PASSES):
            pushed = self.network.overlaps(q, rows, gamma) > self.delta_hold
            disks = [d for d in loose if pushed[(rows[:, 0] == d) | (rows[:, 1] == d)].any()]
            if not disks:
                break
            before, q = q, q.copy()
            for d in disks:
                q = self._give_way(q, d, rows[(rows[:, 0] == d) | (rows[:, 1] == d)], gamma)
            moved = q
            if np.abs(q - before).max() <= 1e-3 * self.delta_hold:
                break
        return moved

    def _give_way(self, q: np.ndarray, d: int, mine: np.ndarray, gamma: float) -> np.ndarray:
        """q with loose disk d moved by Newton steps along the net normal force of its rows
        `mine`, its neighbours fixed, until no contact of it holds it (or the forces balance),
        and RELEASE_GAP further when nothing is in the way (q is changed in place)."""
        N, k_n = self.network.N, self.network.constants[1]
        start = np.array([q[d], q[N + d]])
        for _ in range(60):
            dl = self.network.overlaps(q, mine, gamma)
            touching = dl > 0
            if not touching.any():
                break
            F = self.network.forces(q, np.zeros(len(mine)), mine, gamma)
            k = float(np.sum(self.network.kernels.normal_stiffness(dl[touching], k_n)))
            step = np.array([F[d], F[N + d]]) / k
            if np.abs(step).max() <= 1e-3 * self.delta_hold:
                break
            q[d] += step[0]
            q[N + d] += step[1]
        away = np.array([q[d], q[N + d]]) - start
        if np.any(away) and (self.network.overlaps(q, mine, gamma) <= self.delta_hold).all():
            trial = q.copy()  # give way a little further, if nothing is in the way
            gap = RELEASE_GAP * self.network.constants[0]
            trial[[d, N + d]] += gap * away / np.linalg.norm(away)
            if (self.network.overlaps(trial, mine, gamma) < 0).all():
                q = trial
        return q


KEPT_STATES = 6
"""Committed states whose derived part PackingEquilibria keeps for restore."""
_DERIVED = ("gauge", "active", "sliding", "_band", "kappa", "gauge_rows", "_maps")
"""What _set_committed derives from a state (q, xi, rows, gamma, sliding)."""


def _digest(snapshot: tuple) -> bytes:
    """A key of a state() snapshot (q, xi, rows, gamma, sliding): the hash of its bytes."""
    q, xi, rows, gamma, sliding = snapshot
    h = hashlib.blake2b(digest_size=16)
    for part in (q, xi, rows, np.float64(gamma), sliding):
        h.update(np.ascontiguousarray(part).tobytes())
    return h.digest()


def row_keys(rows: np.ndarray) -> np.ndarray:
    """One integer per contact row (i, j, cx, cy), images within +-2^15."""
    shifted = rows[:, 2:] + 2**15
    return ((rows[:, 0] * 2**20 + rows[:, 1]) * 2**16 + shifted[:, 0]) * 2**16 + shifted[:, 1]


def carried(old_rows: np.ndarray, xi: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The history of each of `rows` taken from the same row among `old_rows` (0 for a new
    one)."""
    old = dict(zip(row_keys(old_rows).tolist(), xi.tolist()))
    return np.array([old.get(k, 0.0) for k in row_keys(rows).tolist()])


def start(network: Network, positions: np.ndarray, gamma: float = 0.0
          ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(q, xi, rows) of a prepared packing's positions (N, 2) with friction switched on: angles
    0, every history 0."""
    N = network.N
    q = np.concatenate([positions[:, 0], positions[:, 1], np.zeros(N)])
    rows = network.contacts(q, gamma, REACH * network.constants[0])
    return q, np.zeros(rows.shape[0]), rows


def mass_diagonal(network: Network, m: float, inertia: float) -> np.ndarray:
    """diag(M): m_i = m (R_i / R)^2 for x and y (one density), I_i = c m_i R_i^2 for theta."""
    R = network.constants[0]
    m_i = m * (network.radii / R) ** 2
    return np.concatenate([m_i, m_i, inertia * m_i * network.radii**2])


def largest_force(problem: PackingEquilibria, q: np.ndarray, gamma: float) -> float:
    """max |F| over every equation of the network's disks, the reference disk's included (the
    loose disks' excluded) at (q, gamma) [force]."""
    F = problem._evaluate(q, gamma)[0].copy()
    loose = np.flatnonzero(problem.gauge.loose)
    F[(np.arange(D)[:, None] * problem.network.N + loose[None, :]).ravel()] = 0.0
    return float(np.abs(F).max())
