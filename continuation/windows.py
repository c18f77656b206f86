"""Complex windows of a branch leg: the F_x intervals between consecutive located collisions,
each with its number of complex pairs (constant inside, by construction of the collisions)."""
from __future__ import annotations

from typing import Iterable, NamedTuple

from diskfriction.continuation.spectra import Kind


class Window(NamedTuple):
    """F_x from `start` to `stop` [force] with `pairs` complex pairs throughout."""

    start: float
    stop: float
    pairs: int


def complex_windows(F_start: float, F_stop: float, pairs_at_start: int,
                    collisions: Iterable[tuple[float, str]]) -> list[Window]:
    """The intervals of a leg from F_start to F_stop cut at its collisions ((F_x, kind) in
    branch order, kind a spectra.Kind or its name): the pair count starts at pairs_at_start
    and changes by +1 at a birth, -1 at a death (Kind.sign)."""
    collisions = list(collisions)
    edges = [float(F_start)] + [float(p) for p, _ in collisions] + [float(F_stop)]
    count, out = int(pairs_at_start), []
    for k, (a, b) in enumerate(zip(edges, edges[1:])):
        out.append(Window(a, b, count))
        if k < len(collisions):
            count += Kind(collisions[k][1]).sign
    return out


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
