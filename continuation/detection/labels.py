"""Labels: which eigenvalue of a sample continues which label of its neighbour's (samples.py).

Matching the labels of a new sample uses the eigenvalues' slopes along the branch: label i goes
to the eigenvalue nearest to the trapezoid prediction lambda_i + (slope_i + slope_new) ds / 2
(predicted_match: the assignment of least total distance, tracking.match_eigenvalues on the
predicted values), which follows a fast eigenvalue through a cluster; without slopes, to the
nearest eigenvalue. Excluded modes (decoupled blocks, outside a spectral window) are matched
among themselves in order of value (order_match). A spectral window's samples hold the k
eigenvalues nearest its centre, a set that changes along the branch: an eigenvalue beyond the
guard bands may leave it and another join it (window_match). A partial sample's labels are
matched where it knows them (known).
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Optional

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree

from diskfriction.continuation.spectra.tracking import match_eigenvalues

if TYPE_CHECKING:  # pragma: no cover
    from diskfriction.continuation.detection.samples import Sample

Array = np.ndarray


def prediction_cost(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                    ds_ref: float, ds_new: float) -> Array:
    """|ref_i + ds_ref ref_dlam_i / 2 - (values_j - ds_new dlam_j / 2)|: how far eigenvalue j
    lies from the trapezoid prediction of reference i (ds_* = the step projected on each end's
    unit tangent). Built COST_ROWS rows at a time: the whole complex difference at n = m =
    3000 is a 144 MB temporary (the same values)."""
    return _distances(*_predictions(ref_values, ref_dlam, values, dlam, ds_ref, ds_new))


def _predictions(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                 ds_ref: float, ds_new: float) -> tuple[Array, Array]:
    """The two ends' trapezoid predictions, whose distances are prediction_cost."""
    return ref_values + 0.5 * ds_ref * ref_dlam, values - 0.5 * ds_new * dlam


def _distances(a: Array, z: Array) -> Array:
    """|a_i - z_j| (n, m), COST_ROWS rows at a time."""
    out = np.empty((a.size, z.size))
    for start in range(0, a.size, COST_ROWS):
        np.abs(a[start:start + COST_ROWS, None] - z[None, :], out=out[start:start + COST_ROWS])
    return out


COST_ROWS = 128
"""Rows of prediction_cost computed at once."""


def nearest_predicted(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                      ds_ref: float, ds_new: float) -> Array:
    """For each reference i, the j of least prediction_cost (i, j), the first such j where
    several tie: np.argmin(prediction_cost(...), axis=1) without the n x m matrix (144 MB at
    n = m = 3000). A k-d tree offers each i its NEAREST_CANDIDATES nearest
    predictions, whose costs are computed as prediction_cost does; a row whose candidates all
    lie within relative 1e-12 of the nearest (the tree's distances may differ from |z| in the
    last bit, so a farther candidate might tie), or any value that is not finite, is computed
    whole."""
    a, z = _predictions(ref_values, ref_dlam, values, dlam, ds_ref, ds_new)
    if z.size <= NEAREST_CANDIDATES or a.size == 0 or not (np.all(np.isfinite(a)) and np.all(np.isfinite(z))):
        return np.argmin(_distances(a, z), axis=1)
    distance, candidates = cKDTree(np.column_stack([z.real, z.imag])).query(
        np.column_stack([a.real, a.imag]), k=NEAREST_CANDIDATES)
    candidates = np.sort(candidates, axis=1)  # ties: the first index, as np.argmin
    nearest = candidates[np.arange(a.size), np.argmin(np.abs(a[:, None] - z[candidates]), axis=1)]
    open_rows = np.flatnonzero(distance[:, -1] <= distance[:, 0] * (1.0 + 1e-12))
    for i in open_rows:
        nearest[i] = np.argmin(np.abs(a[i] - z))
    return nearest


NEAREST_CANDIDATES = 4
"""Predictions nearest_predicted takes from its k-d tree for each reference."""


def predicted_match(ref_values: Array, ref_dlam: Array, values: Array, dlam: Array,
                    ds_ref: float, ds_new: float) -> Array:
    """Labels of `values` continuing `ref_values`: perm minimising sum_i of the
    prediction_cost of (i, perm(i)) (each its nearest where those are all different)."""
    nearest = nearest_predicted(ref_values, ref_dlam, values, dlam, ds_ref, ds_new)
    if np.unique(nearest).size == nearest.size:
        return nearest
    return linear_sum_assignment(prediction_cost(ref_values, ref_dlam, values, dlam, ds_ref, ds_new))[1]


def window_match(left: "Sample", right: "Sample", ds_left: float, ds_right: float,
                 dlam_left: Array, dlam_right: Array) -> Array:
    """Labels of the full window sample `right` continuing `left` (both hold the k eigenvalues
    nearest the window's centre sigma, Eigensystem.disc). An eigenvalue of `left` beyond the
    guard bands may have left the disc |lambda - sigma| < radius_right, and one of `right` may
    have entered it; the pairs (i, j) cost their prediction_cost, and label i leaving costs
    max(0, radius_right - |lambda_i + ds_left slope_i - sigma|) (how far its prediction at
    `right` would have to be off for it to lie outside that disc), eigenvalue j entering
    max(0, radius_left - |lambda_j - ds_right slope_j - sigma|) alike; a tracked eigenvalue
    (not excluded: in the window or its guard bands) never leaves or enters (the disc reaches
    beyond the guard bands, spectra/window.py). The assignment of least total cost (leaving
    and entering as dummy partners) keeps every eigenvalue present at both ends on its label;
    the labels left free take the entered eigenvalues (in the order of least prediction_cost):
    new eigenvalues on them, not continuations. A plain assignment over the pairs alone has
    no such choice: where the set changes it shifts a chain of labels along the real axis (on
    the line, all such chains cost about the same), relabelling eigenvalues in the window.
    dlam_*: the slopes that ds_* multiply (continuation_perm)."""
    nearest = nearest_predicted(left.eigvals, dlam_left, right.eigvals, dlam_right, ds_left, ds_right)
    if np.unique(nearest).size == nearest.size:
        return nearest
    cost = prediction_cost(left.eigvals, dlam_left, right.eigvals, dlam_right, ds_left, ds_right)
    (sigma, radius_left), (_, radius_right) = left.disc, right.disc
    k = cost.shape[0]
    leave = np.where(left.excluded, np.maximum(
        0.0, radius_right - np.abs(left.eigvals + ds_left * dlam_left - sigma)), np.inf)
    enter = np.where(right.excluded, np.maximum(
        0.0, radius_left - np.abs(right.eigvals - ds_right * dlam_right - sigma)), np.inf)
    full = np.full((2 * k, 2 * k), np.inf)
    full[:k, :k] = cost
    full[np.arange(k), k + np.arange(k)] = leave
    full[k + np.arange(k), np.arange(k)] = enter
    full[k:, k:] = 0.0
    cols = linear_sum_assignment(full)[1][:k]
    perm = cols.copy()
    gone, new = np.flatnonzero(cols >= k), np.setdiff1d(np.arange(k), cols)
    perm[gone] = new[linear_sum_assignment(cost[np.ix_(gone, new)])[1]]
    return perm


def continuation_perm(left: Sample, right: Sample, slopes: Optional[tuple[Array, Array]] = None) -> Array:
    """Labels of `right` continuing `left`: by prediction if both carry slopes, else by the
    nearest eigenvalue (tracking.match_eigenvalues). With a partial sample only the labels known
    at both are matched (the others keep theirs). Free disks' modes (excluded, outside a
    spectral window), as many at both ends, are matched among themselves in order of (Re, Im)
    (the optimal match of real values; identical free disks share their eigenvalues, and an
    assignment over all n labels costs n^3), the others by
    prediction among themselves. slopes: both ends' slopes per unit of the interval between
    them (verdicts.scaled_slopes), for an interval that ends at a root end (Sample.root_end),
    whose dlam is not along its tangent; default: dlam times the step projected on each
    end's tangent."""
    if left.dlam is None or right.dlam is None:
        return match_eigenvalues(left.eigvals, right.eigvals)
    dlam_left, dlam_right, ds_left, ds_right = _prediction_terms(left, right, slopes)
    common = known(left) & known(right)
    perm = np.arange(left.eigvals.size)
    free_l, free_r = common & left.excluded, common & right.excluded
    if left.guard is None and free_l.any() and free_r.any():
        by_l, by_r = _by_value(left, free_l), _by_value(right, free_r)
        i_l, i_r = order_match(left.eigvals[by_l], right.eigvals[by_r])
        perm[by_l[i_l]] = by_r[i_r]
        # a disk that joined the chain (or left it): its modes go with the chain's
        rest_l = np.union1d(np.flatnonzero(common & ~left.excluded), np.delete(by_l, i_l))
        rest_r = np.union1d(np.flatnonzero(common & ~right.excluded), np.delete(by_r, i_r))
    elif left.disc is not None and right.disc is not None and left.known is None and right.known is None:
        return window_match(left, right, ds_left, ds_right, dlam_left, dlam_right)
    else:
        rest_l = rest_r = np.flatnonzero(common)
    perm[rest_l] = rest_r[predicted_match(left.eigvals[rest_l], dlam_left[rest_l], right.eigvals[rest_r],
                                          dlam_right[rest_r], ds_left, ds_right)]
    return perm


def _prediction_terms(left: Sample, right: Sample, slopes: Optional[tuple[Array, Array]]):
    """(dlam_left, dlam_right, ds_left, ds_right) of continuation_perm's prediction."""
    if slopes is not None:
        return slopes[0], slopes[1], 1.0, 1.0
    step = right.x - left.x
    return left.dlam, right.dlam, float(step @ left.tangent), float(step @ right.tangent)


def claimed_outside(left: Sample, right: Sample, slopes: Optional[tuple[Array, Array]] = None) -> bool:
    """Whether the eigenvalue of the full sample `right` that best continues some label the
    partial sample `left` computed (least prediction_cost among all of right's labels) sits
    on a label that `left` did not compute. continuation_perm matches only the labels known at
    both, so it would give that label another eigenvalue, and the interval between the two
    would never be certified: a scan of 256 disks split it 70 times, each partial sample
    continuing the last one's labels, down to 7e-11 in strain (docs/notes/core-detection.md,
    "Partial samples declined where their labels would be claimed outside"). slopes: as
    continuation_perm's."""
    dlam_left, dlam_right, ds_left, ds_right = _prediction_terms(left, right, slopes)
    mine = np.flatnonzero(known(left))
    nearest = nearest_predicted(left.eigvals[mine], dlam_left[mine], right.eigvals, dlam_right, ds_left, ds_right)
    return bool(np.any(~known(left)[nearest]))


def order_match(a: Array, b: Array) -> tuple[Array, Array]:
    """The order-keeping match of two value lists, each sorted by (Re, Im), whose sizes differ
    by a few (the free disks' modes before and after a disk joins the chain): indices (i_a,
    i_b) of the matched pairs, minimising sum |a_i - b_j| over them, the surplus of the longer
    list left out. Dynamic programming over the k left out: O(n k) time, O(n k) memory, where
    an assignment over all n labels would take n^2 (at N = 3000, eps = 0: 1.9 GB)."""
    if a.size < b.size:
        i_b, i_a = order_match(b, a)
        return i_a, i_b
    k, m = a.size - b.size, b.size
    if k == 0:
        return np.arange(m), np.arange(m)
    shift = np.arange(k + 1)
    cost = np.full(k + 1, np.inf)
    cost[0] = 0.0  # cost[s]: best after the first i of a, s of them left out
    left_out = np.zeros((a.size, k + 1), bool)
    for i in range(a.size):
        j = i - shift  # the b that a[i] meets when s of a[:i] are left out
        keep = np.where((j >= 0) & (j < m), cost + np.abs(a[i] - b[np.clip(j, 0, max(m - 1, 0))]), np.inf)
        drop = np.concatenate([[np.inf], cost[:-1]])
        left_out[i] = drop < keep
        cost = np.minimum(keep, drop)
    pairs, s = [], k
    for i in range(a.size - 1, -1, -1):
        if left_out[i, s]:
            s -= 1
        else:
            pairs.append((i, i - s))
    pairs = np.array(pairs[::-1], dtype=int).reshape(-1, 2)
    return pairs[:, 0], pairs[:, 1]


def _by_value(sample: Sample, mask: Array) -> Array:
    """The labels in mask in order of (Re, Im) of their eigenvalues, ties in label order."""
    labels = np.flatnonzero(mask)
    return labels[np.lexsort((sample.eigvals.imag[labels], sample.eigvals.real[labels]))]


def known(sample: Sample) -> Array:
    """Mask of the labels computed at the sample (all of a full one)."""
    return np.ones(sample.eigvals.size, bool) if sample.known is None else sample.known
