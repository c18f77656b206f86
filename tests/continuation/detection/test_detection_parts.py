"""The detection's parts alone (issue 8, Shape): the certifier's verdict on one interval
(verdicts.py) and the partial-split rules (partial_splits.py), on samples of small problems of
the continuation core whose collisions are known in closed form."""
from __future__ import annotations

import re
from dataclasses import replace

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from diskfriction.continuation import FunctionProblem
from diskfriction.continuation.stepping.newton import tangent
from diskfriction.continuation.detection.partial_splits import (PARTIAL_CLUSTERS, PARTIAL_EXTRA, ROWS_PER_CLUSTER,
                                                      certificates_survive, clusters, most_clusters,
                                                      partial_allowed)
from diskfriction.continuation.detection.labels import (claimed_outside, continuation_perm, nearest_predicted,
                                                       predicted_match, prediction_cost)
from diskfriction.continuation.detection.samples import Sample, label_gaps, sample_at
from diskfriction.continuation.stepping.segment import Segment
from diskfriction.continuation.detection.verdicts import Verdict, judge_exhaustive, judge_fast

RHO, DOUBT, REL_TOL = 0.5, 0.25, 1e-9
V, C = 10.0, 1e-3
"""A fast eigenvalue V p meets the eigenvalue 2 with skew coupling C: a complex pair for
|V p - 2| < 2 C, i.e. p in (0.2 - 2e-4, 0.2 + 2e-4)."""


def bubble_problem(diagonal=(1.0, 2.0, 3.0)):
    """A(p) = diag(V p, *diagonal) with the skew coupling C between the first two; the branch
    is u = 0 (G = A(p) u)."""
    n = len(diagonal) + 1

    def A(p):
        M = np.diag([V * p, *diagonal])
        M[0, 2], M[2, 0] = C, -C
        return M

    dA = np.zeros((n, n))
    dA[0, 0] = V
    return FunctionProblem(lambda u, p: A(p) @ u, lambda u, p: A(p), lambda u, p: dA @ u)


def interval(problem, n: int, p_a: float, p_b: float, slopes: bool = True):
    """Samples at p_a (s = 0) and p_b (s = 1) on the branch u = 0, labels of b continuing a;
    with slopes unless asked not to (the exhaustive detection's samples)."""
    x_a, x_b = np.append(np.zeros(n), p_a), np.append(np.zeros(n), p_b)
    segment = Segment(problem, x_a, x_b, tol=1e-12, max_iter=10)
    t = (lambda x: tangent(problem, x, segment.sigma)) if slopes else (lambda x: None)
    a = sample_at(problem, 0.0, x_a, REL_TOL, None, t(x_a))
    b = sample_at(problem, 1.0, x_b, REL_TOL, a, t(x_b))
    return a, b, segment


def label_of(sample, value: float) -> int:
    return int(np.argmin(np.abs(sample.eigvals - value)))


def test_a_verdict_is_clean_far_from_any_encounter():
    problem = bubble_problem()
    a, b, segment = interval(problem, 4, 0.03, 0.07)
    verdict = judge_fast(a, b, segment, RHO, DOUBT)
    assert verdict.kind == "clean" and verdict.events == [] and verdict.consistent


def test_a_verdict_splits_an_interval_that_hides_a_whole_bubble_for_the_pair_in_trouble():
    """Both ends real, the bubble inside: no status change, but the pair's discriminant model
    dips, so the interval splits inside it, for that pair's labels alone (the eigenvalues 1
    and 3 stay 0.9 away)."""
    problem = bubble_problem()
    a, b, segment = interval(problem, 4, 0.19, 0.21)
    assert not np.any(a.status) and not np.any(b.status)
    verdict = judge_fast(a, b, segment, RHO, DOUBT)
    assert verdict.kind == "split" and verdict.consistent and 0.0 < verdict.split_at < 1.0
    fast, two = label_of(a, V * 0.19), label_of(a, 2.0)
    assert np.flatnonzero(verdict.labels).tolist() == sorted([fast, two])


def test_a_verdict_lists_the_birth_of_the_pair_and_its_labels():
    """a real (p = 0.1995), b inside the bubble (p = 0.2001): one birth of the pair the fast
    eigenvalue and the eigenvalue 2 form, the interval ready for the locator."""
    problem = bubble_problem()
    a, b, segment = interval(problem, 4, 0.1995, 0.2001)
    assert np.count_nonzero(b.status) == 2
    verdict = judge_fast(a, b, segment, RHO, DOUBT)
    assert verdict.kind == "events" and len(verdict.events) == 1
    i, j, kind = verdict.events[0]
    assert kind == "birth" and {i, j} == {label_of(a, V * 0.1995), label_of(a, 2.0)}


def test_a_relabelling_beyond_the_windows_band_needs_no_explaining():
    """The birth of the bubble's pair in [0.1995, 0.2001] beside three eigenvalues 20, 21, 22
    whose statuses change in a way no birth or death explains (at a: 21 and 22 a 'pair'; at b:
    20 and 22), as a guard band's pairs relabel where they move fast. With a window whose
    certified band ends at 10, those three lie beyond it at both ends: the verdict holds the
    birth, consistent. With the band reaching 30, or with no window, the change must be
    explained and the interval splits."""
    problem = bubble_problem((1.0, 2.0, 3.0, 20.0, 21.0, 22.0))
    a, b, segment = interval(problem, 7, 0.1995, 0.2001)
    far = [label_of(a, v) for v in (20.0, 21.0, 22.0)]
    status_a, status_b = a.status.copy(), b.status.copy()
    status_a[far], status_b[far] = [0, -1, 1], [-1, 0, 1]

    def verdict(band):
        return judge_fast(replace(a, status=status_a, band=band), replace(b, status=status_b, band=band),
                          segment, RHO, DOUBT)

    within = verdict((-10.0, 10.0))
    assert within.kind == "events" and within.consistent and len(within.events) == 1
    i, j, kind = within.events[0]
    assert kind == "birth" and {i, j} == {label_of(a, V * 0.1995), label_of(a, 2.0)}
    for band in [(-10.0, 30.0), None]:
        assert verdict(band).kind == "split" and not verdict(band).consistent


def test_the_exhaustive_verdict_needs_its_stencil():
    """Without slopes an interval is certified by the quadratic through a third sample: with
    none it splits; with one at p = 0.05 (s = 1.5) the pair of the fast eigenvalue and 1,
    y = (1 - V p)^2, stays far from 0 on [0.02, 0.04] and it is clean; across the exact
    crossing at p = 0.1, [0.08, 0.12] with a stencil at 0.13, y reaches 0 and it splits."""
    problem = bubble_problem()

    def verdict(p_a, p_b, p_c):
        a, b, segment = interval(problem, 4, p_a, p_b, slopes=False)
        stencil = None
        if p_c is not None:
            stencil = replace(interval(problem, 4, p_a, p_c, slopes=False)[1], s=(p_c - p_a) / (p_b - p_a))
        return judge_exhaustive(a, b, stencil, RHO).kind

    assert verdict(0.02, 0.04, None) == "split"
    assert verdict(0.02, 0.04, 0.05) == "clean"
    assert verdict(0.08, 0.12, 0.13) == "split"


def test_partial_samples_are_allowed_by_size_and_known_labels_only():
    problem = bubble_problem()
    a, b, _ = interval(problem, 4, 0.19, 0.21)
    labels = np.array([True, False, True, False])
    assert partial_allowed(a, b, labels, partial_from=0)
    assert not partial_allowed(a, b, labels, partial_from=5)  # n = 4 < 5
    assert not partial_allowed(a, b, None, partial_from=0)  # the next sample must be full
    half = replace(b, known=np.array([True, True, False, True]))
    assert not partial_allowed(a, half, labels, partial_from=0)  # label 2 unknown at b


def test_clusters_group_the_labels_by_their_predicted_eigenvalues():
    """n = 40, eigenvalues V p and 1..39: labels near 1 and 2 share one shift, the one at 39
    gets its own; four far-apart groups are more than PARTIAL_CLUSTERS, and are taken where four
    are allowed."""
    diagonal = tuple(float(k) for k in range(1, 40))
    problem = bubble_problem(diagonal)
    a, b, segment = interval(problem, 40, 0.03, 0.07)
    reference = a.eigvals
    at = {value: label_of(a, value) for value in (1.0, 2.0, 12.0, 25.0, 39.0)}
    found = clusters(a, b, 0.5, np.array([at[1.0], at[2.0], at[39.0]]), reference, segment, 16)
    assert [(sorted(lab.tolist()), sigma, k) for lab, sigma, k in found] == [
        (sorted([at[1.0], at[2.0]]), pytest.approx(1.5), 2 + PARTIAL_EXTRA),
        ([at[39.0]], pytest.approx(39.0), 1 + PARTIAL_EXTRA)]
    spread = np.array([at[1.0], at[12.0], at[25.0], at[39.0]])
    assert PARTIAL_CLUSTERS < 4 and clusters(a, b, 0.5, spread, reference, segment, 16) is None
    four = clusters(a, b, 0.5, spread, reference, segment, 16, most=4)
    assert [lab.tolist() for lab, _, _ in four] == [[at[v]] for v in (1.0, 12.0, 25.0, 39.0)]
    assert clusters(a, b, 0.5, np.array([at[1.0]]), reference, segment, PARTIAL_EXTRA) is None  # k > max_k


def test_most_clusters_grow_with_a_whole_spectrum_only():
    """A partial sample may take n // ROWS_PER_CLUSTER shift-inverts where the full sample is
    the whole spectrum, never fewer than PARTIAL_CLUSTERS, and PARTIAL_CLUSTERS next to a
    spectral window's sample."""
    a, _, _ = interval(bubble_problem(), 4, 0.19, 0.21)
    n = 12 * ROWS_PER_CLUSTER + ROWS_PER_CLUSTER // 2
    large = replace(a, eigvals=np.zeros(n, complex))
    assert most_clusters(a) == PARTIAL_CLUSTERS  # n = 4
    assert most_clusters(large) == 12 > PARTIAL_CLUSTERS
    assert most_clusters(replace(large, guard=np.zeros(n, bool))) == PARTIAL_CLUSTERS


def test_certificates_survive_only_within_the_labels_the_new_sample_knows():
    """trial = [a, p, b] with p partial (labels 0 and 2 known) just inserted: the interval p
    splits must keep its trouble within p's labels; a full spectrum needed (labels None) or
    trouble on an unknown label breaks the certificate."""
    problem = bubble_problem()
    a, b, _ = interval(problem, 4, 0.19, 0.21)
    p = replace(a, s=0.5, known=np.array([True, False, True, False]))
    trial, ages = [a, p, b], [-1, 0, -1]

    def verdict(kind, labels=None, events=()):
        return lambda l, r: Verdict(kind, list(events), True, 0.5, labels)

    assert certificates_survive(trial, 1, ages, verdict("clean"))
    assert certificates_survive(trial, 1, ages, verdict("split", np.array([True, False, True, False])))
    assert certificates_survive(trial, 1, ages, verdict("events", events=[(0, 2, "birth")]))
    assert not certificates_survive(trial, 1, ages, verdict("split", None))
    assert not certificates_survive(trial, 1, ages, verdict("split", np.array([False, True, False, False])))
    assert not certificates_survive(trial, 1, ages, verdict("events", events=[(1, 3, "death")]))


def partial_scan():
    """A fast StepScan on the n = 40 bubble problem over p = 0.03 .. 0.07, with two partial
    samples (the labels near 1 and 2) at s = 0.5 and 0.75: [a, P1, P2, b]."""
    from diskfriction.continuation.detection.collisions import DetectionParams, StepScan

    problem = bubble_problem(tuple(float(k) for k in range(1, 40)))
    a, b, segment = interval(problem, 40, 0.03, 0.07)
    scan = StepScan(problem, segment, [a, b], DetectionParams(partial_from=0), step=0)
    labels = np.zeros(a.eigvals.size, bool)
    labels[[label_of(a, 1.0), label_of(a, 2.0)]] = True
    assert scan._insert_partial(0, 0.5, labels) and scan._insert_partial(1, 0.75, labels)
    assert [smp.partial for smp in scan.samples] == [False, True, True, False]
    return scan


def test_a_partial_end_is_made_full_with_the_partial_samples_it_is_tracked_through_only():
    """A split next to P1 that needs a full sample makes P1 full and leaves P2 partial (its
    labels unchanged); next to P2 it makes both full (P2 is tracked through P1)."""
    scan = partial_scan()
    labels = scan.samples[2].eigvals.copy()
    scan._upgrade_partials(1)
    assert [smp.partial for smp in scan.samples] == [False, False, True, False]
    assert np.array_equal(scan.samples[2].eigvals, labels, equal_nan=True)
    scan = partial_scan()
    scan._upgrade_partials(2)
    assert [smp.partial for smp in scan.samples] == [False, False, False, False]
    full = scan.samples[2].eigvals
    assert np.allclose(full[~np.isnan(labels)], labels[~np.isnan(labels)], rtol=0, atol=1e-12)


def test_a_relabelling_that_reaches_a_partial_sample_makes_it_full():
    """Two labels of the samples right of a full one swapped: continuing it relabels them,
    and the partial sample among them, whose certificates rested on its old labels, is
    recomputed as a full one."""
    scan = partial_scan()
    scan._upgrade_partials(1)
    known_labels = np.flatnonzero(scan.samples[2].known)
    swap = np.arange(scan.samples[2].eigvals.size)
    swap[known_labels[:2]] = known_labels[1::-1]
    scan.samples[2:] = [smp.relabel(swap) for smp in scan.samples[2:]]
    assert scan._relabel_right(1) is not None
    assert [smp.partial for smp in scan.samples] == [False, False, False, False]
    for k in (1, 2):  # every label continues its left neighbour's eigenvalue
        left, right = scan.samples[k].eigvals, scan.samples[k + 1].eigvals
        assert np.max(np.abs(right - left)) < 0.5


def test_free_modes_are_matched_among_themselves_and_give_no_gaps_to_the_chain():
    """Free disks' modes (excluded) and the chain's are tracked apart: the chain eigenvalue
    1.0 rising with slope 1 over 0.1 goes to 1.101, not to the free mode at 1.05, where the
    trapezoid predictions of both meet (an assignment over all labels takes that one: 3.949
    against 3.951 in total); the free modes take the free eigenvalues; and the chain
    eigenvalue's gap ignores the free mode 0.051 away."""
    def sample(x_p, values, dlam, excluded):
        values = np.array(values, complex)
        excluded = np.array(excluded)
        return Sample(0.0, np.array([0.0, x_p]), values, np.zeros(4, np.int8), 1e-12, excluded,
                      np.array([0.0, 1.0]), np.array(dlam, complex), None, None,
                      label_gaps(values, excluded, None))

    left = sample(0.0, [1.0, 3.0, 5.0, 5.0], [1.0, 0.0, 0.0, 0.0], [False, False, True, True])
    right = sample(0.1, [3.0, 1.101, 5.0, 1.05], [0.0, 1.0, 0.0, 0.0], [False, False, True, True])
    perm = continuation_perm(left, right)
    assert perm[0] == 1 and perm[1] == 0 and sorted(perm[2:].tolist()) == [2, 3]
    assert right.gaps[1] == pytest.approx(1.899) and right.gaps[3] == pytest.approx(3.95)


def test_order_match_leaves_out_the_surplus_of_the_longer_list():
    """Sorted lists whose sizes differ: the pairs keep the order and minimise the total
    distance; the values the other list lacks (1.5), or one of each tie, are left out."""
    from diskfriction.continuation.detection.labels import order_match

    a, b = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0, 5.0]), np.array([1.0, 1.0, 2.0, 2.0, 5.0])
    i_a, i_b = order_match(a, b)
    assert i_b.tolist() == [0, 1, 2, 3, 4] and np.array_equal(a[i_a], b)
    j_b, j_a = order_match(b, a)
    assert np.array_equal(j_a, i_a) and np.array_equal(j_b, i_b)
    i_a, i_b = order_match(np.array([0.0, 1.0, 1.5, 2.0, 3.0]), np.array([0.0, 1.0, 2.0, 3.0]))
    assert i_a.tolist() == [0, 1, 3, 4] and i_b.tolist() == [0, 1, 2, 3]
    same = np.arange(4.0)
    assert [x.tolist() for x in order_match(same, same)] == [[0, 1, 2, 3]] * 2


def test_a_disk_joining_the_chain_takes_its_free_modes_into_the_chain_s_match():
    """Four free disks (modes 0.5 and 0.7, excluded) and a chain (1, 2, 3); one disk joins:
    its modes, now 0.52 and 0.69, are the chain's. The three disks still free are matched by
    value, the chain's labels and the joining disk's two free labels by prediction among the
    chain's, whatever the right sample's label order."""
    def sample(x_p, values, excluded):
        values, excluded = np.array(values, complex), np.array(excluded)
        return Sample(0.0, np.array([0.0, x_p]), values, np.zeros(values.size, np.int8), 1e-12,
                      excluded, np.array([0.0, 1.0]), np.zeros(values.size, complex), None, None,
                      label_gaps(values, excluded, None))

    chain, free = [1.0, 2.0, 3.0], [0.5, 0.7] * 4
    left = sample(0.0, chain + free, [False] * 3 + [True] * 8)
    values = np.array(chain + [0.52, 0.69] + [0.5, 0.7] * 3)
    excluded = np.array([False] * 5 + [True] * 6)
    order = np.random.default_rng(1).permutation(values.size)
    right = sample(0.1, values[order], excluded[order])
    perm = continuation_perm(left, right)
    assert sorted(perm.tolist()) == list(range(11))
    assert np.max(np.abs(left.eigvals - right.eigvals[perm])) <= 0.02 + 1e-12
    assert np.array_equal(right.excluded[perm[:3]], [False] * 3)
    assert right.excluded[perm[3:]].sum() == 6  # two of the eight free labels went to the chain


def test_nearest_gaps_equal_all_pairs_on_spectra_with_ties_and_pairs():
    """The gaps from neighbours in order of real part are those of all pairs, to the bit, on
    random spectra with equal values, equal real parts and conjugate pairs."""
    from diskfriction.continuation.detection.certify import nearest_gaps

    rng = np.random.default_rng(0)
    for _ in range(200):
        n = int(rng.integers(1, 40))
        lam = np.round(rng.standard_normal(n), int(rng.integers(0, 3))) \
            + 1j * np.where(rng.random(n) < 0.3, np.round(rng.standard_normal(n), 1), 0.0)
        if rng.random() < 0.3:
            lam = np.concatenate([lam, np.conj(lam)])
        pairs = [min((abs(complex(a) - complex(b)) for j, b in enumerate(lam) if j != i), default=np.inf)
                 for i, a in enumerate(lam)]
        assert np.array_equal(nearest_gaps(lam), pairs)


def test_a_samples_cache_token_changes_with_its_data_and_survives_releasing_its_vectors():
    """Sample.uid keys the scan's caches: a new token when the point, the labels or the slopes
    change, the same when only the vectors go; tokens are objects of their own (no shared
    counter: a sample made in a scan worker cannot take the token of one made here), and a
    pickled sample keeps one token for its copies within one message."""
    import pickle

    from diskfriction.continuation.detection.samples import Sample
    from diskfriction.continuation.spectra.tracking import Eigensystem

    values = np.array([1.0 + 0j, 2.0 + 0j])
    a = Sample(0.0, np.zeros(3), values, np.zeros(2, int), 1e-12, np.zeros(2, bool),
               dlam=np.ones(2, complex), system=Eigensystem(values, np.eye(2), np.eye(2)))
    changed = [a.at(0.5), a.relabel(np.array([1, 0])), a.moved(a.x, a.tangent, np.zeros(2, complex))]
    assert all(b.uid is not a.uid for b in changed) and len({id(b.uid) for b in changed}) == 3
    lean = a.without_vectors()
    assert lean.system is None and lean.uid is a.uid
    copies = pickle.loads(pickle.dumps((a, lean)))
    assert copies[0].uid is copies[1].uid


def test_measured_work_is_what_the_block_spent_and_nests():
    """linalg.measured: the core's spending inside a block, read without resetting anything
    (an outer measurement keeps what an inner one saw); workers' counts booked with
    book_counts count in the block that books them."""
    from diskfriction.continuation.linalg.solves import book_counts, measured
    from diskfriction.continuation.spectra.tracking import eigensystem

    A = np.diag([1.0, 2.0, 3.0])
    with measured() as outer:
        eigensystem(A, False)
        with measured() as inner:
            eigensystem(A, False)
            book_counts((2, 1, 0, 5, 0, 0, 1))
    assert inner.counts() == (3, 1, 0, 5, 0, 0, 1)
    assert outer.counts() == (4, 1, 0, 5, 0, 0, 1)


def test_a_located_double_eigenvalue_must_be_the_pairs_own():
    """belongs_to_pair: over an interval where labels 0, 1 meet near lambda = 1 and labels 2, 3
    near lambda = 3, a double eigenvalue found at 3 is not the collision of (0, 1) (the locator
    started from one pair's model and converged on the other's), one found at 1 is."""
    from diskfriction.continuation.detection.detectors.fast import belongs_to_pair
    from diskfriction.continuation.detection.samples import make_sample
    from diskfriction.continuation.stepping.segment import Segment
    from diskfriction.continuation.spectra.tracking import Eigensystem
    from diskfriction.continuation.detection.verdicts import scaled_slopes

    x_a, x_b, t = np.array([0.0, 0.0]), np.array([0.0, 1.0]), np.array([0.0, 1.0])
    segment = Segment(None, x_a, x_b, 1e-12, 8)
    slopes = np.array([1.0, -1.0, 1.0, -1.0])
    a = make_sample(0.0, x_a, Eigensystem(np.array([0.5, 1.5, 2.5, 3.5], complex)), 1e-9, None, t, slopes)
    b = make_sample(1.0, x_b, Eigensystem(np.array([1.5, 0.5, 3.5, 2.5], complex)), 1e-9, None, t, slopes)
    d = scaled_slopes(a, b, segment)
    assert belongs_to_pair(a, b, 0, 1, 1.0, 1.0, 0.5, *d)
    assert not belongs_to_pair(a, b, 0, 1, 3.0, 1.0, 0.5, *d)
    assert belongs_to_pair(a, b, 2, 3, 3.0, 3.0, 0.5, *d)


def test_a_branch_that_jumps_within_a_step_fails_its_scan_instead_of_giving_a_collision():
    """G = (u1^2 - 1, u2): two branches u1 = -1 and u1 = +1 for every p, real eigenvalues of
    A = [[0, 1], [-u1, 0]] on the first, complex on the second, so no collision anywhere. A
    step whose corrector lands on the first for s < 1/2 and on the second from 1/2 on (as
    256 sheared disks' did across an S-shaped stretch of their branch) used to bisect down to
    min_ds and report a located birth there; now its scan fails with BranchJump, a
    SegmentSolveError, which rejects the step (scans.run_scan), as soon as the interval's
    ends lie JUMP_RATIO times farther apart than their tangents allow."""
    from dataclasses import dataclass

    from diskfriction.continuation.detection.collisions import BranchJump, DetectionParams, scan_step
    from diskfriction.continuation.stepping.segment import SegmentSolveError

    @dataclass(frozen=True)
    class Jumping(Segment):
        def point(self, s):
            x = np.array([-1.0 if s < 0.5 else 1.0, 0.0, s])
            self.remember(s, x.copy())
            return x

    problem = FunctionProblem(lambda u, p: np.array([u[0] ** 2 - 1, u[1]]),
                              lambda u, p: np.array([[2 * u[0], 0.0], [0.0, 1.0]]),
                              lambda u, p: np.zeros(2),
                              lambda u, p: np.array([[0.0, 1.0], [-u[0], 0.0]]))
    x_a, x_b = np.array([-1.0, 0.0, 0.0]), np.array([1.0, 0.0, 1.0])
    sigma = (x_b - x_a) / np.linalg.norm(x_b - x_a)
    t_a, t_b = tangent(problem, x_a, sigma), tangent(problem, x_b, sigma)
    a = sample_at(problem, 0.0, x_a, REL_TOL, None, t_a)
    b = sample_at(problem, 1.0, x_b, REL_TOL, a, t_b)
    assert not a.status.any() and b.status.all()  # all real at x_a, a complex pair at x_b
    with pytest.raises(BranchJump, match="the branch jumps between s = ") as jump:
        scan_step(problem, Jumping(problem, x_a, x_b, 1e-12, 10, t_a, t_b), a, b, DetectionParams(), 0)
    assert isinstance(jump.value, SegmentSolveError)
    s_a, s_b = (float(v) for v in re.findall(r"s = (\S+) and (\S+),", str(jump.value))[0])
    assert s_a < 0.5 <= s_b and s_b - s_a > 1e-6  # told by the tangents, long before min_ds


def test_a_partial_sample_whose_eigenvalue_continues_on_a_label_it_did_not_compute_is_told():
    """The partial sample knows labels 1 and 2; at the full sample to its right the eigenvalue
    continuing its label 1 (6.935, slope 0) sits on label 0. continuation_perm, matching only
    labels 1 and 2, would give label 1 the eigenvalue 7.064, and the interval between them
    could never be certified (256 disks: 70 partial samples creeping towards the full one);
    claimed_outside says so, and does not where labels 1 and 2 continue on themselves."""
    def sample(x_p, values, known=None):
        values = np.array(values, complex)
        n = values.size
        return Sample(0.0, np.array([0.0, x_p]), values, np.zeros(n, np.int8), 1e-12, np.zeros(n, bool),
                      np.array([0.0, 1.0]), np.zeros(n, complex), None, None,
                      label_gaps(values, np.zeros(n, bool), None), known)

    known = np.array([False, True, True, False])
    partial = sample(0.0, [np.nan, 6.935, 6.808, np.nan], known)
    crossed = sample(1e-9, [6.935, 7.064, 6.808, 7.235])
    assert claimed_outside(partial, crossed)
    assert continuation_perm(partial, crossed)[1] == 1  # the restricted match pairs it wrongly
    kept = sample(1e-9, [7.064, 6.935, 6.808, 7.235])
    assert not claimed_outside(partial, kept)


def test_nearest_predicted_is_the_dense_argmin_ties_and_all():
    """nearest_predicted (a k-d tree's candidates) returns exactly np.argmin of the whole
    prediction_cost matrix, rows by rows: on random spectra with conjugate pairs, values
    repeated up to six times (exact ties: the first index wins, and a row whose candidates
    all tie is computed whole), a value nearly tied in the last bits, and a non-finite one."""
    rng = np.random.default_rng(7)
    for trial in range(40):
        n = int(rng.integers(2, 300))
        values = rng.normal(size=n) + 1j * np.where(rng.random(n) < 0.3, rng.normal(size=n), 0.0)
        dlam = rng.normal(size=n) + 0j
        copies = rng.integers(0, n, size=int(rng.integers(0, 4)))
        into = rng.integers(0, n, size=copies.size)
        values[into], dlam[into] = values[copies], dlam[copies]  # exact ties
        if n > 8 and trial % 2:
            values[1:6], dlam[1:6] = values[n - 1], dlam[n - 1]  # more ties than candidates
        values[0] = values[n // 2] * (1.0 + 4e-16)
        ref = values + 1e-3 * rng.normal(size=n) * (trial % 3 != 0)  # every third: the same values
        ref_dlam = rng.normal(size=n) + 0j
        if trial % 7 == 6:
            ref[int(rng.integers(0, n))] = np.nan
        ds_ref, ds_new = 1e-3 * rng.random(), 1e-3 * rng.random()
        dense = np.argmin(prediction_cost(ref, ref_dlam, values, dlam, ds_ref, ds_new), axis=1)
        assert np.array_equal(nearest_predicted(ref, ref_dlam, values, dlam, ds_ref, ds_new), dense)


def test_predicted_match_costs_what_the_whole_assignment_costs():
    """predicted_match is a perm of least total prediction_cost (that of linear_sum_assignment
    over the whole matrix) where the nearest predictions are all different and where they
    collide (degenerate pairs, twelve labels predicted at one eigenvalue repeated twelve
    times); prediction_cost, built in rows, is the whole np.abs of the differences."""
    rng = np.random.default_rng(11)
    for trial in range(30):
        n = int(rng.integers(20, 400))
        values = np.sort(rng.normal(size=n)) + 1j * np.where(rng.random(n) < 0.3, 1e-2 * rng.normal(size=n), 0.0)
        dlam = rng.normal(size=n) + 0j
        pairs = rng.choice(n - 1, size=n // 10, replace=False)
        values[pairs], dlam[pairs] = values[pairs + 1], dlam[pairs + 1]  # degenerate pairs
        shuffle = rng.permutation(n)  # the labels continue eigenvalues in another order
        ref = values[shuffle] + 1e-3 * rng.normal(size=n)
        if trial % 3 == 0:  # a crowd beyond the candidates
            values[:12], dlam[:12] = values[12], dlam[12]
            ref[:12] = values[12] + 1e-9 * rng.normal(size=12)
        ref_dlam = rng.normal(size=n) + 0j
        cost = prediction_cost(ref, ref_dlam, values, dlam, 1e-3, 2e-3)
        assert np.array_equal(cost, np.abs((ref + 0.5e-3 * ref_dlam)[:, None] - (values - 1e-3 * dlam)[None, :]))
        perm = predicted_match(ref, ref_dlam, values, dlam, 1e-3, 2e-3)
        assert np.array_equal(np.sort(perm), np.arange(n))
        best = cost[np.arange(n), linear_sum_assignment(cost)[1]].sum()
        assert cost[np.arange(n), perm].sum() == pytest.approx(best, rel=1e-12, abs=1e-15)


def test_a_split_holds_every_label_a_later_test_refuses():
    """hermite_split's trouble is the union of every test's refusals, not the first one's: on
    an interval where a label is inconsistent (the label test refuses first) and a birth's
    members (1 and 3, real at the start) have a real eigenvalue between them (2: the event
    pair's clearance refuses it), the split's labels hold that eigenvalue too. A partial split
    computes only those labels and rests on every other being certified; with the first test's
    labels alone, the chain of 400 disks lost a short-lived pair (docs/notes/core-detection.md, A
    split holds every label any test refuses)."""
    from diskfriction.continuation.spectra.tracking import Kind
    from diskfriction.continuation.detection.verdicts import hermite_split

    def sample(s, values, status):
        values = np.array(values, complex)
        n = values.size
        return Sample(s, np.array([0.0, s]), values, np.array(status, np.int8), 1e-12, np.zeros(n, bool),
                      np.array([0.0, 1.0]), np.zeros(n, complex), None, None,
                      label_gaps(values, np.zeros(n, bool), None), None)

    # labels: 0 and 1 the birth's members, 2 between them, 3 inconsistent, 4 its neighbour
    a = sample(0.0, [1.0, 3.0, 2.0, 10.0, 10.3], [0, 0, 0, 0, 0])
    b = sample(1.0, [2.0 - 0.1j, 2.0 + 0.1j, 2.05, 10.6, 10.3], [-1, 1, 0, 0, 0])
    d_a = np.array([2.0, -2.0, 0.05, 0.0, 0.0], complex)
    d_b = np.array([0.0 - 0.2j, 0.0 + 0.2j, 0.05, 0.0, 0.0], complex)
    t, labels = hermite_split(a, b, d_a, d_b, [(0, 1, Kind.BIRTH)], np.ones(5, bool), RHO, DOUBT)
    assert labels[3]  # the label test's refusal, where the split is
    assert t == pytest.approx(0.5)
    assert labels[0] and labels[1] and labels[2]
