"""Statistics of a shear's branch per unit strain, not per accepted state (issue 63).

The shear's steps shrink near contact events, collisions and folds, where the spectrum changes
fastest, so its accepted states crowd there: a mean over states weighs those places by how
hard the continuation worked at them, not by how much strain they take up. Here every figure
is a mean over the strain the branch covers, each state (or sample) standing for a cell of
strain around it:

    w_k = (gamma_{k+1} - gamma_{k-1}) / 2  inside a segment,  (gamma_1 - gamma_0) / 2 and
    (gamma_{n-1} - gamma_{n-2}) / 2 at its ends,

the strain nearer to state k than to its neighbours in its segment (models/packing/shear.py:
the stretch between two plastic events; no cell reaches across a plastic event, where the
strain jumps by PAST_FOLD and the state with it). sum_k w_k f_k is the trapezoid rule for the
integral of f over the segment: exact for an f linear between states. For an indicator (a
complex pair, a damped-unstable mode) the error is at most half the step holding each change
of the indicator, if it changes at most once in a step. The samples of spectra "sample:DGAMMA"
(models/packing/sampled.py) sit on an even grid: each stands for DGAMMA, the first and last in
a segment for half a step plus the strain to the segment's end, so that their cells too add up
to the strain covered; an indicator's error is then at most DGAMMA / 2 at each change between
two samples, and the cell's part beyond a segment's outer sample (under DGAMMA) at a change
there.

A fraction is sum_k w_k [indicator_k] / sum_k w_k; a quantile of a per-state quantity is that
of the distribution putting the weight w_k at f_k (strain_quantile). Growth rates are those of
the damped linearization M q'' + eta M q' + J q = 0 (dynamics/damped_modes.py) from the
eigenvalues of M^-1 J; at eta = 0 the fastest is the fastest pair's |Im sqrt(lambda)|
(models/packing/dynamics.fastest_pair) wherever no real eigenvalue is negative.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Sequence

import numpy as np

from diskfriction.continuation.branch import Branch
from diskfriction.continuation.spectra.tracking import DEFAULT_REL_TOL
from diskfriction.models.packing.damped import fastest_damped


@dataclass(frozen=True)
class StrainStatistics:
    """A branch's spectrum per unit strain (module docstring), from its accepted states or its
    samples: strain, the strain they stand for (the segments' spans, plastic events' jumps left
    out; with samples, those of the segments holding one);
    complex_fraction, the fraction of it with a complex pair (in the window, with one);
    pairs_mean, the mean number of pairs per unit strain; at each drag eta in etas [1 / time]
    (0: the undamped analysis), unstable_fraction, the fraction with a damped-unstable mode
    (a growth rate max Re s > 0), growth_median and growth_max, the median over that strain
    and the largest of the fastest mode's growth rate max Re s [1 / time] (None without any);
    collisions_per_disk_strain, the located collisions per disk per unit strain covered (None where
    the states' spectra were not tracked: spectra "none" or "sample:DGAMMA" locate none). The
    fractions and means are nan for a branch that covers no strain."""

    strain: float
    complex_fraction: float
    pairs_mean: float
    etas: tuple[float, ...]
    unstable_fraction: tuple[float, ...]
    growth_median: tuple[Optional[float], ...]
    growth_max: tuple[Optional[float], ...]
    collisions_per_disk_strain: Optional[float]


def cell_widths(gamma: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """(n,): the strain nearer to each of the increasing strains gamma than to its neighbours,
    within [lo, hi] (lo <= gamma[0], gamma[-1] <= hi); they add up to hi - lo."""
    edges = np.concatenate([[lo], 0.5 * (gamma[:-1] + gamma[1:]), [hi]])
    return np.diff(edges)


def segment_rows(branch: Branch) -> list[tuple[int, int]]:
    """(start, stop) rows of each segment of the branch (its pieces "segment"; the whole branch
    where it has none)."""
    return [(p.start, p.stop) for p in branch.of_kind("segment")] or [(0, len(branch))]


def state_weights(branch: Branch) -> np.ndarray:
    """(m,): the strain each accepted state stands for: its cell within its segment (module
    docstring; a segment of one state stands for none). They add up to strain_covered."""
    gamma = branch.p
    return np.concatenate([cell_widths(gamma[a:b], gamma[a], gamma[b - 1])
                           for a, b in segment_rows(branch)])


def sample_weights(branch: Branch) -> np.ndarray:
    """(k,): the strain each of the branch's samples (labelled "sample") stands for: its cell
    within the segment holding it, the first and last of a segment reaching to its ends (module
    docstring). They add up to the strain covered by the segments holding a sample."""
    at = np.array([x.gamma for x in branch.sample], dtype=float)
    weights = np.zeros(at.size)
    for a, b in segment_rows(branch):
        lo, hi = branch.p[a], branch.p[b - 1]
        inside = (at >= lo) & (at <= hi)
        if inside.any():
            weights[inside] = cell_widths(at[inside], lo, hi)
    return weights


def strain_covered(branch: Branch, above: float = -np.inf) -> float:
    """The strain the branch covers above `above`: its segments' spans (a plastic event's jump
    PAST_FOLD left out), each cut at `above`."""
    gamma = branch.p
    return float(sum(max(0.0, gamma[b - 1] - max(gamma[a], above)) for a, b in segment_rows(branch)))


def strain_mean(values: np.ndarray, weights: np.ndarray) -> float:
    """The mean of a per-point quantity per unit strain, sum w f / sum w; nan without weight
    (a branch that covers no strain). Of an indicator (bool), the fraction of the strain where
    it holds."""
    total = float(np.sum(weights))
    return float(np.sum(weights * np.asarray(values, float)) / total) if total > 0 else float("nan")


def strain_quantile(values: np.ndarray, weights: np.ndarray, q):
    """The q-quantile(s) of `values` per unit strain: each value stands for its weight, at the
    middle of its share of the cumulative weight, linear in between (with equal weights, numpy's
    "hazen" quantile; the median of an odd number of values is the middle one). nan without
    weight."""
    values, weights = np.asarray(values, float), np.asarray(weights, float)
    kept = weights > 0
    if not kept.any():
        return np.full(np.shape(q), np.nan)[()]
    order = np.argsort(values[kept])
    v, w = values[kept][order], weights[kept][order]
    middle = (np.cumsum(w) - 0.5 * w) / w.sum()
    return np.interp(q, middle, v)


def spectra_by_strain(branch: Branch, sampled: bool) -> tuple[np.ndarray, list[np.ndarray], np.ndarray]:
    """(weights, eigenvalues per point, complex pairs per point) of the branch's accepted states
    (sampled False) or samples (True). ValueError where the branch holds no such spectra."""
    if sampled:
        if "sample" not in branch.labelled:
            raise ValueError("the branch holds no samples (its shear's spectra was not \"sample:DGAMMA\")")
        samples = branch.sample
        return (sample_weights(branch), [x.eigenvalues for x in samples],
                np.array([x.n_complex for x in samples], dtype=int))
    if (branch.n_complex < 0).any():
        raise ValueError("the branch's states carry no spectrum (its shear's spectra was \"none\" "
                         "or \"sample:DGAMMA\": take the samples)")
    return state_weights(branch), list(branch.eigenvalues), np.asarray(branch.n_complex)


def strain_statistics(branch: Branch, etas: Sequence[float] = (0.0,), sampled: bool = False,
                      counted_from: float = 0.0, rel_tol: float = DEFAULT_REL_TOL) -> StrainStatistics:
    """The branch's StrainStatistics at the drags `etas` [1 / time] (the eigenvalues must be
    those of M^-1 J for its growth rates to mean one; () for none), from its accepted states
    or (sampled) its samples. Collisions per disk (N from the state q, 3N) per unit strain
    covered above counted_from, the strain below which the shear kept no collision (the
    scene's gamma_range[0])."""
    weights, eigenvalues, n_complex = spectra_by_strain(branch, sampled)
    unstable, medians, largest = [], [], []
    for eta in etas:
        growth = np.array([fastest_damped(e, eta, rel_tol) for e in eigenvalues])
        grows = growth > 0
        unstable.append(strain_mean(grows, weights))
        median = strain_quantile(growth[grows], weights[grows], 0.5)
        medians.append(None if np.isnan(median) else float(median))
        largest.append(float(growth[grows].max()) if grows.any() else None)
    collisions, covered = None, strain_covered(branch, counted_from)
    if (branch.n_complex >= 0).all() and covered > 0:
        collisions = len(branch.collisions) / (branch.u.shape[1] // 3 * covered)  # q: 3N
    return StrainStatistics(float(weights.sum()), strain_mean(n_complex > 0, weights),
                            strain_mean(n_complex, weights), tuple(etas),
                            tuple(unstable), tuple(medians), tuple(largest), collisions)
