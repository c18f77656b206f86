"""Collision scans of accepted steps: inline, or on worker processes while the branch goes on.

The scan of a step (collisions.scan_step) needs only the step's end points, the samples there
and the problem's state committed at its start (Problem.state). Its labels continue those of
the start sample, whatever they are: a scan from a relabelled start is the same scan
relabelled (up to ties between labels, such as the two real eigenvalues after a death, which
the labels' order breaks). So the continuation may commit a step and go on while the step is scanned
elsewhere, tracking its accepted points' labels directly from one another; when a scan comes
back, its collisions and the labels of the points after it follow from one permutation
(arclength.py). A scan that fails rejects its step: the continuation returns to the state
committed at the step's start, and the scans of later steps are dropped.

InlineScans scans at once, in this process (the problem is still in the step's start state).
WorkerScans forks worker processes that each hold a copy of the problem as it was at the fork,
restore the job's state, scan and send back the ScanResult with what it cost (solves.book).
Fork, not spawn: a worker inherits the compiled kernels instead of compiling them again. Jobs
go to idle workers in order of submission; results are taken in any order and kept until asked
for.
"""
from __future__ import annotations

import multiprocessing
import os
import signal
import sys
from dataclasses import dataclass
from multiprocessing.connection import wait
from typing import Optional

import numpy as np
import scipy.sparse

from diskfriction.errors import OneLineError

from diskfriction.continuation.detection.collisions import DetectionParams, ScanResult, scan_step
from diskfriction.continuation.linalg.solves import (DIRECT, LinearSolver, SingularMatrix, blas_threads, book_counts,
                                                     measured)
from diskfriction.continuation.problem import Problem
from diskfriction.continuation.detection.samples import Sample
from diskfriction.continuation.stepping.segment import Segment, SegmentSolveError
from diskfriction.continuation.spectra.eigensolvers import DEFAULT, Eigensolver
from diskfriction.continuation.spectra.tracking import GPU_FROM, on_gpu
from diskfriction.continuation.spectra.window import WindowCrowded

Array = np.ndarray

PARALLEL_FROM = 60
"""Stability matrix size from which scans go to workers by default (N = 20 disks with rotation):
below it a scan costs less than shipping it, and the paper's scene (n = 30) is scanned inline."""
WORKER_NICENESS = 10
"""Scan workers run this much nicer than the continuation: the continuation's steps are the
run's critical path (each needs the last one's committed state), the scans fill the cores
around them."""
PENDING_BYTES = 2 ** 30
"""Eigenvectors the continuation may hold in steps whose scans are pending (pending_full)."""


@dataclass(frozen=True)
class ScanJob:
    """The scan of accepted step `step` from x_a to x_b (collisions.scan_step's arguments);
    state: the problem's state committed at x_a (Problem.state); tol, max_iter, linear_solver:
    the corrector of the step's intermediate points (segment.Segment); eigensolver: their
    spectra's (eigensolvers.py)."""

    state: object
    x_a: Array
    x_b: Array
    tol: float
    max_iter: int
    start: Sample
    end: Sample
    detection: DetectionParams
    step: int
    previous: Optional[Sample] = None
    ends_at_event: bool = False
    linear_solver: LinearSolver = DIRECT
    eigensolver: Eigensolver = DEFAULT


@dataclass(frozen=True)
class ScanOutcome:
    """A scan's result, or why it failed (failure: the step is rejected, as when its corrector
    fails); spent: the solves.Work counts the scan spent (solves.measured); crowded: the
    failure is a spectral window that no longer covers its guard bands (WindowCrowded: the run
    ends at the step's start, a shorter step would not help)."""

    result: Optional[ScanResult]
    failure: Optional[str]
    spent: tuple
    crowded: bool = False


def run_scan(problem: Problem, job: ScanJob) -> ScanOutcome:
    """Scan job's step on `problem`, which is in job.state."""
    result, failure, crowded = None, None, False
    with measured() as spent:
        try:
            result = scan_step(problem, Segment(problem, job.x_a, job.x_b, job.tol, job.max_iter,
                                                    job.start.tangent, job.end.tangent, chord=True,
                                                    linear_solver=job.linear_solver),
                               job.start, job.end, job.detection, job.step, job.previous,
                               job.ends_at_event, job.eigensolver)
        except SegmentSolveError as err:
            failure = f"collision scan: {err}"
        except SingularMatrix as err:
            failure = f"singular matrix: {err}"
        except WindowCrowded as err:
            failure, crowded = str(err), True
    return ScanOutcome(result, failure, spent.counts(), crowded)


class WorkersOnGpu(OneLineError, ValueError):
    """Scan workers asked for where the spectra run on a GPU (planned_workers)."""

    exit_code = 2


def default_workers(problem: Problem, n: int, detection: DetectionParams,
                    asked: Optional[int] = None, eigensolver: Eigensolver = DEFAULT) -> int:
    """Workers for `problem`, whose stability matrix is n x n, its spectra by `eigensolver`:
    planned_workers, or 0 (inline) for a problem whose committed state cannot be shipped
    (has_snapshots); asking for workers explicitly for such a problem raises ValueError."""
    workers = planned_workers(n, detection, asked, dense=eigensolver.dense, gpu=eigensolver.on_gpu(n))
    if workers and not has_snapshots(problem):
        if asked is not None:
            raise ValueError(f"{type(problem).__name__} commits a state but has no state()/restore(): "
                             "its steps cannot be scanned on workers (workers=0)")
        return 0
    return workers


def planned_workers(n: int, detection: DetectionParams, asked: Optional[int] = None,
                    dense: bool = True, gpu: Optional[bool] = None) -> int:
    """Scan workers for an n x n stability matrix: 0 (inline) unless the detector's scans are
    independent (Detector.parallel: the exhaustive one's stencil is a sample of the previous
    step, known only once that step's scan is done); then `asked` if given (0: every scan
    inline), else 2 from n = PARALLEL_FROM on, on Linux, when this process may use 2 cores or
    more and is not daemonic. Always 0 where dense spectra are taken (`dense`: the eigensolver
    is no spectral window, Eigensolver.dense) and run on a GPU (`gpu`, None: tracking.on_gpu
    on spectra_on's device): the GPU does the heavy part, and a forked worker cannot use the
    CUDA context this process started. ValueError for asked < 0, or asked > 0 with dense
    spectra on a GPU."""
    if asked is not None and asked < 0:
        raise ValueError(f"workers must be >= 0 (or None: automatic), got {asked}")
    if not (detection.enabled and detection.detector.parallel):
        return 0
    if dense and (on_gpu(n) if gpu is None else gpu):
        if asked:
            raise WorkersOnGpu(f"--workers: the spectra run on the GPU (--device gpu, or auto from "
                               f"n = {GPU_FROM}), where the scans run inline; ask for --device cpu "
                               f"to scan on workers (got {asked})")
        return 0
    if asked is not None:
        return asked
    if n < PARALLEL_FROM or not sys.platform.startswith("linux"):
        return 0  # fork is the start method there (macOS has fork, but it is not safe to use)
    if multiprocessing.current_process().daemon:
        return 0  # a daemonic process (a dask worker, say) may not start children
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
    return 2 if cores >= 2 else 0


def has_snapshots(problem: Problem) -> bool:
    """Whether a worker can be put in the problem's committed state: it commits none (no
    commit()) or it implements state() and restore()."""
    cls = type(problem)
    return cls.commit is Problem.commit or (cls.state is not Problem.state and cls.restore is not Problem.restore)


def pending_full(workers: int, ends: list) -> bool:
    """Whether the continuation must wait for the oldest pending scan: the end samples of the
    pending steps (`ends`; None for a step whose commit found no equilibrium) are more than 2
    per worker (one running, one queued) and hold more than PENDING_BYTES of eigenvectors
    (with their matrix derivatives),
    counted as they are (a sample at eps = 0 grows as the load reaches more disks). A deep
    queue lets the continuation run ahead through quiet steps while the workers are on crowded
    ones."""
    return len(ends) > 2 * workers and sum(_vector_bytes(end) for end in ends if end is not None) > PENDING_BYTES


def _vector_bytes(sample: Sample) -> int:
    """The bytes of the sample's eigenvectors and of the matrix derivative kept with them."""
    vectors, dA = sample.vectors_in_memory, sample.dA
    if dA is None:
        return vectors
    if scipy.sparse.issparse(dA):
        parts = ("data", "indices", "indptr", "row", "col", "offsets")
        return vectors + sum(getattr(dA, k).nbytes for k in parts if hasattr(dA, k))
    return vectors + dA.nbytes


class InlineScans:
    """Scans run at submission, in this process."""

    def __init__(self, problem: Problem):
        self.problem = problem
        self._done: dict[int, ScanOutcome] = {}
        self._tickets = 0

    def submit(self, job: ScanJob) -> int:
        self._tickets += 1
        self._done[self._tickets] = run_scan(self.problem, job)
        return self._tickets

    def ready(self, ticket: int) -> bool:
        return True

    def result(self, ticket: int) -> ScanOutcome:
        return self._done.pop(ticket)

    def discard(self, tickets) -> None:
        for t in tickets:
            self._done.pop(t, None)

    def close(self) -> None:
        pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        pass


class WorkerError(OneLineError):
    """A worker process raised an unexpected exception (type and message are this one's) or
    died (killed for memory, say): the command says so in one line, exit 1."""


def _serve(problem: Problem, conn) -> None:
    """A worker's loop, at WORKER_NICENESS: (ticket, job) in, (ticket, outcome or the error in
    one line) out; None ends it. Ctrl-C reaches the whole process group: the worker ignores it
    (it starts with SIGINT blocked: WorkerScans) and the parent, leaving the sweep, ends it."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    os.nice(WORKER_NICENESS)
    with blas_threads():
        while True:
            message = conn.recv()
            if message is None:
                return
            ticket, job = message
            try:
                problem.restore(job.state)
                reply = run_scan(problem, job)
            except Exception as err:  # noqa: BLE001 - the problem's own functions run here
                reply = f"{type(err).__name__}: {err}"
            conn.send((ticket, reply))


class WorkerScans:
    """Scans on `workers` forked processes (module docstring). Use as a context manager, or
    call close(): the workers end with it.

    The workers are forked with SIGINT blocked: a Ctrl-C during a fork would otherwise be
    handled in an at-fork callback (logging's lock release), where Python prints it as an
    ignored exception and drops it (the run goes on), or in a child before it ignores SIGINT
    (_serve). Blocked, it waits until the workers are started, is raised here, and they are
    ended."""

    def __init__(self, problem: Problem, workers: int):
        context = multiprocessing.get_context("fork")
        self._conns, self._procs = [], []
        self._queue: list[tuple[int, ScanJob]] = []
        self._done: dict[int, ScanOutcome] = {}
        self._dropped: set[int] = set()
        self._tickets = 0
        mask = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            for _ in range(workers):
                parent, child = context.Pipe()
                proc = context.Process(target=_serve, args=(problem, child), daemon=True)
                proc.start()
                child.close()
                self._conns.append(parent)
                self._procs.append(proc)
        finally:
            try:
                signal.pthread_sigmask(signal.SIG_SETMASK, mask)  # a Ctrl-C meanwhile: raised here
            except KeyboardInterrupt:
                self.close(grace=0.0)
                raise
        self._idle = list(self._conns)

    def submit(self, job: ScanJob) -> int:
        self._tickets += 1
        self._queue.append((self._tickets, job))
        self._dispatch()
        return self._tickets

    def _dispatch(self) -> None:
        while self._idle and self._queue:
            try:
                self._idle.pop(0).send(self._queue.pop(0))
            except (BrokenPipeError, ConnectionResetError):
                raise WorkerError("a scan worker died") from None

    def _receive(self, timeout: Optional[float]) -> None:
        busy = [c for c in self._conns if c not in self._idle]
        for conn in wait(busy, timeout):
            try:
                ticket, reply = conn.recv()
            except EOFError:
                raise WorkerError("a scan worker died") from None
            self._idle.append(conn)
            if ticket in self._dropped:  # its step was rejected: whatever came back is moot
                self._dropped.discard(ticket)
            elif isinstance(reply, str):
                raise WorkerError(f"in a scan worker: {reply}")
            else:
                self._done[ticket] = reply
        self._dispatch()

    def ready(self, ticket: int) -> bool:
        self._receive(0.0)
        return ticket in self._done

    def result(self, ticket: int) -> ScanOutcome:
        while ticket not in self._done:
            self._receive(None)
        outcome = self._done.pop(ticket)
        book_counts(outcome.spent)  # spent in the worker
        return outcome

    def discard(self, tickets) -> None:
        """Forget these scans: queued ones are not sent, running ones' results are dropped."""
        tickets = set(tickets)
        queued = {t for t, _ in self._queue} & tickets
        self._queue = [(t, j) for t, j in self._queue if t not in queued]
        for t in tickets - queued:
            if self._done.pop(t, None) is None:
                self._dropped.add(t)

    def close(self, grace: float = 5.0) -> None:
        """End the workers: each finishes its scan (at most `grace` seconds) or is killed."""
        for conn in self._conns:
            try:
                conn.send(None)
            except (BrokenPipeError, OSError):
                pass
        for proc in self._procs:
            proc.join(timeout=grace)
            if proc.is_alive():
                proc.kill()
                proc.join()
        for conn in self._conns:
            conn.close()

    def __enter__(self):
        return self

    def __exit__(self, kind, value, tb):
        self.close(grace=0.0 if kind is not None else 5.0)  # interrupted: no scan is awaited


def scans_for(problem: Problem, workers: int):
    """WorkerScans with `workers` processes, or InlineScans if workers is 0 (context managers:
    leaving one ends its workers)."""
    return WorkerScans(problem, workers) if workers > 0 else InlineScans(problem)
