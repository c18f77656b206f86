"""Checks that hold for every branch, used where a test once compared a golden count."""
from __future__ import annotations

import numpy as np


def unaccounted_pair_changes(p: np.ndarray, n_complex: np.ndarray,
                             kinds_at: list[tuple[float, str]]) -> list:
    """(k, change, births - deaths) for each step k -> k + 1 of a one-leg branch (parameter p,
    pair count n_complex) whose change in the number of complex pairs is not the number of
    births minus deaths located in it (kinds_at: (location, "birth" | "death"); a step holds
    the locations between its ends, its end included); [] when every change is accounted
    for and no collision is spurious."""
    wrong = []
    for k in range(len(p) - 1):
        a, b = p[k], p[k + 1]
        inside = [kind for at, kind in kinds_at if at != a and (at - a) * (b - at) >= 0]
        net = inside.count("birth") - inside.count("death")
        if n_complex[k + 1] - n_complex[k] != net:
            wrong.append((k, int(n_complex[k + 1] - n_complex[k]), net))
    return wrong
