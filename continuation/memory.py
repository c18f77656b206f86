"""What a sweep holds in memory, so that a scene too large for the machine is refused first.

A sweep is dense linear algebra on n x n matrices (n = ndof = 3N, or 2N without rotation). At
a step it holds DENSE_MATRICES of them at once: J, the stability matrix (M^-1 J is a copy),
LAPACK's working copy in the eigenvalue solve (dgeev), the bordered (n+1) x (n+1) Newton matrix
and its LU factors, and the relaxation's J + M / dt^2 at the start. Per stored point it keeps
q, the trial and committed histories, the tracked eigenvalues (complex) and the core's tangent,
about POINT_VECTORS vectors of n doubles, for at most `points` points (the paper's diagram has
about 700; a sweep stops after 20 000).
"""
from __future__ import annotations

DENSE_MATRICES = 6
POINT_VECTORS = 8
TYPICAL_POINTS = 2000


def sweep_bytes(ndof: int, points: int = TYPICAL_POINTS) -> float:
    """Estimated peak memory of a sweep [bytes] (float: N may be huge)."""
    n = float(ndof)
    return 8.0 * (DENSE_MATRICES * n * n + POINT_VECTORS * n * points)
