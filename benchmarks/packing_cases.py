"""The case argument of the packing benchmarks, N:SEED:X[:LO:HI] (X: what the benchmark runs to,
LO:HI: a spectral window, as `bifurcate --window`), read or refused in one line."""
from __future__ import annotations

import argparse
from typing import Callable, Optional


def read_case(parser: argparse.ArgumentParser, case: str, x_name: str,
              x_type: Callable[[str], float]) -> tuple[int, int, float, Optional[tuple[float, float]]]:
    """(N, seed, X, window or None); parser.error (one line, exit 2) where the case is malformed."""
    fields = case.split(":")
    try:
        if len(fields) not in (3, 5):
            raise ValueError("3 or 5 fields")
        window = (float(fields[3]), float(fields[4])) if len(fields) == 5 else None
        return int(fields[0]), int(fields[1]), x_type(fields[2]), window
    except ValueError as error:
        parser.error(f"case {case!r} is not N:SEED:{x_name}[:LO:HI] ({error})")
