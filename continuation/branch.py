"""The result of a continuation: one record of arrays, one row per accepted point, with the
pieces it is made of and its labelled points, for every problem (Branch); its columns from a
record hook (Record); the recorder that builds a run's branch (BranchRecorder)."""
from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from enum import StrEnum
from typing import Any, Callable, Mapping, Optional, Sequence, Union

import numpy as np

from diskfriction.continuation.detection.detectors import Collision
from diskfriction.continuation.stepping.newton import NewtonResult
from diskfriction.continuation.detection.samples import Sample, continued_labels
from diskfriction.continuation.spectra.tracking import condition_numbers, count_complex_pairs

Array = np.ndarray


class StopCode(StrEnum):
    """Why a run stopped (arclength.py): it reached the end of the span it heads for, the
    branch folded and left the span on its starting side, the step limit, a step that had to
    shrink below ds_min, a commit (Problem.commit) after which no equilibrium was found,
    (with stop_at_fold) a step that would have turned p back, or a spectral window that no
    longer holds every eigenvalue its guard bands reach (spectra.window.WindowCrowded: the
    branch ends at the last point whose step was certified; a caller may size the window
    anew there and go on)."""

    REACHED = "p_end"
    TURNED_BACK = "turned back"
    MAX_STEPS = "max_steps"
    DS_MIN = "ds_min"
    COMMIT = "commit"
    FOLD = "fold"
    WINDOW = "window"


MESSAGES = {
    StopCode.REACHED: "p_end",
    StopCode.MAX_STEPS: "max_steps",
    StopCode.DS_MIN: "ds_min: {reason} at p={p:.12g}",
    StopCode.COMMIT: "commit: {reason} at p={p:.12g}",
    StopCode.TURNED_BACK: "turned back: {reason} at p={p:.12g}",
    StopCode.FOLD: "fold: {reason} at p={p:.12g}",
    StopCode.WINDOW: "window: {reason} at p={p:.12g}",
}
"""The status line of each code (str(Stop)): the text Branch.status had before it was a Stop."""


@dataclass(frozen=True)
class Stop:
    """Why a run stopped: code; reason, what failed or happened, as words (e.g. "corrector
    failed (residual 1.6e-11)"; empty for REACHED and MAX_STEPS); p, where (None for REACHED
    and MAX_STEPS). str() is its status line (MESSAGES)."""

    code: StopCode
    reason: str = ""
    p: Optional[float] = None

    def __str__(self) -> str:
        return MESSAGES[self.code].format(reason=self.reason, p=self.p)

    @property
    def reached(self) -> bool:
        """Whether the run reached the end of the span it heads for."""
        return self.code is StopCode.REACHED

    def sentence(self, points: int) -> str:
        """The stop for a sentence, without its location: "reached", "the run stopped after
        {points} points" (points: the run's accepted points), else the reason."""
        if self.code is StopCode.REACHED:
            return "reached"
        if self.code is StopCode.MAX_STEPS:
            return f"the run stopped after {points} points"
        return self.reason


Column = Union[Array, tuple]
"""A per-point column of a Branch: an array whose first axis runs over the points, where every
point's value has one shape, else a tuple of the points' arrays (ragged: a packing's contact
rows)."""


def column_of(values: Sequence, ragged: bool = False) -> Column:
    """The points' values as one Column: stacked (np.array) where they share a shape, else,
    or where asked (ragged: a column whose shape varies from point to point, kept as tuples
    whatever the points at hand), a tuple of arrays."""
    if ragged or len({np.shape(v) for v in values}) > 1:
        return tuple(np.asarray(v) for v in values)
    return np.array(values)


def columns_of(records: Sequence[Mapping[str, Any]]) -> dict[str, Column]:
    """The columns of a branch's points from each point's record {name: value} (a record hook's,
    Record): one Column per name, in the first record's order."""
    if not records:
        return {}
    return {name: column_of([r[name] for r in records]) for name in records[0]}


Record = Callable[[float, Array], Mapping[str, Any]]
"""A record hook, record(p, u) -> {name: value}: what a branch stores of each accepted point
besides p, u and the spectrum, called with the problem in the state committed at the point (as
BifurcationKit's record_from_solution): a chain's committed histories xi and free rolling modes,
a packing's contact rows, stress and contacts. Every point's record has the same names; the
Branch stacks them into its columns (recorded). A record's "residual", where it gives one, is
the point's residual in place of the corrector's max|G| (a chain's and a packing's: max|F|
over the disks with the committed history)."""


@dataclass(frozen=True)
class Piece:
    """A stretch of a branch, its rows start:stop (start inclusive, stop exclusive).

    kind: what stretch, "leg" (a chain's sweep: 0 the preparation from rest, 1 the requested
    sweep), "segment" (a packing's shear between two plastic events: 0, 1, ...) or "run" (a
    stretch with one size of spectral window: a window that crowded is sized anew, wider, at
    the last certified point and its columns start anew there); label: its number among the
    pieces of its kind; status: how it ended (a Stop). The pieces of one kind partition the
    branch's rows in order: a piece that goes on from the one before starts at its first own
    point (the shared point is the one before's last)."""

    kind: str
    label: int
    start: int
    stop: int
    status: Stop


@dataclass(frozen=True)
class EventPoint:
    """A point of a branch where a step was cut at an event of the problem
    (Problem.event_functions: for the disks, a contact opening or closing, starting or ending
    to hold its disk, reaching its Coulomb cap or sticking again): p there, and its row."""

    p: float
    row: int


@dataclass(frozen=True)
class Branch:
    """Accepted points k = 0..m-1 of a branch G(u, p) = 0: one record for every problem (a run
    of the core, a chain's sweep in F_x, a packing's shear in gamma, a problem file's).

    Per point: p (m,) [units]; u (m, n) the state; eigenvalues (m, n_A) complex, tracked: column
    i is one eigenvalue followed along the branch (with a spectral window, one column per
    eigenvalue that passed through the window or its guard bands: window.block_columns, nan
    where it was not tracked); n_complex (m,): complex pairs (tracking.count_complex_pairs; in the
    window, with one); residual (m,): max|G| at the stored point (a model may record its own:
    a chain's or a packing's max|F| over the disks); condition (m, n_A): each tracked
    eigenvalue's condition number |l| |r| / |l^H r| (tracking.condition_numbers; nan where the
    point's sample holds no vectors: exhaustive detection, no spectra, a free disk's mode);
    columns: {name: Column} from a record hook (Record: a chain's xi, free; a packing's rows,
    xi, contacts, loose, stress).
    The core's run also keeps, per point (None on a branch joined from runs): ds (m,) the
    arclength step that reached it (0 for the first); newton_iterations (m,) corrector
    updates; tangent (m, n+1) the unit tangent in x = (u, p); detection_solves (m,) corrector
    solves spent on collision detection in the step ending at it; continued (m, n_A) bool, with
    a spectral window only: label i at point k is certified to hold the eigenvalue it held at
    point k - 1 (False at k = 0; samples.continued_labels).
    Pieces: the stretches it is made of (Piece: a chain's legs, a packing's segments, the runs
    of a widened window); () for a branch of one piece.
    Labelled points, in branch order: collisions (Collision: the located births and deaths of
    complex pairs; with a window, those with the double eigenvalue in it; step, the row that
    starts the step holding it), and labelled {label: records with a location p or gamma}:
    "event", the points where a step was cut at an event of the problem (EventPoint: for the
    disks a contact event), a packing's "plastic" events (models/packing/plastic.PlasticEvent),
    a problem's "fold", "branch" and "hopf" points (bifurcations.SpecialPoint); events: how
    many steps were cut at an event (one per "event" point, and a last step whose commit found
    no equilibrium).
    The run: status, why it stopped (a Stop; a joined branch's last piece's); warnings; window
    (lo, hi) of Re lambda tracked, or None (every eigenvalue); widenings: how often the window
    crowded and was sized anew.
    Names: parameter, the name of p ("F_x", "gamma", or a problem's own), units its units (""
    for none); state, the name of u ("q" for the disks); matrix, the tracked matrix's name
    ("J", "M^-1 J", a problem's own), eigenvalue_units its eigenvalues' units. Besides its
    fields a branch answers, as attributes, its parameter's and state's names (branch.F_x is
    branch.p on a chain), each column (branch.xi), each label of labelled points
    (branch.plastic) and each kind of piece, as the label of the piece of that kind holding
    each point (branch.leg, branch.segment: int (m,), -1 where none does).
    """

    p: Array
    u: Array
    eigenvalues: Array
    n_complex: Array
    residual: Array
    collisions: tuple[Collision, ...]
    status: Stop
    condition: Optional[Array] = None
    columns: Mapping[str, Column] = field(default_factory=dict)
    pieces: tuple[Piece, ...] = ()
    labelled: Mapping[str, tuple] = field(default_factory=dict)
    events: int = 0
    warnings: tuple[str, ...] = ()
    window: Optional[tuple[float, float]] = None
    widenings: int = 0
    parameter: str = "p"
    units: str = ""
    state: str = "u"
    matrix: str = ""
    eigenvalue_units: str = ""
    ds: Optional[Array] = None
    newton_iterations: Optional[Array] = None
    tangent: Optional[Array] = None
    detection_solves: Optional[Array] = None
    continued: Optional[Array] = None

    def __post_init__(self):
        names = [*self.columns, *self.labelled, *{piece.kind for piece in self.pieces}]
        names += [name for name, own in ((self.parameter, "p"), (self.state, "u")) if name != own]
        taken = [n for n in names if n in _FIELDS or names.count(n) > 1]
        if taken:
            raise ValueError(f"a branch's names must differ from each other and from its fields: "
                             f"{sorted(set(taken))}")

    def __len__(self) -> int:
        return self.p.size

    def __getattr__(self, name: str):
        """The parameter and state by their names, a column, labelled points or the labels of
        a kind of piece (class docstring)."""
        fields = self.__dict__
        if name.startswith("__") or name in _FIELDS or "columns" not in fields:
            raise AttributeError(name)  # not set yet (a copy or an unpickling in progress)
        if name == fields["parameter"]:
            return self.p
        if name == fields["state"]:
            return self.u
        for found in (fields["columns"], fields["labelled"]):
            if name in found:
                return found[name]
        if any(piece.kind == name for piece in fields["pieces"]):
            return self.labels(name)
        raise AttributeError(f"this branch has no field, column, labelled points or pieces "
                             f"named {name!r}")

    @property
    def x(self) -> Array:
        """Rows (u, p), shape (m, n+1)."""
        return np.column_stack([self.u, self.p])

    def of_kind(self, kind: str) -> tuple[Piece, ...]:
        """The pieces of one kind, in order."""
        return tuple(piece for piece in self.pieces if piece.kind == kind)

    def labels(self, kind: str) -> Array:
        """int (m,): the label of the piece of `kind` holding each point (-1 where none does)."""
        out = np.full(len(self), -1, dtype=np.int64)
        for piece in self.of_kind(kind):
            out[piece.start:piece.stop] = piece.label
        return out

    def holding(self, row: int) -> Array:
        """The rows of every piece that holds `row`, intersected: a point's leg, segment and
        run (all rows for a branch of one piece)."""
        on = np.ones(len(self), bool)
        for piece in self.pieces:
            if piece.start <= row < piece.stop:
                on[:piece.start] = on[piece.stop:] = False
        return np.flatnonzero(on)


_FIELDS = frozenset(f.name for f in fields(Branch))


def recorded(branch: Branch, records: Sequence[Mapping[str, Any]]) -> Branch:
    """The branch with its points' records (a Record's, one per point, in order) as its
    columns (columns_of), a record's "residual" as its residual; the branch itself for none."""
    if not records:
        return branch
    columns = columns_of(records)
    residual = columns.pop("residual", branch.residual)
    return replace(branch, columns=columns, residual=residual)


class JoinedRuns:
    """The rows of runs (branches of solve_in_runs, a model's legs or segments) joined into one
    branch, in order: the per-point lists, the columns, each row's block (its run's number,
    for a windowed branch's block_columns), {block: its rows' Branch.continued}, the
    collisions and event points with their rows renumbered, and the count of events."""

    def __init__(self) -> None:
        self.p, self.u, self.residual, self.eigenvalues, self.condition = [], [], [], [], []
        self.columns: dict[str, list] = {}
        self.blocks: list[int] = []
        self.continued: dict[int, list] = {}
        self.collisions: list = []
        self.event_points: list[EventPoint] = []
        self.events = 0

    def __len__(self) -> int:
        return len(self.p)

    def add(self, run: Branch, block: int, skip: int, collisions: bool = True,
            continued: bool = True) -> int:
        """Append `run`'s rows from `skip` (1 where its first point is the last one kept) as
        `block`; its collisions unless not `collisions`, its continued rows unless not
        `continued`. Returns the row offset: the run's row k is the joined row offset + k."""
        offset = len(self.p) - skip
        self.p += list(run.p[skip:])
        self.u += list(run.u[skip:])
        self.residual += list(run.residual[skip:])
        for name, column in run.columns.items():
            self.columns.setdefault(name, []).extend(column[skip:])
        self.eigenvalues += list(run.eigenvalues[skip:])
        self.condition += list(run.condition[skip:])
        self.blocks += [block] * (len(run) - skip)
        if continued:
            self.continued.setdefault(block, []).extend(run.continued[skip:])
        if collisions:
            self.collisions += [replace(c, step=offset + c.step) for c in run.collisions]
        self.event_points += [EventPoint(e.p, offset + e.row) for e in run.labelled.get("event", ())
                              if e.row >= skip]
        self.events += run.events
        return offset


class BranchRecorder:
    """Accumulates the accepted points of a run (arclength.continuation) and builds the Branch:
    rel_tol, the complex-pair threshold (tracking.count_complex_pairs); rho, the certification
    margin of a spectral window's label continuity (samples.continued_labels); callback(k, p,
    u, eigenvalues), called for every point recorded."""

    def __init__(self, rel_tol: float, rho: float, callback: Optional[Callable]):
        self.rel_tol, self.rho, self.callback = rel_tol, rho, callback
        self.rows: list[tuple] = []
        self.collisions: list = []
        self.warnings: list = []
        self.events = 0
        self.continued: list[Array] = []
        self.event_rows: list[int] = []
        self.last: Optional[Sample] = None

    @property
    def steps(self) -> int:
        return len(self.rows) - 1

    def add(self, sample: Sample, ds: float, newton: NewtonResult, t: Array, solves: int,
            tracked: Optional[Array] = None, event: bool = False) -> None:
        """Record an accepted point (with a spectral window, Branch.continued too); event: its
        step was cut at an event of the problem."""
        u, p = sample.x[:-1].copy(), float(sample.x[-1])
        kappa = (np.full(sample.eigvals.size, np.nan) if sample.system is None
                 else condition_numbers(sample.system))
        self.rows.append((p, u, sample.eigvals, count_complex_pairs(sample.eigvals, self.rel_tol),
                          ds, newton.iterations, newton.residual, t, solves, kappa))
        if event:
            self.event_rows.append(len(self.rows) - 1)
        if sample.disc is not None:
            self.continued.append(continued_labels(self.last, sample, tracked, self.rho))
            self.last = sample.without_vectors()
        if self.callback is not None:
            self.callback(len(self.rows) - 1, p, u, sample.eigvals)

    def branch(self, status: Stop) -> Branch:
        cols = list(zip(*self.rows))
        return Branch(p=np.array(cols[0]), u=np.array(cols[1]), eigenvalues=np.array(cols[2]),
                      n_complex=np.array(cols[3]), ds=np.array(cols[4]),
                      newton_iterations=np.array(cols[5]), residual=np.array(cols[6]),
                      tangent=np.array(cols[7]), detection_solves=np.array(cols[8]),
                      collisions=tuple(self.collisions), status=status, warnings=tuple(self.warnings),
                      labelled={"event": tuple(EventPoint(float(cols[0][k]), k) for k in self.event_rows)},
                      events=self.events, continued=np.array(self.continued) if self.continued else None,
                      condition=np.array(cols[9]))
