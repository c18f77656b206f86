"""Collisions as JSON records: what bifurcate writes to collisions.json, a parameter map to
each cell's file, and `bifurcate --problem` to its collisions.json (raw units)."""
from __future__ import annotations

from typing import Optional, Sequence

import numpy as np

from diskfriction.continuation.detection.collisions import Collision
from diskfriction.models.chain.sweep import DiskBranch


def collision_record(c: Collision, parameter: str, matrix: str, window=None,
                     condition=None) -> dict:
    """One located collision as a JSON object, keyed by the parameter's name.

    At a collision the two eigenvalues coincide on the real axis: lambda_im is 0 by definition
    and lambda_re is the double eigenvalue. `bracket` is the parameter interval (width <= 1e-10)
    across which the count of complex pairs changes; `eigenvector` and `jordan_vector` form the
    Jordan chain (A - lambda) v = 0, (A - lambda) w = v of the stability matrix A. `window`: the
    band [lo, hi] of Re lambda the sweep tracked and certified (only collisions there are
    listed), or null when it covered the whole spectrum. `condition` (pair_condition): the
    pair's condition number at the accepted points before and after the collision, and
    `condition_amplitude` its amplitude a in kappa ~ a |p - p_c|^(-1/2) there; null where not
    known (a window's columns, the exhaustive detection), and the amplitude null where another
    collision of the pair's members shares the interval.
    """
    kappa, amplitude = (None, None) if condition is None else condition
    return {parameter: float(c.p), "kind": c.kind, "lambda_re": float(c.eigenvalue),
            "lambda_im": 0.0, "matrix": matrix, "window": None if window is None else list(window),
            "bracket": [float(b) for b in c.bracket],
            "resolved": bool(c.resolved), "residual": float(c.residual),
            "eigenvector": np.asarray(c.eigenvector, dtype=float).tolist(),
            "jordan_vector": np.asarray(c.generalized_eigenvector, dtype=float).tolist(),
            "condition": kappa, "condition_amplitude": amplitude}


RECORD_KEYS = ("kind", "lambda_re", "lambda_im", "matrix", "window", "bracket", "resolved",
               "residual", "eigenvector", "jordan_vector", "condition", "condition_amplitude")
"""The keys of a collision record besides the parameter's name."""


def pair_condition(p: np.ndarray, condition: Optional[np.ndarray], c: Collision,
                   collisions: Sequence[Collision]):
    """([kappa before, kappa after], [amplitude before, amplitude after]) of collision c's
    pair at the accepted points p[k], p[k + 1] around it: kappa the larger condition number of
    its two members there (Branch.condition, columns = labels), amplitude = kappa sqrt|p -
    p_c| (kappa diverges like |p - p_c|^(-1/2) at a collision: the amplitude is the pair's
    non-normality, nearly the same on both sides for points close to p_c). None if the
    condition numbers are not known (None, or nan at either point) or no interval holds p_c.
    The amplitude is None where another of the branch's `collisions` in the same interval
    involves a member of the pair: kappa at the interval's ends then follows both collisions,
    not c's law alone."""
    if condition is None:
        return None
    around = np.flatnonzero((p[:-1] - c.p) * (p[1:] - c.p) <= 0.0)
    if not around.size:
        return None
    k = int(around[0])
    kappa = [float(np.max(condition[r, list(c.pair)])) for r in (k, k + 1)]
    if not np.all(np.isfinite(kappa)):
        return None
    lo, hi = sorted((p[k], p[k + 1]))
    if any(other is not c and lo <= other.p <= hi and set(other.pair) & set(c.pair) for other in collisions):
        return kappa, None
    return kappa, [float(kap * np.sqrt(abs(p[r] - c.p))) for kap, r in zip(kappa, (k, k + 1))]


def collision_records(branch: DiskBranch) -> list[dict]:
    """One JSON object per located collision of the requested leg, raw units, keyed F_x
    (collision_record; the condition numbers from the leg's points, without a window)."""
    window = None if branch.window is None else tuple(float(w) for w in branch.window)
    leg = branch.leg == 1
    condition = None if window is not None or branch.condition is None else branch.condition[leg]
    return [collision_record(c, "F_x", branch.matrix, window,
                             pair_condition(branch.F_x[leg], condition, c, branch.collisions))
            for c in branch.collisions]
