"""The machine's memory, and the one check made before a large allocation.

Bottom layer (beside files.py): anybody may import it. A layer that knows what it is about to
hold (a sweep's dense matrices, a run's frames) estimates the bytes and calls
`require_memory`, so that a scene or a run too large for this machine is refused with one line
before anything is allocated, instead of a MemoryError deep inside numpy (or the kernel's
out-of-memory killer).
"""
from __future__ import annotations

import os

from diskfriction.errors import OneLineError


class NotEnoughMemory(OneLineError, MemoryError):
    """What would not fit, and how much memory the machine has; str() is one line."""

    exit_code = 2


def physical_memory() -> int:
    """This machine's physical memory [bytes]."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")


def size(nbytes: float) -> str:
    """A byte count for people: 1.5 GB, 720 GB, 3.6e+12 GB."""
    return f"{nbytes / 1e9:.3g} GB"


def require_memory(nbytes: float, what: str) -> None:
    """Raise NotEnoughMemory when `what` needs more than the machine's physical memory."""
    have = physical_memory()
    if nbytes > have:
        raise NotEnoughMemory(f"{what} needs about {size(nbytes)} of memory, more than this "
                              f"machine's {size(have)}")
