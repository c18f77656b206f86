"""A spectral window: the eigenvalues near a band of real parts, by sparse shift-invert, when a
full dense spectrum (O(n^3)) is too expensive (a chain of 1000 disks: n = 3000). The
eigensolver SpectralWindow(lo, hi) (eigensolvers.py) holds the window and its size k.

The window W = [lo, hi] of Re lambda is tracked with a guard band of width g = GUARD (hi - lo)
on each side. At every sample the k eigenvalues nearest sigma = (lo + hi) / 2 are computed by
shift-invert with left and right vectors (nearest.py: one sparse LU of A - sigma I serves
ARPACK on both sides, and a two-sided Rayleigh-Ritz projection pairs them). Completeness: the k
nearest eigenvalues include every eigenvalue within the distance of the farthest one; if that
distance does not exceed the reach of the guard bands (the farthest corner of the rectangle
of Re lambda in [lo - g, hi + g] and |Im lambda| up to the largest |Im| seen there:
SpectralWindow.reach), some eigenvalue of the band may be missing and WindowCrowded is raised
(choose a narrower window, or size it anew: SpectralWindow.widened). A pair that comes down
into the band from a larger |Im| enters the disc where its own |Im| puts it within the new
reach: the window crowds and is sized anew. The k eigenvalues keep their labels along the
branch like a full spectrum's; those beyond the guard band are `excluded`, those in the guard
band are `guard`: an eigenvalue joins or leaves the tracked set only through the guard band
(verdicts._enters_past_guard). The detection certifies pairs, and locates collisions, only in
the certified band, W widened by CERTIFIED of the guard band on each side
(SpectralWindow.certified): an eigenvalue beyond it at both ends of an interval on the same
side (verdicts.beyond_band) takes part in no certificate and none of its collisions is
located while the cubic model of its real part stays beyond the band between the samples, for
its value at any collision inside the interval lies outside W (the assumption the guard band
rests on: an eigenvalue does not stray CERTIFIED of the guard band off its model between two
samples). A collision is reported when its double eigenvalue lies in W (models/chain/sweep.py,
models/packing/shear.py); the certificate covers exactly the window.

The set of the k nearest changes along the branch: an eigenvalue beyond the guard band leaves
the disc and another enters it. Labels are matched so that every eigenvalue present at both
samples keeps its label and the label of one that left takes one that entered
(labels.window_match). Such a label then holds another eigenvalue, so the stored spectrum
is not the labels but columns (window_columns): a label continues its column from one
accepted point to the next only where it is certified to hold the same eigenvalue (it stayed
in the tracked set throughout the step, where the detection certified its continuity, or
the label test certifies the step: samples.certified_labels, with gaps no larger than the
distance to the edge of the disc, beyond which eigenvalues are unknown); else it starts a new
column. A column holds its eigenvalue while it is in W or its guard bands, nan elsewhere.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from diskfriction.continuation.linalg.solves import Matrix, book
from diskfriction.continuation.spectra.eigensolvers import Eigensolver
from diskfriction.continuation.spectra.nearest import nearest_eigensystem, nearest_values
from diskfriction.continuation.spectra.structure import on_blocks
from diskfriction.continuation.spectra.tracking import Eigensystem

Array = np.ndarray

GUARD = 0.15
"""Width of each guard band, as a fraction of the window's width: the band an eigenvalue
crosses to join or leave the tracked set (module docstring)."""

MARGIN = 1.5
"""A window's k is sized at the start of a run as MARGIN times the eigenvalues within reach,
plus EXTRA (SpectralWindow's margin and extra, by default)."""
EXTRA = 8
CERTIFIED = 0.5
"""The certified band: W widened by this fraction of the guard band on each side (module
docstring). The outer rest of the guard band is watched, not certified: certifying all of it
would locate collisions beyond W that are not reported."""
WIDENING = 1.5
"""Where a window crowds, a caller may size it anew (widened) with k at least this factor
times the old k."""
BLOCK_SHARE = 0.999
"""A window's mode with more than this share of its right vector's norm^2 on a decoupled
block's coordinates is that block's own: excluded (SpectralWindow.eigensystem)."""
WIDENINGS = 3
"""A caller that widens a crowded window and goes on from the last certified point gives up
after this many widenings in a row that reach no further point (StopCode.WINDOW)."""


class WindowCrowded(RuntimeError):
    """More eigenvalues reach the window and its guard bands than the k tracked."""


@dataclass(frozen=True)
class SpectralWindow(Eigensolver):
    """The eigensolver of a spectral window (module docstring). lo, hi: the band of Re lambda
    tracked [the stability matrix's units]; k: the number of eigenvalues computed (0: sized at
    the run's start, prepared); margin, extra: k is sized as margin times the eigenvalues
    within reach, plus extra (sized)."""

    lo: float
    hi: float
    k: int = 0
    margin: float = MARGIN
    extra: int = EXTRA

    dense = False

    def __post_init__(self):
        if not self.lo < self.hi:
            raise ValueError(f"window needs lo < hi, got {self.lo}, {self.hi}")

    def eigensystem(self, problem, u, p, vectors=False) -> Eigensystem:
        """The k eigenvalues of A(u, p) nearest the window's centre (window_eigensystem): of
        its coupled part where the structure gives one, without vectors; of A with vectors
        (shift-inverting the structure's deflation), the modes of decoupled blocks excluded;
        real where the structure has a symmetric form. Raises WindowCrowded."""
        structure = problem.stability_structure(u, p)
        if not vectors:
            found = window_eigensystem(structure.shifted(), self, False)
        else:
            found = window_eigensystem(structure.matrix, self, True, structure.deflated)
            if structure.decoupled is not None and found.right is not None:
                found = replace(found, excluded=found.excluded | on_blocks(found, structure.decoupled, BLOCK_SHARE))
        if structure.symmetric is not None:  # a real spectrum: the imaginary parts are rounding
            found = replace(found, values=found.values.real + 0j)
        return found

    def prepared(self, problem, u, p) -> "SpectralWindow":
        """The window sized at (u, p) where its k is 0 (sized), else itself."""
        if self.k:
            return self
        return sized(self, problem.stability_structure(u, p).shifted(), self.margin, self.extra)

    def widened(self, problem, u, p) -> "SpectralWindow":
        """The window sized anew at (u, p), wider (widened)."""
        return widened(self, problem.stability_structure(u, p).shifted(), self.margin, self.extra)

    @property
    def sigma(self) -> float:
        return 0.5 * (self.lo + self.hi)

    @property
    def guard(self) -> float:
        return GUARD * (self.hi - self.lo)

    def reach(self, values: Array) -> float:
        """Distance from sigma that the guard bands reach, for eigenvalues with the |Im| of
        those of `values` in them: the corner of the rectangle [lo - g, hi + g] x [-Im, Im],
        hypot((hi - lo) / 2 + g, Im) (a complex pair far outside the band says nothing of the
        band)."""
        band = values[self.tracked(values)]
        height = float(np.max(np.abs(band.imag), initial=0.0))
        return math.hypot(0.5 * (self.hi - self.lo) + self.guard, height)

    def inside(self, values: Array) -> Array:
        return (values.real >= self.lo) & (values.real <= self.hi)

    @property
    def certified(self) -> tuple[float, float]:
        """The certified band (lo, hi) of Re lambda: W widened by CERTIFIED guard bands."""
        margin = CERTIFIED * self.guard
        return self.lo - margin, self.hi + margin

    def tracked(self, values: Array) -> Array:
        """The window and its guard bands: lo - guard <= Re lambda <= hi + guard."""
        return (values.real >= self.lo - self.guard) & (values.real <= self.hi + self.guard)


def sized(window: SpectralWindow, A: Matrix, margin: float = MARGIN, extra: int = EXTRA) -> SpectralWindow:
    """The window with its k: `margin` times the eigenvalues within reach at A, plus `extra`."""
    k = extra
    n = A.shape[0]
    while True:
        values = nearest_values(A, window.sigma, min(k, n - 2))
        near = np.abs(values - window.sigma) <= window.reach(values)
        if not near.all() or k >= n - 2:
            return replace(window, k=min(n - 2, int(margin * near.sum()) + extra))
        k *= 2


def widened(window: SpectralWindow, A: Matrix, margin: float = MARGIN, extra: int = EXTRA) -> SpectralWindow:
    """The window sized anew at A (sized), with k at least WIDENING times its old k, at most
    A's size less 2 (ARPACK's limit): where it crowded, so that the run can go on."""
    k = max(sized(replace(window, k=0), A, margin, extra).k, math.ceil(WIDENING * window.k))
    return replace(window, k=min(k, A.shape[0] - 2))


def window_eigensystem(A: Matrix, window: SpectralWindow, vectors: bool, deflated=None) -> Eigensystem:
    """The window.k eigenvalues of the sparse A nearest the window's centre (module docstring),
    with normalised left and right vectors if `vectors` (shift-inverting `deflated`'s matrix
    if given: nearest.Deflated); excluded beyond the guard bands, guard within them. Raises
    WindowCrowded."""
    book("spectra")
    k, sigma = window.k, window.sigma
    if not vectors:
        values = nearest_values(A, sigma, k)
        return _classified(Eigensystem(values.astype(complex)), window)
    return _classified(nearest_eigensystem(A, sigma, k, deflated)[0], window)


def _classified(system: Eigensystem, window: SpectralWindow) -> Eigensystem:
    values = system.values
    far = np.abs(values - window.sigma).max()
    if far <= window.reach(values):
        raise WindowCrowded(f"the {window.k} eigenvalues nearest {window.sigma:.6g} all lie within "
                            f"{far:.3g} of it: the window [{window.lo:.6g}, {window.hi:.6g}] and its "
                            "guard bands may hold more; choose a narrower window")
    excluded = ~window.tracked(values)
    guard = ~excluded & ~window.inside(values)
    return Eigensystem(values, system.right, system.left, excluded, guard, disc=(window.sigma, float(far)),
                       band=window.certified)


def window_columns(values: Array, continued: Array, shown: Array) -> Array:
    """The stored spectrum of a windowed branch: values (m, k) hold the k eigenvalues of each
    point under labels continued[r, i] (Branch.continued) certifies from point r - 1 to r;
    label i starts a new column wherever it is not certified (a label that left the disc
    holds a new eigenvalue then). Returns (m, C) with each column one eigenvalue: its value
    where `shown` (the window and its guard bands, SpectralWindow.tracked), nan elsewhere (not
    tracked there, or not yet or no more this column's eigenvalue); the columns in order of
    first appearance (point, then label), those never shown left out."""
    return in_columns(values, column_layout(continued, shown))


def column_layout(continued: Array, shown: Array) -> tuple[Array, Array, Array, int]:
    """Where window_columns puts each shown (point, label): (rows, labels, columns, C)."""
    m, k = continued.shape
    ids = np.empty((m, k), dtype=np.int64)
    ids[0] = np.arange(k)
    start = k
    for r in range(1, m):
        fresh = np.flatnonzero(~continued[r])
        ids[r] = ids[r - 1]
        ids[r, fresh] = start + np.arange(fresh.size)
        start += fresh.size
    rows, labels = np.nonzero(shown)  # row-major: in order of appearance
    used, first = np.unique(ids[rows, labels], return_index=True)
    rank = np.empty(used.size, dtype=np.int64)
    rank[np.argsort(first)] = np.arange(used.size)
    return rows, labels, rank[np.searchsorted(used, ids[rows, labels])], used.size


def in_columns(values: Array, layout: tuple[Array, Array, Array, int]) -> Array:
    """values (m, k) per (point, label) placed in the columns of column_layout (nan
    elsewhere), in values' dtype (complex eigenvalues, real condition numbers)."""
    rows, labels, columns, C = layout
    out = np.full((values.shape[0], C), np.nan, dtype=values.dtype)
    out[rows, columns] = values[rows, labels]
    return out


def block_columns(values: list, blocks: Array, continued: dict, band: SpectralWindow,
                  *more: list) -> tuple[Array, ...]:
    """The stored spectrum of a windowed branch made of blocks, stretches with one window size
    (a window sized anew where it crowded, a packing's segment after a plastic event): values
    [m] the eigenvalues of each point (k per point within a block), blocks (m,) each point's
    block, continued {block: its points' Branch.continued rows}. Each block's window_columns
    side by side, nan at the other blocks' points (no eigenvalue continues a column across
    blocks). Returns that array, then each of `more` (per-point arrays aligned with values,
    e.g. condition numbers) placed in the same columns."""
    parts, total = [], 0
    for b in np.unique(blocks):
        on = np.flatnonzero(blocks == b)
        rows = np.array([values[i] for i in on])
        layout = column_layout(np.asarray(continued[b]), band.tracked(rows))
        placed = [in_columns(rows, layout)] + [in_columns(np.array([m[i] for i in on]), layout)
                                               for m in more]
        parts.append((on, total, placed))
        total += layout[3]
    out = []
    for a in range(1 + len(more)):
        array = np.full((blocks.size, total), np.nan, dtype=parts[0][2][a].dtype)
        for on, start, placed in parts:
            array[on, start:start + placed[a].shape[1]] = placed[a]
        out.append(array)
    return tuple(out)
