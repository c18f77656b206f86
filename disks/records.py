"""Collisions as JSON records: what bifurcate writes to collisions.json, a parameter map to
each cell's file, and `bifurcate --problem` to its collisions.json (raw units)."""
from __future__ import annotations

import numpy as np

from diskfriction.continuation.collisions import Collision
from diskfriction.disks.sweep import DiskBranch


def collision_record(c: Collision, parameter: str, matrix: str, window=None) -> dict:
    """One located collision as a JSON object, keyed by the parameter's name.

    At a collision the two eigenvalues coincide on the real axis: lambda_im is 0 by definition
    and lambda_re is the double eigenvalue. `bracket` is the parameter interval (width <= 1e-10)
    across which the count of complex pairs changes; `eigenvector` and `jordan_vector` form the
    Jordan chain (A - lambda) v = 0, (A - lambda) w = v of the stability matrix A. `window`: the
    band [lo, hi] of Re lambda the sweep tracked and certified (only collisions there are
    listed), or null when it covered the whole spectrum.
    """
    return {parameter: float(c.p), "kind": c.kind, "lambda_re": float(c.eigenvalue),
            "lambda_im": 0.0, "matrix": matrix, "window": None if window is None else list(window),
            "bracket": [float(b) for b in c.bracket],
            "resolved": bool(c.resolved), "residual": float(c.residual),
            "eigenvector": np.asarray(c.eigenvector, dtype=float).tolist(),
            "jordan_vector": np.asarray(c.generalized_eigenvector, dtype=float).tolist()}


RECORD_KEYS = ("kind", "lambda_re", "lambda_im", "matrix", "window", "bracket", "resolved",
               "residual", "eigenvector", "jordan_vector")
"""The keys of a collision record besides the parameter's name."""


def collision_records(branch: DiskBranch) -> list[dict]:
    """One JSON object per located collision of the requested leg, raw units, keyed F_x
    (collision_record)."""
    window = None if branch.window is None else tuple(float(w) for w in branch.window)
    return [collision_record(c, "F_x", branch.matrix, window) for c in branch.collisions]
