"""Scans of accepted steps on worker processes (continuation/detection/scans.py): the same branch and
collisions as inline scans, a failed scan's step rejected after the continuation went on, and
workers' errors and lifetimes."""
from __future__ import annotations

import multiprocessing

import numpy as np
import pytest

from diskfriction.continuation.stepping import arclength
from diskfriction.continuation.detection.collisions import DetectionParams
from diskfriction.continuation.linalg.solves import measured
from diskfriction.continuation.problem import FunctionProblem, Problem
from diskfriction.continuation.detection.scans import (InlineScans, ScanJob, ScanOutcome, WorkerError, WorkerScans,
                                             default_workers, has_snapshots)
from diskfriction.models.chain.sweep import SweepParams, sweep
from diskfriction.scenes import Scene
from diskfriction.symbolic import System
from invariants import unaccounted_pair_changes


def run(system, workers):
    with measured() as work:
        branch = sweep(system, 0.0, 0.12, "J", SweepParams(workers=workers))
    return branch, work.counts()


def assert_same_branch(a, b, tol_p=1e-12):
    """The same points and histories exactly; each point's eigenvalues the same set; the same
    collisions in order, at the same double eigenvalue. Labels may differ: after a death the
    two real eigenvalues' labels are a tie, which either run may break its way (at N = 20 a
    pair born and dead within step 18 names 33 or 35 the one that collides next)."""
    assert np.array_equal(a.F_x, b.F_x) and np.array_equal(a.q, b.q) and np.array_equal(a.xi, b.xi)
    assert np.array_equal(np.sort_complex(a.eigenvalues), np.sort_complex(b.eigenvalues))
    assert np.array_equal(a.n_complex, b.n_complex) and np.array_equal(a.free, b.free)
    assert [c.kind for c in a.collisions] == [c.kind for c in b.collisions]
    assert np.max(np.abs([c.p - d.p for c, d in zip(a.collisions, b.collisions)])) <= tol_p
    assert np.max(np.abs([c.eigenvalue - d.eigenvalue for c, d in zip(a.collisions, b.collisions)])) <= 1e-9


@pytest.mark.parametrize("eps", [1e-4, 0.0], ids=["eps1e-4", "eps0"])
@pytest.mark.slow
def test_two_workers_give_the_inline_branch(eps):
    """N = 20, 50 collisions (eps = 1e-4) or 24 with free disks (eps = 0): the workers' scans
    give the inline branch, and the work they did is booked in this process."""
    system = System.from_scene(Scene(N=20, eps=eps))
    (inline, spent_inline), (parallel, spent_parallel) = run(system, 0), run(system, 2)
    assert len(inline.collisions) >= 20  # births and deaths enough to compare
    assert unaccounted_pair_changes(inline.F_x, inline.n_complex, [(c.p, c.kind) for c in inline.collisions]) == []
    assert_same_branch(inline, parallel)
    assert spent_parallel[0] >= len(parallel) and spent_parallel[2] >= 0.9 * spent_inline[2]


class Deferred(InlineScans):
    """Scans at submission, in the state of the step's start as a worker would, but none is
    ready before the continuation stops or has `depth` scans pending; the first scan of step
    `fail` fails (as a corrector failure inside the step would)."""

    def __init__(self, problem, fail, ready):
        super().__init__(problem)
        self.fail, self.is_ready, self.failed = fail, ready, 0

    def submit(self, job: ScanJob) -> int:
        if job.step == self.fail and not self.failed:
            self.failed += 1
            self._tickets += 1
            self._done[self._tickets] = ScanOutcome(None, "collision scan: injected", (0, 0, 0, 0))
            return self._tickets
        return super().submit(job)

    def ready(self, ticket: int) -> bool:
        return self.is_ready


@pytest.mark.slow
def test_a_failed_scan_rejects_its_step_after_the_branch_went_on(monkeypatch, chain_sweep):
    """Step 20's scan fails. Inline, the step is retried at once with half the arclength; with
    the scans deferred, the continuation has reached the end by then and returns to step 20's
    committed state. Both give the same branch: points, histories (the callback sees each
    point's committed state), eigenvalues and collisions."""
    system = System.from_scene(Scene())
    branches = []
    for ready in (True, False):
        scans = Deferred(None, 20, ready)

        def scans_for(problem, workers, scans=scans):
            scans.problem = problem
            return scans

        monkeypatch.setattr(arclength, "scans_for", scans_for)
        monkeypatch.setattr(arclength, "default_workers", lambda problem, n, detection, asked, eigensolver: 1)
        branches.append(sweep(system, 0.0, 0.12, "J"))
        assert scans.failed == 1 and not scans._done
    inline, deferred = branches
    assert inline.collisions
    assert unaccounted_pair_changes(inline.F_x, inline.n_complex, [(c.p, c.kind) for c in inline.collisions]) == []
    assert_same_branch(inline, deferred)
    monkeypatch.undo()
    plain = chain_sweep(Scene(), "J")[0]  # conftest: the paper's sweep, shared
    # up to step 20's start as without the failure, then a shorter step
    assert np.array_equal(plain.F_x[:21], inline.F_x[:21]) and inline.F_x[21] < plain.F_x[21]


LINEAR = FunctionProblem(lambda u, p: u - p, lambda u, p: np.eye(u.size), lambda u, p: -np.ones(u.size))


class Snapshots(Problem):
    """A stateful problem (its committed p shifts G) with snapshots; restore(None) raises."""

    def __init__(self):
        self.c = 0.0

    def residual(self, u, p):
        return u - p - self.c

    def jacobian(self, u, p):
        return np.eye(u.size)

    def dG_dp(self, u, p):
        return -np.ones(u.size)

    def commit(self, u_old, p_old, u_new, p_new):
        self.c = 0.0

    def state(self):
        return self.c

    def restore(self, snapshot):
        if snapshot is None:
            raise RuntimeError("no snapshot")
        self.c = snapshot


class NoSnapshots(Snapshots):
    state, restore = Problem.state, Problem.restore


def test_workers_by_default_and_on_request():
    fast, exhaustive = DetectionParams(), DetectionParams(mode="exhaustive")
    assert has_snapshots(LINEAR) and has_snapshots(Snapshots()) and not has_snapshots(NoSnapshots())
    assert default_workers(LINEAR, 30, fast) == 0  # small: inline
    assert default_workers(LINEAR, 300, exhaustive, 2) == 0  # its stencil needs the previous scan
    assert default_workers(NoSnapshots(), 300, fast) == 0
    assert default_workers(LINEAR, 30, fast, 3) == 3
    with pytest.raises(ValueError, match="NoSnapshots commits a state"):
        default_workers(NoSnapshots(), 300, fast, 2)
    with pytest.raises(ValueError, match="workers must be >= 0"):
        default_workers(LINEAR, 300, fast, -1)


def _default_in(conn):
    conn.send(default_workers(LINEAR, 300, DetectionParams()))


def test_a_daemonic_process_scans_inline():
    """A daemonic process (a dask worker by default, e.g. a map's cell) may not start children."""
    context = multiprocessing.get_context("fork")
    here, there = context.Pipe()
    child = context.Process(target=_default_in, args=(there,), daemon=True)
    child.start()
    assert here.recv() == 0
    child.join()


def test_a_worker_error_is_raised_here_and_workers_end():
    problem = Snapshots()
    x = np.array([0.0, 0.0])
    scans = WorkerScans(problem, 2)
    job = ScanJob(None, x, x + 0.1, 1e-10, 8, None, None, DetectionParams(), 0)
    ticket = scans.submit(job)
    with pytest.raises(WorkerError, match="in a scan worker: RuntimeError: no snapshot"):
        scans.result(ticket)
    scans.close()
    assert not any(proc.is_alive() for proc in scans._procs)


def test_a_dead_worker_is_one_line():
    """A worker killed (by the kernel for memory, say): the sweep stops with a OneLineError,
    which the command line prints as one line, exit 1."""
    from diskfriction.errors import OneLineError

    x = np.array([0.0, 0.0])
    with WorkerScans(Snapshots(), 1) as scans:
        scans._procs[0].kill()
        scans._procs[0].join()
        with pytest.raises(OneLineError, match="a scan worker died"):
            scans.result(scans.submit(ScanJob(0.0, x, x + 0.1, 1e-10, 8, None, None, DetectionParams(), 0)))

