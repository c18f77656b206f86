"""Complex windows of a branch leg: the F_x intervals between consecutive located collisions,
each with its number of complex pairs (constant inside, by construction of the collisions)."""
from __future__ import annotations

from typing import Iterable, NamedTuple

import numpy as np

from diskfriction.continuation.spectra.tracking import Kind


class Window(NamedTuple):
    """F_x from `start` to `stop` [force] with `pairs` complex pairs throughout."""

    start: float
    stop: float
    pairs: int


def complex_windows(F_start: float, F_stop: float, pairs_at_start: int,
                    collisions: Iterable[tuple[float, str]]) -> list[Window]:
    """The intervals of a leg from F_start to F_stop cut at its collisions ((F_x, kind) in
    branch order, kind a tracking.Kind or its name): the pair count starts at pairs_at_start
    and changes by +1 at a birth, -1 at a death (Kind.sign)."""
    collisions = list(collisions)
    edges = [float(F_start)] + [float(p) for p, _ in collisions] + [float(F_stop)]
    count, out = int(pairs_at_start), []
    for k, (a, b) in enumerate(zip(edges, edges[1:])):
        out.append(Window(a, b, count))
        if k < len(collisions):
            count += Kind(collisions[k][1]).sign
    return out


def leg_windows(F_x: np.ndarray, n_complex: np.ndarray, leg: np.ndarray,
                collisions: Iterable[tuple[float, str]]) -> list[Window]:
    """The windows of a branch's requested leg (leg 1) from its points' F_x, n_complex and leg
    (0 for a preparation leg) and its collisions ((F_x, kind) in branch order). Leg 1 starts
    at the last point of leg 0 (which it does not record again), so its windows start there,
    with the pair count there: from its first recorded point instead, a collision in its first
    step would be missed. None if the branch has no point on leg 1 (the preparation ended short)."""
    rows = np.flatnonzero(np.asarray(leg) == 1)
    if not rows.size:
        return []
    start = rows[0] - 1 if rows[0] > 0 else rows[0]
    return complex_windows(F_x[start], F_x[rows[-1]], n_complex[start], collisions)


def complex_spans(windows: Iterable[Window]) -> list[tuple[float, float]]:
    """The F_x spans with at least one complex pair: adjacent complex windows merged."""
    spans: list[tuple[float, float]] = []
    for w in windows:
        if w.pairs <= 0:
            continue
        if spans and spans[-1][1] == w.start:
            spans[-1] = (spans[-1][0], w.stop)
        else:
            spans.append((w.start, w.stop))
    return spans
