"""Collisions as JSON records: what bifurcate writes to collisions.json, and a parameter map
to each cell's file (raw units)."""
from __future__ import annotations

import numpy as np

from diskfriction.continuation.sweep import DiskBranch


def collision_records(branch: DiskBranch) -> list[dict]:
    """One JSON object per located collision of the requested leg, raw units.

    At a collision the two eigenvalues coincide on the real axis: lambda_im is 0 by definition
    and lambda_re is the double eigenvalue. `bracket` is the F_x interval (width <= 1e-10)
    across which the count of complex pairs changes; `eigenvector` and `jordan_vector` form the
    Jordan chain (A - lambda) v = 0, (A - lambda) w = v of the stability matrix.
    """
    return [{"F_x": float(c.p), "kind": c.kind, "lambda_re": float(c.eigenvalue), "lambda_im": 0.0,
             "matrix": branch.matrix, "bracket": [float(b) for b in c.bracket],
             "resolved": bool(c.resolved), "residual": float(c.residual),
             "eigenvector": np.asarray(c.eigenvector, dtype=float).tolist(),
             "jordan_vector": np.asarray(c.generalized_eigenvector, dtype=float).tolist()}
            for c in branch.collisions]
