"""Fast collision detection against the exhaustive one on whole sweeps and a core problem:
the same collisions, about one spectrum per point; partial split samples, a spectral window,
samples released or spilled to disk, a failing locator and a window that crowds leave the
collisions the same."""
from __future__ import annotations

import numpy as np
import pytest

from diskfriction.continuation import ContinuationParams, DetectionParams, FunctionProblem, continuation
from diskfriction.continuation.linalg.solves import measured
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.scenes import Scene
from diskfriction.symbolic import System


AGREE = 1e-9  # the largest distance in p allowed between the two detections' locations


def locations(branch):
    return [(c.kind, c.p) for c in branch.collisions]


def assert_same_collisions(fast, exhaustive):
    assert [k for k, _ in fast] == [k for k, _ in exhaustive]
    assert np.max(np.abs(np.array([p for _, p in fast]) - [p for _, p in exhaustive])) <= AGREE


@pytest.mark.parametrize("scene, matrix, count", [(Scene(), "J", 22), (Scene(), "M^-1 J", 17),
                                                  (Scene(N=20, eps=1e-4), "J", 50)],
                         ids=["paper-J", "paper-M^-1J", "N20-eps1e-4"])
@pytest.mark.slow
def test_fast_detection_finds_the_exhaustive_collisions(scene, matrix, count, chain_sweep):
    """Same kinds in the same order, locations within 1e-9, on one branch (the detection does
    not change the steps); the counts are the measured ones (docs/notes/core-detection.md,
    The fast detection against the exhaustive one)."""
    runs = {mode: chain_sweep(scene, matrix, params=SweepParams(detection=DetectionParams(mode=mode)))[0]
            for mode in ("fast", "exhaustive")}  # conftest: run once, shared with the tests below
    assert np.array_equal(runs["fast"].F_x, runs["exhaustive"].F_x)
    assert len(runs["fast"].collisions) == count
    assert_same_collisions(locations(runs["fast"]), locations(runs["exhaustive"]))
    assert all(c.resolved for c in runs["fast"].collisions)


def cluster_problem(v=10.0, c=1e-3):
    """A fast eigenvalue v p sweeps past 1 (exact crossing), 2 (bubble: skew coupling) and 3
    (avoided crossing): A(p) = diag(v p, 1, 2, 3) + couplings; G = A(p) u, u = 0."""
    def A(p):
        M = np.diag([v * p, 1.0, 2.0, 3.0])
        M[0, 2], M[2, 0] = c, -c
        M[0, 3] = M[3, 0] = c
        return M

    dA = np.diag([v, 0.0, 0.0, 0.0])
    return FunctionProblem(lambda u, p: A(p) @ u, lambda u, p: A(p), lambda u, p: dA @ u)


@pytest.mark.parametrize("ds", [0.1, 0.13])
def test_fast_and_exhaustive_agree_on_a_core_problem_with_a_bubble(ds):
    """The bubble of a fast eigenvalue passing a cluster, with steps 250x its width."""
    problem = cluster_problem()
    par = ContinuationParams(ds=ds, ds_min=1e-9, ds_max=ds, newton_tol=1e-12, p_min=0.0, p_max=0.4)
    runs = [continuation(problem, np.zeros(4), 0.0, par, DetectionParams(mode=mode))
            for mode in ("fast", "exhaustive")]
    assert len(runs[0].collisions) == 2
    assert_same_collisions(locations(runs[0]), locations(runs[1]))


def test_fast_detection_spends_about_one_spectrum_per_point(chain_sweep):
    """The fast detection's point: full eigendecompositions per accepted point on the paper
    scene, against the exhaustive one's (measured: 2.1 and 14)."""

    spent = {}
    for mode in ("fast", "exhaustive"):  # the sweeps of test_fast_detection_finds_...[paper-J]
        detection = SweepParams(detection=DetectionParams(mode=mode))
        branch, spectra = chain_sweep(Scene(), "J", params=detection)
        spent[mode] = spectra / len(branch)
    assert spent["fast"] <= 3.0 and spent["exhaustive"] >= 4 * spent["fast"]


@pytest.mark.parametrize("partial_from", [None, 0], ids=["default", "partial-splits"])
@pytest.mark.slow
def test_a_spectral_window_lists_the_full_detection_s_collisions_in_it(partial_from, chain_sweep):
    """N = 40, eps = 1e-4: tracking only 0.0553 <= Re lambda / k_n <= 0.0562 by shift-invert
    gives the collisions of the full detection whose eigenvalue lies in the window, within
    1e-9, and counts the complex pairs there; also with every split sample partial where it
    can be (partial_from = 0: at N = 40 the default, n >= 240, takes none), which then takes
    partial samples."""

    system = System.from_scene(Scene(N=40, eps=1e-4))
    lo, hi = 0.0553 * system.scene.k_n, 0.0562 * system.scene.k_n
    full = chain_sweep(Scene(N=40, eps=1e-4), "J")[0]  # the same for both cases
    detection = DetectionParams() if partial_from is None else DetectionParams(partial_from=partial_from)
    with measured() as work:
        window = sweep(system, 0.0, 0.12, "J", SweepParams(window=(lo, hi), detection=detection))
    expected = [(c.kind, c.p) for c in full.collisions if lo <= c.eigenvalue <= hi]
    assert len(expected) >= 2 and window.window == (lo, hi)
    assert window.eigenvalues.shape[1] < system.ndof
    assert_same_collisions(locations(window), expected)
    assert (work.spectra_partial > 0) == (partial_from == 0)


@pytest.mark.parametrize("scene, matrix, k_max", [(Scene(), "J", 16), (Scene(), "M^-1 J", 16),
                                                  (Scene(), "J", 8), (Scene(N=20, eps=1e-4), "J", 16)],
                         ids=["paper-J", "paper-M^-1J", "paper-J-k8", "N20-eps1e-4"])
@pytest.mark.slow
def test_partial_split_samples_find_the_collisions_of_full_ones(scene, matrix, k_max):
    """Split samples as partial spectra (forced at every size: partial_from = 0) give the same
    collisions as full ones, to 1e-9, on the same branch, with fewer full spectra; k_max = 8
    sends more splits to the fallbacks (a full sample, upgrading the partial ones)."""

    system = System.from_scene(scene)
    runs, spent = {}, {}
    for partial_from in (0, 10**9):
        detection = DetectionParams(partial_from=partial_from, partial_max_k=k_max)
        with measured() as work:
            runs[partial_from] = sweep(system, 0.0, 0.12, matrix, SweepParams(detection=detection))
        spent[partial_from] = (work.spectra, work.spectra_partial)
    assert np.array_equal(runs[0].F_x, runs[10**9].F_x)
    assert_same_collisions(locations(runs[0]), locations(runs[10**9]))
    assert all(c.resolved for c in runs[0].collisions)
    assert spent[10**9][1] == 0 < spent[0][1] and spent[0][0] < spent[10**9][0]


def test_a_partial_sample_matches_the_full_one_on_its_labels_or_declines():
    """partial_sample_at on a problem with a known spectrum: the labels asked for carry the
    full sample's eigenvalues, slopes and status, the others nan; gaps never exceed the true
    ones; a disc that cannot cover the labels (k too small) gives None."""
    from diskfriction.continuation.detection.samples import partial_sample_at, sample_at

    n = 12
    base = np.diag(np.arange(1.0, n + 1.0))
    skew = np.zeros((n, n))
    skew[4, 5], skew[5, 4] = 0.3, -0.3  # the pair 5, 6 moves towards a collision at p = 0.5/0.6
    problem = FunctionProblem(lambda u, p: (base + p * skew) @ u, lambda u, p: base + p * skew,
                              lambda u, p: skew @ u)
    t = np.zeros(n + 1)
    t[-1] = 1.0
    x0, x1 = np.append(np.zeros(n), 0.5), np.append(np.zeros(n), 0.6)
    left = sample_at(problem, 0.0, x0, 1e-9, None, t)
    full = sample_at(problem, 1.0, x1, 1e-9, left, t)
    labels = np.flatnonzero(np.abs(left.eigvals - 5.5) < 1.0)
    assert labels.size == 2
    part = partial_sample_at(problem, 1.0, x1, left, [(labels, 5.5, 6)], t)
    assert part is not None and part.known.sum() == 2
    assert np.allclose(part.eigvals[labels], full.eigvals[labels], atol=1e-10)
    assert np.allclose(part.dlam[labels], full.dlam[labels], atol=1e-6)
    assert np.array_equal(part.status, full.status)
    assert np.all(np.isnan(part.eigvals[part.known == 0]))
    assert np.all(part.gaps[labels] <= full.gaps[labels] + 1e-12)
    assert partial_sample_at(problem, 1.0, x1, left, [(labels, 5.5, 2)], t) is None


@pytest.mark.slow
def test_settled_samples_drop_their_vectors_and_the_scan_finds_the_same(monkeypatch):
    """A scan drops the eigenvectors of inner samples whose two intervals are settled (clean,
    narrow or with every event located; full neighbours): at the end of every scan of the
    N = 20 sweep no inner sample between two full ones holds vectors (an interval with a
    located collision included), and without the release (monkeypatched away) the branch and
    its collisions are exactly the same."""
    from diskfriction.continuation.detection.collisions import StepScan

    system = System.from_scene(Scene(N=20, eps=1e-4))
    released, inner, held = [], [], []
    run = StepScan.run

    def counting_run(self):
        found = run(self)
        S = self.samples
        inner.append(len(S) - 2)
        released.append(sum(s.system is None and s.tangent is not None for s in S[1:-1]))
        held.extend(k for k in range(1, len(S) - 1) if S[k].system is not None
                    and not (S[k - 1].partial or S[k].partial or S[k + 1].partial))
        return found

    monkeypatch.setattr(StepScan, "run", counting_run)
    lean = sweep(system, 0.0, 0.12, "J", SweepParams(workers=0))
    assert 0 < sum(released) <= sum(inner)
    assert held == []
    assert len(lean.collisions) > 0
    monkeypatch.setattr(StepScan, "release_vectors", lambda self: None)
    released.clear()
    kept = sweep(system, 0.0, 0.12, "J", SweepParams(workers=0))
    assert sum(released) == 0
    assert np.array_equal(lean.F_x, kept.F_x) and np.array_equal(lean.eigenvalues, kept.eigenvalues)
    assert [(c.p, c.kind, c.pair) for c in lean.collisions] == [(c.p, c.kind, c.pair) for c in kept.collisions]


@pytest.mark.slow
def test_samples_spilled_to_disk_leave_the_scan_unchanged(monkeypatch):
    """With no memory for inner samples' vectors (SCAN_MEMORY = 0) a scan keeps in memory only
    the ends of the interval it works on and maps the others from disk (Sample.spilled): the
    N = 20 sweep (partial samples forced) spills samples, and its branch and collisions are
    exactly those of the sweep that keeps them all in memory, and so are they where the disk
    refuses (OSError: the samples stay in memory). on_disk keeps values and memory order,
    read-only."""
    from diskfriction.continuation.detection import collisions
    from diskfriction.continuation.detection.samples import Sample
    from diskfriction.continuation.detection.spill import is_on_disk, on_disk

    a = np.asfortranarray(np.arange(12.0).reshape(3, 4) * (1 + 2j))
    for x in (a, np.ascontiguousarray(a)):
        y = on_disk(x)
        assert np.array_equal(x, y) and y.flags.f_contiguous == x.flags.f_contiguous
        assert is_on_disk(y) and is_on_disk(y[:, 1]) and not is_on_disk(x) and not y.flags.writeable

    system = System.from_scene(Scene(N=20, eps=1e-4))
    params = SweepParams(detection=DetectionParams(partial_from=0), workers=0)  # partial samples too
    kept = sweep(system, 0.0, 0.12, "J", params)
    spilled = []
    spill = Sample.spilled

    def counting(self):
        spilled.append(self.s)
        return spill(self)

    monkeypatch.setattr(collisions, "SCAN_MEMORY", 0)
    monkeypatch.setattr(Sample, "spilled", counting)
    lean = sweep(system, 0.0, 0.12, "J", params)
    assert len(spilled) > 10
    assert np.array_equal(lean.F_x, kept.F_x) and np.array_equal(lean.eigenvalues, kept.eigenvalues)
    assert [(c.p, c.kind, c.pair) for c in lean.collisions] == [(c.p, c.kind, c.pair) for c in kept.collisions]

    def full_disk(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr("tempfile.TemporaryFile", full_disk)  # the samples stay in memory
    refused = sweep(system, 0.0, 0.12, "J", params)
    assert np.array_equal(refused.eigenvalues, kept.eigenvalues) and len(refused.collisions) == len(kept.collisions)


@pytest.mark.slow
def test_a_failing_locator_costs_partial_samples_and_finds_the_same_collisions(monkeypatch):
    """Where the locator fails, the event's interval is split by a partial sample of the event
    pairs' labels (with partial samples forced, partial_from = 0): with every locator call
    failing, the N = 10 sweep brackets each collision to tol_p and reports the same collisions
    within 1e-9, with at most 3 full spectra per collision beyond the sweep whose locator
    works. The labels split for are every event's with their partners and every refusing
    test's (verdicts.hermite_split): a sample of the failed pair's labels alone would miss a
    death of another event pair at N = 20 (docs/notes/core-detection.md, The locator; A split
    holds every label any test refuses)."""
    from diskfriction.continuation.detection.detectors import fast
    from diskfriction.continuation.detection.locate import LocatorFailed

    system = System.from_scene(Scene(N=10, eps=1e-4))
    params = SweepParams(detection=DetectionParams(partial_from=0), workers=0)
    with measured() as working:
        located = sweep(system, 0.0, 0.12, "J", params)

    def failing(*args, **kwargs):
        raise LocatorFailed("forced")

    monkeypatch.setattr(fast, "locate_double_eigenvalue", failing)
    with measured() as failed:
        bracketed = sweep(system, 0.0, 0.12, "J", params)
    assert len(located.collisions) > 10
    assert [c.kind for c in bracketed.collisions] == [c.kind for c in located.collisions]
    assert np.max(np.abs([a.p - b.p for a, b in zip(bracketed.collisions, located.collisions)])) <= 1e-9
    assert failed.spectra_partial > working.spectra_partial
    assert failed.spectra - working.spectra <= 3 * len(located.collisions)


@pytest.mark.slow
def test_a_chain_window_that_crowds_is_widened_and_finds_the_same_collisions(monkeypatch):
    """N = 20, eps = 1e-4, window [0, 0.02] k_n sized with one eigenvalue to spare: it crowds
    along the sweep, is sized anew, wider, at the last certified point and the sweep goes on.
    The same 20 collisions as a generous window, of the same kinds, within 1e-9: the steps after
    the restart differ, and the history makes the branch depend on its steps by up to 5.9e-10
    (docs/notes/core-stepping.md, Step dependence of the chain's branch)."""
    from diskfriction.continuation.spectra import window as spectral_window
    from diskfriction.models.chain.sweep import SweepParams, sweep

    system = System.from_scene(Scene(N=20, eps=1e-4))
    window = SweepParams(window=(0.0, 40.0))
    generous = sweep(system, 0.0, 0.12, params=window)
    sized = spectral_window.sized

    def tightly_sized(w, problem, u, p):  # at the start; widened with the window's own margins
        return w if w.k else sized(w, problem.stability_structure(u, p).shifted(), 1.0, 1)

    monkeypatch.setattr(spectral_window.SpectralWindow, "prepared", tightly_sized)
    tight = sweep(system, 0.0, 0.12, params=window)
    assert generous.widenings == 0 and tight.widenings >= 1
    assert tight.status.reached and np.all(np.diff(tight.F_x) > 0)
    assert [c.kind for c in tight.collisions] == [c.kind for c in generous.collisions]
    assert len(generous.collisions) == 20
    assert np.abs(np.array([c.p for c in tight.collisions])
                  - [c.p for c in generous.collisions]).max() <= 1e-9
