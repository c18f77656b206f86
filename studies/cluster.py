"""dask.distributed for the commands that run many independent tasks (ensembles, maps).

    with dask_client(scheduler, workers) as client:       # a scheduler, or a local cluster
        for key, result in as_finished(client, function, {key: args, ...}):
            save_json(path_of[key], result)                # each result written as it arrives

A local cluster has one single-threaded worker process per core (or `workers`); its workers
ignore SIGINT, so that a Ctrl-C to the terminal's process group reaches only this process,
which shuts them down in order (closing the client and the cluster) and lets the
KeyboardInterrupt end the command with one line (cli/common.py). Worker logs are silenced
below CRITICAL, so that nothing but the command's own lines reaches stderr. Tasks are
submitted with pure=False: each is run once, wherever the scheduler puts it; the caller keys
the results, so the order in which they finish changes nothing it writes.
"""
from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import signal
import threading
from typing import Callable, Hashable, Iterator, Optional

from diskfriction.errors import OneLineError
from diskfriction.files import source_digest

RUN_SOURCES = ("diskfriction", "diskfriction.scenes", "diskfriction.symbolic",
               "diskfriction.continuation", "diskfriction.dynamics", "diskfriction.models",
               "diskfriction.studies")
"""The packages a task's result depends on: its code version digests their sources (each
with its sub-packages). Every folder the studies reach (tests/test_layers.py): a folder left
out would leave map cells on disk that a rerun takes as current after an edit there."""

HTTP_ANY_PORT = {"dashboard_address": "127.0.0.1:0"}
"""The scheduler serves HTTP (health, metrics) even without a dashboard, by default on port
8787; when another cluster holds that port it warns on stderr and takes another. A free port
chosen by the system on localhost (no dashboard) avoids the warning."""


def code_version() -> str:
    """Digest of the sources a task's result depends on (RUN_SOURCES): resumable runs key
    their files with it, so that an edit of those sources makes the files on disk stale."""
    return source_digest(RUN_SOURCES)[:12]


def task_key(*parts) -> str:
    """16 hex digits of sha256 over `parts` as sorted JSON: the name of a task's result file,
    from everything the result depends on (its inputs and the code version)."""
    text = json.dumps(list(parts), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


class SchedulerUnreachable(OneLineError):
    """The dask scheduler given cannot be reached (or its address is malformed)."""


@contextlib.contextmanager
def workers_ignore_interrupts():
    """Ignore SIGINT while worker processes are started, so that they inherit SIG_IGN.

    A terminal sends Ctrl-C to the whole process group: without this every dask worker would
    die with a KeyboardInterrupt traceback while this process shuts them down in order. The
    disposition is process-wide, so a Ctrl-C during the start itself (about a second, a few
    on a loaded machine) is ignored too and has to be pressed again; afterwards this process
    handles it as before. (Blocking SIGINT instead of ignoring it does not keep it: dask's
    threads that do not block it take it, and discard it.) Only the main thread may set
    handlers: elsewhere this does nothing."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def local_workers(workers: Optional[int] = None) -> int:
    """Processes of the local cluster that dask_client starts: `workers`, or one per core
    (dask's CPU_COUNT, which heeds CPU affinity and cgroup limits)."""
    from dask.system import CPU_COUNT

    return workers or CPU_COUNT


@contextlib.contextmanager
def dask_client(scheduler: Optional[str] = None, workers: Optional[int] = None):
    """A dask.distributed Client on the scheduler at `scheduler` ([tcp://]HOST:PORT), else on
    a LocalCluster of `workers` single-threaded processes (None: one per core). Raises
    SchedulerUnreachable (one line) if the scheduler cannot be used; closes the client and the
    local cluster on leaving, also on an interrupt, ignoring a second Ctrl-C meanwhile (it
    would cut the shutdown short and leave workers behind)."""
    from dask.distributed import Client, LocalCluster

    cluster = client = None
    try:
        if scheduler is None:
            with workers_ignore_interrupts():
                cluster = LocalCluster(n_workers=local_workers(workers), threads_per_worker=1,
                                       processes=True, dashboard_address=None,
                                       scheduler_kwargs=HTTP_ANY_PORT, silence_logs=logging.CRITICAL)
        try:
            client = Client(scheduler or cluster)
        except (OSError, ValueError) as error:
            raise SchedulerUnreachable(f"cannot use the dask scheduler at {scheduler!r}: "
                                       f"{(str(error).splitlines() or [''])[0]}") from None
        yield client
    finally:
        with workers_ignore_interrupts():
            if client is not None:
                client.close()
            if cluster is not None:
                cluster.close()


def as_finished(client, function: Callable, tasks: dict[Hashable, tuple]
                ) -> Iterator[tuple[Hashable, object]]:
    """Submit function(*args) for every (key, args) of `tasks`; yield (key, result) in the
    order the tasks finish. A task's exception is raised here, when its turn comes."""
    from dask.distributed import as_completed

    futures = {client.submit(function, *args, pure=False): key for key, args in tasks.items()}
    for future in as_completed(futures):
        yield futures[future], future.result()
