"""Numbers with their nouns, for lines a person reads: count(1, "collision") -> "1 collision"."""
from __future__ import annotations

from typing import Optional


def count(n: int, noun: str, plural: Optional[str] = None) -> str:
    """"1 collision", "2 collisions", "1 equilibrium", "3 equilibria" (plural given)."""
    return f"{n} {noun if n == 1 else plural or noun + 's'}"
