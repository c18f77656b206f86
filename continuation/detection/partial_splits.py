"""Partial split samples: when a split sample may compute only the labels in trouble, and how.

A split of [l, r] for the labels T in trouble (verdicts.Verdict.labels) needs only their
eigenvalues at the new sample p: every pair with a label outside T is certified on [l, r] (so
on [l, p] and [p, r]), and outside T no status changes. The children [l, p] and [p, r] are
judged on the labels known at both ends (verdicts.active_labels); their splits nest. This holds
while the labels of l and r stay associated as they were when [l, r] was judged: a partial
sample that relabels its right neighbour is inserted only if [l, r] and every interval whose
certificate [l, r] inherits, judged again with the new labels, keep their trouble within the
labels split for (certificates_survive). A full sample is tracked from a full left neighbour,
so a split that needs a full sample next to a partial one first makes that end full, with the
partial samples it was tracked through back to the nearest full one
(collisions.StepScan._upgrade_partials); a partial sample whose labels a full one then
relabels is made full too (StepScan._relabel_right). Partial samples right of that, untouched,
keep their labels and so their certificates.

The eigenvalues of a partial sample come from a few shift-inverts (nearest.py via
samples.partial_sample_at), one per cluster of the labels' predicted eigenvalues (clusters).
"""
from __future__ import annotations

from typing import Callable, Optional

import numpy as np

from diskfriction.continuation.detection import certify
from diskfriction.continuation.detection.labels import known
from diskfriction.continuation.detection.samples import Sample
from diskfriction.continuation.stepping.segment import Segment
from diskfriction.continuation.detection.verdicts import Verdict, VerdictKind, active_labels, event_labels, scaled_slopes

Array = np.ndarray

PARTIAL_EXTRA = 6
"""Eigenvalues a partial sample computes beyond those expected near its labels."""
PARTIAL_CLUSTERS = 3
"""Shift-inverts a partial sample may take at least (each costs about 1/5 of a full spectrum at
n = 300; more did not pay at N = 100: docs/notes/core-detection.md, "How many clusters a partial
sample may take"), and always where the full sample is a spectral window's (most_clusters)."""
ROWS_PER_CLUSTER = 100
"""Where the full sample is the whole spectrum, a partial sample may take one shift-invert per
this many rows of the stability matrix (most_clusters)."""


def partial_allowed(a: Sample, b: Sample, labels: Optional[Array], partial_from: int) -> bool:
    """A partial sample may split [a, b] (fast detection) for `labels`: a stability matrix of
    size n >= partial_from, labels known at both ends, and no excluded mode at either end
    unless a spectral window is tracked (decoupled blocks' spectra are computed block by block
    and are cheap when they are many, where partial samples are not; a window's excluded
    labels, beyond its guard bands, are
    never in trouble, and a partial sample keeps its left neighbour's excluded and guard flags
    for the labels it does not compute)."""
    window = a.guard is not None and b.guard is not None
    return (labels is not None and a.matrix_size >= partial_from
            and (window or not (a.excluded.any() or b.excluded.any()))
            and not np.any(labels & ~active_labels(a, b)))


def most_clusters(sample: Sample) -> int:
    """The shift-inverts a partial sample next to `sample` may take: PARTIAL_CLUSTERS where
    the full sample would be a spectral window's (a shift-invert itself: 5 clusters gained
    nothing on 256 sheared disks, docs/notes/packings-speed.md, "Tried and left"), else
    n // ROWS_PER_CLUSTER if that is more. A whole spectrum costs O(n^2) refined or O(n^3)
    decomposed, a cluster's shift-invert O(n): the labels in trouble of a long chain fall into
    more than a few clusters, and each cluster is cheap beside a full sample
    (docs/notes/core-detection.md, "How many clusters a partial sample may take")."""
    if sample.guard is not None:
        return PARTIAL_CLUSTERS
    return max(PARTIAL_CLUSTERS, sample.eigvals.size // ROWS_PER_CLUSTER)


def clusters(l: Sample, r: Sample, s: float, labels: Array, reference: Array, segment: Segment,
             max_k: int, most: int = PARTIAL_CLUSTERS) -> Optional[list]:
    """The shift-inverts of a partial sample at s in [l, r] for `labels` (int array):
    [(labels of the cluster, sigma, k), ...]. The labels' eigenvalues predicted at s (cubic
    Hermite over [l, r]) are taken in order of real part and grouped while the group's k stays
    within max_k: sigma the middle of its real parts, k the eigenvalues of `reference` (those
    of the nearest full sample to the left) within twice its reach of sigma, plus
    PARTIAL_EXTRA. None if that takes more than `most` groups (most_clusters)."""
    d_l, d_r = scaled_slopes(l, r, segment)
    mu = certify.cubic_at(certify.hermite_coefficients(l.eigvals[labels], r.eigvals[labels],
                                                       d_l[labels], d_r[labels]), (s - l.s) / (r.s - l.s))
    order = np.argsort(mu.real)
    k_max = min(max_k, l.eigvals.size - 2)

    def shift(group: list) -> tuple[float, int]:
        sigma = 0.5 * float(mu.real[group].min() + mu.real[group].max())
        reach = 2.0 * float(np.max(np.abs(mu[group] - sigma)))
        return sigma, int(np.count_nonzero(np.abs(reference - sigma) <= reach)) + PARTIAL_EXTRA

    groups = [[order[0]]]
    for i in order[1:]:
        if shift(groups[-1] + [i])[1] <= k_max:
            groups[-1].append(i)
        else:
            groups.append([i])
    found = [(labels[group], *shift(group)) for group in groups]
    if len(found) > most or any(k > k_max for _, _, k in found):
        return None
    return found


def certificates_survive(trial: list, new: int, ages: list, judge: Callable[[Sample, Sample], Verdict]) -> bool:
    """Whether the samples `trial`, with trial[new] just inserted and the samples right of it
    relabelled, leave every certificate their intervals rely on valid: the interval trial[new]
    splits and each ancestor up to the first between two full samples (the parent of an
    interval is the one its younger end was inserted into; ages: the insertion order of each
    sample, the step's ends oldest) are judged again with the new labels, and each one's
    trouble must stay within the labels of the sample inserted into it."""
    n = trial[new].eigvals.size
    lo, child, hi = new - 1, new, new + 1
    while True:
        a, b = trial[lo], trial[hi]
        again = judge(a, b)
        trouble = again.labels if again.kind == VerdictKind.SPLIT else event_labels(again.events, n)
        if trouble is None or np.any(trouble & ~known(trial[child])):
            return False
        if not (a.partial or b.partial):
            return True
        if ages[hi] > ages[lo]:
            child = hi
            hi = next(k for k in range(hi + 1, len(trial)) if ages[k] < ages[child])
        else:
            child = lo
            lo = next(k for k in range(lo - 1, -1, -1) if ages[k] < ages[child])
