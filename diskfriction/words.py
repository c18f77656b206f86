"""Numbers with their nouns, for lines a person reads: count(1, "collision") -> "1 collision"."""
from __future__ import annotations

from typing import Optional


def duration(seconds: float) -> str:
    """A wall time as a person says it: "0.4 s", "12 min", "3.1 h", "9.2 days"."""
    for unit, size in (("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= 2 * size:
            return f"{seconds / size:.2g} {unit}"
    return f"{seconds:.2g} s"


def count(n: int, noun: str, plural: Optional[str] = None) -> str:
    """"1 collision", "2 collisions", "1 equilibrium", "3 equilibria" (plural given)."""
    return f"{n} {noun if n == 1 else plural or noun + 's'}"
