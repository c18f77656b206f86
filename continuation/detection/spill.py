"""Arrays spilled to disk: eigenvectors a scan needs only later (collisions.StepScan._spill).

on_disk(a) writes a to a temporary file (tempfile's directory: TMPDIR) and maps it read-only:
the same values, which the operating system pages in on use and may drop again under memory
pressure (clean file pages, unlike the process's own memory).

Inside files_kept() (the continuation runs in it, arclength.continuation) a file whose mapping
is gone is kept, idle, and the next spill overwrites it in place instead of writing a new one.
Pages the kernel hands out afresh are slow to touch where the host of a virtual machine takes
back the memory its guest frees, and a new file for each spill of the chain of 1000 disks (288
MB a sample) would copy every spill into fresh page-cache pages. An idle file keeps its
pages. Files still mapped when the process forks are never reused (a child's inherited mapping
must keep its values): they are closed when their mapping is gone, as outside files_kept.
"""
from __future__ import annotations

import os
import tempfile
import weakref

import numpy as np

from diskfriction.continuation.linalg.solves import outermost

Array = np.ndarray

_idle: list = []  # files kept for reuse, no mapping of them left
_kept = [0]  # files_kept's nesting depth
_generation = [0]  # forks so far: files mapped in an earlier generation are never reused


def _forked() -> None:
    _generation[0] += 1


def _forked_child() -> None:
    _idle.clear()  # the parent's idle files are the parent's to reuse


if hasattr(os, "register_at_fork"):  # not on Windows, which has no fork
    os.register_at_fork(before=_forked, after_in_child=_forked_child)


def on_disk(a: Array) -> Array:
    """a written to a temporary file (an idle kept one, else a new unlinked one) and mapped
    read-only in its own memory order: a plain ndarray (compiled kernels take it) whose base
    keeps the map; the file goes back to the idle files, or is closed, with the last view of
    it (module docstring). OSError where the disk refuses."""
    fortran = a.flags.f_contiguous and not a.flags.c_contiguous
    f = _file(a.nbytes)
    try:
        np.ascontiguousarray(a.T if fortran else a).tofile(f)
        f.flush()
        mapped = np.memmap(f, dtype=a.dtype, mode="r", shape=a.shape, order="F" if fortran else "C")
    except BaseException:
        f.close()
        raise
    weakref.finalize(mapped, _release, f, _generation[0])
    return np.asarray(mapped)


def is_on_disk(a: Array) -> bool:
    """Whether a is (a view of) on_disk's mapped file."""
    while isinstance(a, np.ndarray):
        if isinstance(a, np.memmap):
            return True
        a = a.base
    return False


def _file(nbytes: int):
    """An idle file of nbytes if any, else any idle one cut to nbytes, else a new one; at its
    start."""
    if not _idle:
        return tempfile.TemporaryFile()
    sizes = [os.fstat(f.fileno()).st_size for f in _idle]
    k = sizes.index(nbytes) if nbytes in sizes else -1
    f = _idle.pop(k)
    f.seek(0)
    if sizes[k] > nbytes:
        f.truncate(nbytes)
    return f


def _release(f, generation: int) -> None:
    """The last mapping of f is gone: keep f for reuse inside files_kept (if it was mapped in
    this generation), else close it."""
    if _kept[0] and generation == _generation[0]:
        _idle.append(f)
    else:
        f.close()


def files_kept():
    """Context in which spilled files are kept for reuse (module docstring); on leaving, the
    idle ones are closed (their space freed). Nests."""
    return outermost(_kept, lambda: None, _close_idle)


def _close_idle() -> None:
    while _idle:
        _idle.pop().close()
